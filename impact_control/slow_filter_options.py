"""Options of the slow filter that the authors' released controller uses (off in ``default``
and ``paper``): w_slow kept and clipped in the TCP frame, a leak, norm clamps
(``SlowWrenchConfig``; their controller's ``updateSlowFast``). ``slow_filter.py::
slow_filter_tick`` runs ``update_with_options`` only when one is on; otherwise the plain
update, unchanged.

    e      = clip(w_hat - w_slow, -c, c)          per axis, in the filter's frame
    w_slow = (w_slow + eta dt e) max(0, 1 - leak dt)
    |w_slow force| <= force_norm_max_n,  |w_slow torque| <= torque_norm_max_nm

The constants live in the filter's buffer as (1,) views (flags 0 or 1), not as scalars, so
that the filter crosses into numba as cheaply as before they existed; the views are built
only on ticks that use an option.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from impact_control.kernel_math import clamp_norm3, rotate, rotate_back
from impact_control.stage_layout import Layout


class SlowFilterExtra(NamedTuple):
    """The options' constants and arrays, views of ``SlowFilterState.extra``.

    Attributes:
        on: Whether any option is on (else ``slow_filter_tick`` is the plain update).
        tcp_frame: Keep and clip w_slow in the TCP frame.
        leak_scale: max(0, 1 - leak dt) per tick (1: no leak).
        force_norm_max_n, torque_norm_max_nm: Norm bounds (inf: none) [N], [Nm].
        wrench_kept: (6,) w_slow in the filter's frame [N, Nm].
        wrench_in: (6,) this tick's input in the filter's frame [N, Nm] (scratch).
    """

    on: np.ndarray
    tcp_frame: np.ndarray
    leak_scale: np.ndarray
    force_norm_max_n: np.ndarray
    torque_norm_max_nm: np.ndarray
    wrench_kept: np.ndarray
    wrench_in: np.ndarray


SLOW_FILTER_EXTRA_LAYOUT = Layout.of(SlowFilterExtra, dict(
    on=1, tcp_frame=1, leak_scale=1, force_norm_max_n=1, torque_norm_max_nm=1, wrench_kept=6,
    wrench_in=6), args=("ext",))
"""The options' tail of the filter's buffer."""
unpack_slow_filter_extra = SLOW_FILTER_EXTRA_LAYOUT.unpacker(
    "unpack_slow_filter_extra", __name__, returns_length=False)
options_on = SLOW_FILTER_EXTRA_LAYOUT.flag_reader("on", "options_on", __name__)


def write_slow_filter_options(x: SlowFilterExtra, on: bool, tcp_frame: bool,
                              leak_per_tick: float, force_norm_max_n: float | None,
                              torque_norm_max_nm: float | None) -> None:
    """Write the config's options into the views ``x`` (None: no clamp)."""
    x.on[0], x.tcp_frame[0] = on, tcp_frame
    x.leak_scale[0] = max(0.0, 1.0 - leak_per_tick)
    x.force_norm_max_n[0] = math.inf if force_norm_max_n is None else force_norm_max_n
    x.torque_norm_max_nm[0] = math.inf if torque_norm_max_nm is None else torque_norm_max_nm


@njit(cache=True)  # out of line: the tick's default path stays as small as before
def update_with_options(wrench_ext, rot_ee, st, x) -> float:
    """The update in the filter's frame, then leak, then norm clamps (``st``: the
    ``SlowFilterState``, ``x`` its ``SlowFilterExtra``); returns the slow rate."""
    par, w, w_in, rate = st.params, x.wrench_kept, x.wrench_in, st.rate
    tcp = x.tcp_frame[0] != 0.0
    if tcp:
        rotate_back(rot_ee, wrench_ext, w_in)
    else:
        for i in range(6):
            w_in[i] = wrench_ext[i]
            w[i] = st.wrench_slow[i]
    for i in range(6):
        d = min(max(w_in[i] - w[i], -par.clip[i]), par.clip[i])
        rate[i] = par.eta_per_s[i] * d
        w[i] += d * par.gain[i]
    for i in range(6):
        w[i] *= x.leak_scale[0]
    clamp_norm3(w, 0, x.force_norm_max_n[0])
    clamp_norm3(w, 3, x.torque_norm_max_nm[0])
    if tcp:
        rotate(rot_ee, w, st.wrench_slow)
    else:
        for i in range(6):
            st.wrench_slow[i] = w[i]
    fx, fy, fz = rate[0], rate[1], rate[2]
    st.slow_rate[0] = math.sqrt(fx * fx + fy * fy + fz * fz) * par.inv_max_force_slew
    return st.slow_rate[0]
