"""Property test of ImpactController.compute: any input either is refused with
InvalidArgumentError (state untouched) or gives finite torques within the FR3 limits.

Inputs are drawn per tick: arrays of random shape, NaN/inf, extreme finite values
(up to 1.8e308) and values inside ``INPUT_ABS_MAX``; a drawn tick may be held for up to 600
ticks so the surprise gate opens and the internal model learns from it. The oracle of
refusal is the documented contract (wrong shape, not finite, beyond ``INPUT_ABS_MAX``, zero
quaternion, learn_mask not 6 values in [0, 1]). CI runs a few hundred examples; the slow test
reruns this file with 10,000 examples under ``NUMBA_BOUNDSCHECK=1`` (a fresh kernel cache),
where an out-of-bounds read inside a kernel raises IndexError and fails the test.
"""

from __future__ import annotations

import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from impact_control import kernels
from impact_control.config import ControllerConfig
from impact_control.controller import INPUT_ABS_MAX, ImpactController
from impact_control.errors import InvalidArgumentError
from impact_control.lie import matrix_to_quat
from impact_control.limits import unpack_limiter
from impact_franka.fci import fr3_config

dynamics = pytest.importorskip("impact_control.dynamics")

EXAMPLES = int(os.environ.get("IMPACT_PROPERTY_EXAMPLES", "100"))
"""Examples per run of the default suite (52 s for 300 in CI's two processes); the slow test
below runs 10,000 with bounds checking."""
Q0 = np.array([0.0, -0.3, 0.0, -2.2, 0.0, 1.9, 0.785])
SIZES = {"q": 7, "dq": 7, "tau_measured": 7, "pos_target_world": 3, "quat_target_world": 4,
         "wrench_cmd_world": 6}
BOUND = {name: bound for name, bound, _ in INPUT_ABS_MAX}


_ARM = dynamics.PinocchioArm()
_ARM.update(Q0, np.zeros(7))
NOMINAL = {"q": Q0, "dq": np.zeros(7), "tau_measured": _ARM.gravity.copy(),
           "pos_target_world": _ARM.pos_ee_world.copy(),
           "quat_target_world": matrix_to_quat(_ARM.rot_ee_world), "wrench_cmd_world": np.zeros(6)}
CONTROLLERS = {mode: ImpactController(dynamics.PinocchioArm(), ControllerConfig(), mode=mode)
               for mode in ("impact", "impedance")}
# The configuration an FR3 runs (impact_franka.fci.fr3_config): libfranka's limiter, the
# in-kernel learner and the contact guard, under the same contract.
CONTROLLERS["fr3"] = ImpactController(dynamics.PinocchioArm(), fr3_config(), mode="impact")

_element = st.one_of(
    st.floats(-1.0, 1.0),                                         # near nominal (scaled below)
    st.sampled_from([math.nan, math.inf, -math.inf, 0.0]),
    st.floats(allow_nan=False, allow_infinity=False),             # anything finite
    st.sampled_from([b * s for b in (10.0, 100.0, 1000.0, 10000.0) for s in (1.0, -1.0)]),
)


FIELDS = (*SIZES, "gripper_width_m", "learn_mask")


def _bounded(bound: float) -> st.SearchStrategy[float]:
    """Values anywhere inside an input's bound, its edges included."""
    return st.one_of(st.floats(-bound, bound), st.sampled_from([bound, -bound]))


@st.composite
def _valid(draw, name: str):
    """An input the contract accepts: nominal (+ a small offset) or anywhere within bounds."""
    bounded = draw(st.booleans()) and name != "quat_target_world"
    if name == "gripper_width_m":
        return draw(_bounded(1.0) if bounded else st.floats(0.0, 0.08))
    if name == "learn_mask":
        return draw(st.one_of(st.none(), hnp.arrays(np.bool_, 6)))
    n = SIZES[name]
    if bounded:
        return draw(hnp.arrays(np.float64, n, elements=_bounded(BOUND[name])))
    return NOMINAL[name] + draw(hnp.arrays(np.float64, n, elements=st.floats(-0.05, 0.05)))


@st.composite
def _hostile(draw, name: str):
    """Hostile elements (NaN, inf, any finite) in the right or a random shape."""
    if name == "gripper_width_m":
        return draw(_element)
    shape = draw(st.one_of(st.just((SIZES.get(name, 6),)),
                           hnp.array_shapes(min_dims=0, max_dims=2, max_side=9)))
    return draw(hnp.arrays(np.float64, shape, elements=_element))


@st.composite
def _tick(draw) -> dict:
    """One controller input (keyword arguments; about half of them valid) and how many
    ticks it is held."""
    bad = draw(st.one_of(st.just(frozenset()),
                         st.frozensets(st.sampled_from(FIELDS), min_size=1, max_size=2)))
    kwargs = {name: draw(_hostile(name) if name in bad else _valid(name)) for name in FIELDS}
    return {"kwargs": kwargs, "hold": draw(st.sampled_from([1, 1, 5, 60, 250, 600]))}


def _refused(kwargs: dict) -> bool:
    """The documented contract: whether compute must raise InvalidArgumentError."""
    for name, n in SIZES.items():
        a = kwargs[name]
        if a.shape != (n,) or not np.all(np.abs(a) <= BOUND[name]):
            return True
    w = kwargs["gripper_width_m"]
    if not abs(w) <= BOUND["gripper_width_m"]:
        return True
    m = kwargs["learn_mask"]
    if m is not None and (m.shape != (6,) or not np.all((m >= 0.0) & (m <= 1.0))):
        return True
    w0, x, y, z = kwargs["quat_target_world"]
    return not math.sqrt(w0 * w0 + x * x + y * y + z * z) > 1e-12


def _state(ctrl: ImpactController) -> dict[str, np.ndarray]:
    """Every array that carries the controller's state from tick to tick, copied, by name."""
    im = ctrl.internal_model
    return {**{k: a.copy() for k, a in ctrl.state_arrays().items()},
            "counts": np.array([im.replay.count, im.n_updates])}


def _check_limits(ctrl: ImpactController, out: np.ndarray, before: dict) -> None:
    """Finite, saturated to tau_max, and (unless a joint sits at its limit, the documented
    re-synchronisation case of TorqueLimiter) no more than the rate bound per tick."""
    tau_max = ctrl.limiter.tau_max
    assert np.all(np.isfinite(out))
    assert np.all(np.abs(out) <= tau_max + 1e-9)
    last = unpack_limiter(before["lim.buffer"], ctrl.limiter.packed.scalars)[0].last_no_gravity
    step = np.abs(ctrl.limiter.state.last_no_gravity - last)
    free = np.abs(out) < tau_max - 1e-9
    assert np.all(step[free] <= ctrl.limiter.max_delta_nm + 1e-9)


@settings(max_examples=EXAMPLES, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(mode=st.sampled_from(["impact", "impedance", "fr3"]),
       ticks=st.lists(_tick(), min_size=1, max_size=6))
def test_compute_refuses_or_returns_limited_finite_torques(mode, ticks) -> None:
    ctrl = CONTROLLERS[mode]
    ctrl.reset(Q0)
    for tick in ticks:
        kwargs, refused = tick["kwargs"], _refused(tick["kwargs"])
        for _ in range(tick["hold"]):
            before = _state(ctrl)
            if refused:
                with pytest.raises(InvalidArgumentError):
                    ctrl.compute(**kwargs)
                after = _state(ctrl)
                for name, a in before.items():
                    np.testing.assert_array_equal(a, after[name], err_msg=name)
                event("tick refused")
                break
            out = ctrl.compute(**kwargs)
            _check_limits(ctrl, out, before)
            event("tick accepted")
        event(f"torques saturated: {bool(np.any(np.abs(ctrl.signals.tau_cmd) >= 12.0))}")
    im = ctrl.internal_model
    event(f"model learned: {im.n_updates > 0}, diverged: {im.n_divergences > 0}")


@pytest.mark.skipif(os.environ.get("NUMBA_BOUNDSCHECK") != "1",
                    reason="needs kernels compiled with NUMBA_BOUNDSCHECK=1 (the slow test)")
def test_bounds_checked_kernels_raise_on_a_short_array() -> None:
    """The slow run can see an out-of-bounds read: the kernel called directly (past the
    Python shape check) with a 1-element q raises IndexError."""
    ctrl = CONTROLLERS["impact"]
    ctrl.reset(Q0)
    args = list(ctrl._kernel_args(*NOMINAL.values(), ctrl.internal_model.mask_array(None), 0.04))
    args[0] = np.zeros(1)
    with pytest.raises(IndexError):
        kernels.controller_tick(*args, ctrl.kernel_state())


@pytest.mark.slow
def test_property_10k_examples_with_numba_bounds_checking(tmp_path: Path) -> None:
    """10,000 examples with every kernel compiled with bounds checks (fresh cache)."""
    env = {**os.environ, "IMPACT_PROPERTY_EXAMPLES": "10000", "NUMBA_BOUNDSCHECK": "1",
           "NUMBA_CACHE_DIR": str(tmp_path / "numba")}
    cmd = [sys.executable, "-m", "pytest", "-p", "no:cacheprovider", __file__, "-k",
           "refuses_or_returns or short_array", "--hypothesis-show-statistics"]
    run = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=3000)
    assert run.returncode == 0, run.stdout[-3000:] + run.stderr[-2000:]
    assert "10000 passing, 0 failing" in run.stdout and "2 passed" in run.stdout, run.stdout
