"""docs/adding_a_stage.md, proven: a stage added by its own module and the guide's edits.

The package is copied to a temporary folder, the example stage (``stage_example/
friction_observer.py``, a joint-friction observer feeding the wrench estimator) is added as
``impact_control/friction_observer.py``, and ``EDITS`` (the guide's, verbatim) are applied
to ``impact_control/kernels.py`` and ``impact_control/controller.py``. In a fresh interpreter
on that copy, with numba's cache starting empty, an env then runs the stage inside its
compiled 1 kHz loop, and ``get_state``/``set_state`` restore it, with nothing else of the
package edited.
"""

from __future__ import annotations

import filecmp
import os
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

import impact_control
import impact_envs

PACKAGE = Path(impact_control.__file__).resolve().parent
ENVS = Path(impact_envs.__file__).resolve().parent
STAGE = Path(__file__).parent / "stage_example" / "friction_observer.py"
STAGE_PATH = "friction_observer.py"

EDITS: dict[str, list[tuple[str, str]]] = {
    "kernels.py": [
        ("from impact_control.limits import torque_limiter, unpack_limiter\n",
         "from impact_control.friction_observer import (\n"
         "    friction_observer_step,\n    unpack_friction_observer,\n)\n"
         "from impact_control.limits import torque_limiter, unpack_limiter\n"),
        ("    lim: Packed\n", "    lim: Packed\n    fo: Packed\n"),
        ("    lim = unpack_limiter(state.lim.buffer, state.lim.scalars)[0]\n",
         "    lim = unpack_limiter(state.lim.buffer, state.lim.scalars)[0]\n"
         "    fo = unpack_friction_observer(state.fo.buffer, state.fo.scalars)[0]\n"),
        ("    if est.momentum:\n",
         "    fric = friction_observer_step(dq, fric, fo)\n    if est.momentum:\n"),
    ],
    "controller.py": [
        ("from impact_control.limits import TorqueLimiter\n",
         "from impact_control.friction_observer import FrictionObserver, "
         "FrictionObserverConfig\nfrom impact_control.limits import TorqueLimiter\n"),
        ("        self.limiter = TorqueLimiter(cfg.limits, cfg.dt_s)\n",
         "        self.limiter = TorqueLimiter(cfg.limits, cfg.dt_s)\n"
         "        self.friction_observer = FrictionObserver(FrictionObserverConfig(), cfg.dt_s)\n"),
        ("        self.limiter.reset()\n",
         "        self.limiter.reset()\n        self.friction_observer.reset()\n"),
        ("lim=self.limiter.packed)", "lim=self.limiter.packed,\n"
         "            fo=self.friction_observer.packed)"),
    ],
}
"""(anchor, replacement) per file: each anchor occurs exactly once in today's source."""

CHECK = textwrap.dedent('''
    import gymnasium as gym
    import numpy as np
    import impact_control
    import impact_envs
    from impact_control import jit_cache
    assert impact_envs.__file__.startswith({root!r}), impact_envs.__file__
    assert impact_control.__file__.startswith({root!r}), impact_control.__file__
    assert any(p.name == "friction_observer.py" for p in jit_cache.kernel_sources())
    env = gym.make("IMPACT/Hammer-v1", controller="impact")
    obs, _ = env.reset(seed=3)
    ctrl = env.unwrapped.controller
    names = [k for k in ctrl.state_arrays() if k.startswith("fo.")]
    assert names == ["fo.buffer"], names
    live = list(ctrl.state_arrays().values())
    tau_f = ctrl.friction_observer.state.tau_friction
    assert any(np.shares_memory(tau_f, a) for a in live)
    hold = np.concatenate([obs["ee_pos"] + [0.0, 0.0, 0.05], obs["ee_rot6d"], [-1.0]])
    for _ in range(5):
        env.step(hold)
    assert np.abs(tau_f).max() > 1e-4, tau_f  # the compiled loop ran the stage
    snap = env.unwrapped.get_state()
    saved = tau_f.copy()
    first = [env.step(hold)[0]["joint_pos"] for _ in range(5)]
    after = tau_f.copy()
    env.unwrapped.set_state(snap)
    assert np.array_equal(tau_f, saved)
    again = [env.step(hold)[0]["joint_pos"] for _ in range(5)]
    assert all(np.array_equal(a, b) for a, b in zip(first, again))
    assert np.array_equal(tau_f, after)
    print("stage ok", float(np.abs(saved).max()))
''')


def _copy_with_stage(root: Path) -> Path:
    """The controller package under ``root``, with the stage module added and ``EDITS``
    applied, and the env package beside it."""
    copy = root / "impact_control"
    for source, target in ((PACKAGE, copy), (ENVS, root / "impact_envs")):
        shutil.copytree(source, target, ignore=shutil.ignore_patterns(
            "__pycache__", "checkpoints", "*.nbi", "*.nbc"))
    shutil.copy(STAGE, copy / STAGE_PATH)
    for rel, edits in EDITS.items():
        path = copy / rel
        text = path.read_text()
        for anchor, replacement in edits:
            assert text.count(anchor) == 1, f"{rel}: anchor {anchor!r}"
            text = text.replace(anchor, replacement)
        path.write_text(text)
    return copy


def test_the_guides_edits_apply_to_today_s_source(tmp_path):
    """Cheap half: the stage lands in at most three files, envs/state.py untouched."""
    copy = _copy_with_stage(tmp_path)
    changed = {rel for rel in EDITS if not filecmp.cmp(PACKAGE / rel, copy / rel, shallow=False)}
    assert changed | {STAGE_PATH} == {*EDITS, STAGE_PATH}
    assert len(changed | {STAGE_PATH}) <= 3
    assert filecmp.cmp(ENVS / "envs/state.py", tmp_path / "impact_envs/envs/state.py",
                       shallow=False)


@pytest.mark.slow
def test_an_added_stage_runs_compiled_and_is_snapshotted(tmp_path):
    """Expensive half (compiles every kernel of the copy, ~1-2 min): the stage runs in the
    env's 1 kHz loop and get_state/set_state cover it."""
    _copy_with_stage(tmp_path)
    env = {**os.environ, "PYTHONPATH": str(tmp_path), "MUJOCO_GL": "egl"}
    env.pop("NUMBA_CACHE_DIR", None)
    result = subprocess.run([sys.executable, "-c", CHECK.format(root=str(tmp_path))],
                            capture_output=True, text=True, env=env, timeout=900,
                            cwd=tmp_path, check=False)
    assert result.returncode == 0, result.stderr[-3000:]
    assert "stage ok" in result.stdout
