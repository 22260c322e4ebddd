"""Stage layouts declared once (impact_control/stage_layout.py): every generated unpack
tiles its buffer in declaration order, and the sizes, offsets and errors come from the
declaration."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

import impact_control.controller  # noqa: F401 - imports every stage, filling LAYOUTS
from impact_control.errors import InvalidArgumentError
from impact_control.stage_layout import LAYOUTS, N_JOINTS, Dim, Layout, slots

N = 7
HIDDEN = 3


class _Scalars:
    """Any scalar attribute a layout's dims read: the joint count."""

    def __getattr__(self, name: str) -> int:
        return N


def _arg(name: str) -> Any:
    return N if name in ("n_joints", "n_features") else _Scalars()


def _leaves(state: Any, prefix: str = "") -> dict[str, np.ndarray]:
    out: dict[str, np.ndarray] = {}
    for field, value in zip(state._fields, state, strict=True):
        if isinstance(value, np.ndarray):
            out[prefix + field] = value
        elif isinstance(value, tuple) and hasattr(value, "_fields"):
            out.update(_leaves(value, f"{prefix}{field}__"))
    return out


def test_the_stages_register_their_layouts() -> None:
    names = {key.rsplit(".", 1)[1] for key in LAYOUTS}
    assert {"unpack_tick", "unpack_guard", "unpack_estimator", "unpack_impedance",
            "unpack_impedance_extra", "unpack_limiter", "unpack_gravity_rate",
            "unpack_slow_filter", "unpack_slow_filter_extra", "unpack_target_filter",
            "unpack_observer", "unpack_payload", "unpack_saturation_release",
            "unpack_joint_limits", "unpack_model", "unpack_model32",
            "unpack_counters"} <= names


@pytest.mark.parametrize("key", sorted(LAYOUTS))
def test_each_unpack_tiles_its_buffer_in_declaration_order(key: str) -> None:
    layout, unpack = LAYOUTS[key]
    buf = np.zeros(4096, dtype=np.float32 if key.endswith("model32") else np.float64)
    buf[0] = HIDDEN  # the model's max_hidden (its first slot) sizes its activations
    out = unpack(buf, *(_arg(a) for a in layout.args[1:]))
    state, length = out if isinstance(out, tuple) and not hasattr(out, "_fields") else (out,
                                                                                          None)
    leaves = _leaves(state)
    start = 0
    for name, size, shape in layout.flat():
        view = leaves.pop(name)
        assert np.shares_memory(view, buf), name
        offset = (view.__array_interface__["data"][0] - buf.__array_interface__["data"][0])
        assert offset // buf.itemsize == start, name
        assert view.size == size.value({"n": N, "n_res": N, "n_obs": N, "hidden": HIDDEN,
                                        "f": N, "hist": view.size}), name
        if shape is not None:
            assert view.ndim == len(shape), name
        start += view.size
    assert not leaves, f"views the layout does not declare: {sorted(leaves)}"
    if length is not None:
        assert length == start


def test_sizes_and_offsets_come_from_the_declaration() -> None:
    class Toy(tuple):
        _fields = ("on", "gains", "tau")

    layout = Layout.of(Toy, dict(on=1, gains=(2, 3), tau=2 * N_JOINTS + 1))
    assert layout.size(n=7) == 1 + 6 + 15
    assert layout.offset("gains") == 1 and layout.offset("tau") == 7
    assert layout.length == Dim(8, (("n", 2),))
    assert slots("a b") == {"a": 1, "b": 1}
    with pytest.raises(InvalidArgumentError, match="needs dimension"):
        layout.size()
    with pytest.raises(InvalidArgumentError, match="no field 'nope'.*fields: \\['on'"):
        layout.offset("nope")
    late = Layout.of(Toy, dict(tau=N_JOINTS, on=1, gains=1))
    with pytest.raises(InvalidArgumentError, match="offset of 'on' depends on"):
        late.offset("on")
    with pytest.raises(InvalidArgumentError, match="at most one dimension"):
        Layout.of(Toy, dict(gains=(N_JOINTS, N_JOINTS))).size(n=7)


def test_a_field_the_state_lacks_is_an_error() -> None:
    class Toy(tuple):
        _fields = ("on",)

    with pytest.raises(InvalidArgumentError, match="has no field"):
        Layout.of(Toy, dict(on=1, off=1)).source("unpack_toy")
