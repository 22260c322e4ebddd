"""Fake env + fake policies for the impact-eval tests (no MuJoCo, milliseconds per episode).

``ImpactTest/Fake-v0``: a 1-D "push progress to 1" task whose success at the end depends on the
object mass (heavier -> less likely) and on the reset seed; the ``impact`` controller has more
capacity than ``impedance``. Masses 66, 77 and 88 trigger a ``SimulationError``, a
``RuntimeError`` and a NaN observation at step 3. ``$IMPACT_FAKE_STEP_DELAY`` [s] slows steps;
``$IMPACT_FAKE_CRASH_DIR`` holds a one-shot switch that kills the process at step 3.

Import as ``test_eval_fake``; CLI runs use the id ``test_eval_fake:ImpactTest/Fake-v0`` so that
subprocesses and sweep workers import this module (and its methods) too.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

from impact_envs.errors import InvalidArgumentError, SimulationError
from impact_eval.methods import MethodSpec, register_method

BARE_ID = "ImpactTest/Fake-v0"
ENV_ID = f"test_eval_fake:{BARE_ID}"
MAX_STEPS = 30
CAPACITY_KG = {"impedance": 2.0, "impact": 6.0}
REPO = Path(__file__).resolve().parent.parent


CRASH_DIR_ENV = "IMPACT_FAKE_CRASH_DIR"
"""Directory of the one-shot crash switch (``crash_once_if_armed``)."""


def crash_once_if_armed() -> None:
    """SIGKILL this process once, mid-episode, if ``$IMPACT_FAKE_CRASH_DIR/arm`` exists and
    ``fired`` does not yet (it is created first): a worker dying for real, once."""
    root = os.environ.get(CRASH_DIR_ENV)
    if not root or not (Path(root) / "arm").exists():
        return
    try:
        (Path(root) / "fired").touch(exist_ok=False)
    except FileExistsError:
        return
    os.kill(os.getpid(), signal.SIGKILL)


class FakeEnv(gym.Env):
    """Tiny deterministic-given-seed env with the IMPACT env interface."""

    metadata = {"render_modes": [], "render_fps": 30}
    param_name = "object_mass"
    policy_dt = 1.0 / 30.0
    control_dt = 0.001

    def __init__(self, controller: str = "impedance", object_mass: float = 0.2) -> None:
        if controller not in CAPACITY_KG:
            raise InvalidArgumentError(f"invalid controller {controller!r}")
        self.controller = controller
        self.object_mass = object_mass
        self.observation_space = gym.spaces.Dict(
            {
                "progress": gym.spaces.Box(0.0, 2.0, (1,), np.float32),
                "noise": gym.spaces.Box(-1.0, 1.0, (2,), np.float32),
            }
        )
        self.action_space = gym.spaces.Box(-1.0, 1.0, (10,), np.float32)
        self._progress, self._u, self._t = 0.0, 0.0, 0

    def _obs(self) -> dict[str, np.ndarray]:
        noise = self.np_random.uniform(-1, 1, 2).astype(np.float32)
        return {"progress": np.array([self._progress], np.float32), "noise": noise}

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        super().reset(seed=seed)
        mass = float((options or {}).get("object_mass", self.object_mass))
        if mass <= 0:
            raise InvalidArgumentError(f"object_mass must be > 0, got {mass}")
        self.object_mass = mass
        self._progress, self._t = 0.0, 0
        self._u = float(self.np_random.uniform())
        return self._obs(), {"is_success": False, "object_mass": mass}

    def step(self, action):
        self._t += 1
        if delay := float(os.environ.get("IMPACT_FAKE_STEP_DELAY", "0")):
            time.sleep(delay)
        if self._t == 3:
            crash_once_if_armed()
        m = self.object_mass
        if self._t == 3 and m == 66:
            raise SimulationError("qacc diverged at t=0.1 s")
        if self._t == 3 and m == 77:
            raise RuntimeError("boom")
        self._progress = min(2.0, self._progress + 0.05 * (float(action[0]) + 1.0))
        p_success = CAPACITY_KG[self.controller] / (CAPACITY_KG[self.controller] + m)
        success = self._progress >= 1.0 and self._u < p_success
        obs = self._obs()
        if self._t >= 3 and m == 88:
            obs["progress"][0] = np.nan
        info = {
            "is_success": success,
            "object_mass": m,
            "energy_j": 0.1 * m * abs(float(action[0])),
            "peak_torque_nm": 2.0 * m + self._u,
            "peak_contact_force_n": 9.81 * m,
            "pose_error_m": 0.001 * m * (1.0 - min(1.0, self._progress)),
        }
        return obs, float(success), bool(success), False, info


class FakePolicy:
    """Batched stateful policy: pushes at ``push`` plus a little per-episode noise.

    The noise of env i comes from a generator seeded by ``seed_envs`` with its episode seed
    (as the diffusion policy does), so an episode's row does not depend on how the sweep
    grouped episodes into batches (a resumed sweep regroups what is left).
    """

    def __init__(self, push: float) -> None:
        self.push = push
        self.n_envs = 0
        self._rngs: list[np.random.Generator] = []

    def reset(self, n_envs: int) -> None:
        self.n_envs = n_envs
        self._rngs = [np.random.default_rng(i) for i in range(n_envs)]

    def seed_envs(self, seeds: list[int]) -> None:
        self._rngs = [np.random.default_rng(s) for s in seeds]

    def act(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        assert obs["progress"].shape == (self.n_envs, 1), "batch size must match reset(n)"
        actions = np.zeros((self.n_envs, 10), np.float32)
        noise = np.array([rng.uniform(-1, 1) for rng in self._rngs])
        actions[:, 0] = self.push + 0.1 * noise
        return actions


if BARE_ID not in gym.registry:
    gym.register(BARE_ID, entry_point="test_eval_fake:FakeEnv", max_episode_steps=MAX_STEPS)
register_method(MethodSpec("fake_fast", "impedance", lambda _id, _env: FakePolicy(0.9), "fast"))
register_method(MethodSpec("fake_impact", "impact", lambda _id, _env: FakePolicy(0.9), "impact"))
register_method(MethodSpec("fake_slow", "impedance", lambda _id, _env: FakePolicy(-0.5), "slow"))


def cli_env() -> dict[str, str]:
    """Environment for CLI subprocesses: this directory importable, one thread."""
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(REPO / "tests"), str(REPO)])
    env["OMP_NUM_THREADS"] = "1"
    return env


def run_cli(*args: str, timeout: float = 120) -> subprocess.CompletedProcess:
    """Run ``python -m impact_eval ARGS`` in a subprocess."""
    return subprocess.run(
        [sys.executable, "-m", "impact_eval", *args],
        capture_output=True,
        text=True,
        env=cli_env(),
        timeout=timeout,
        cwd=REPO,
    )


def test_fake_env_success_depends_on_mass_and_controller() -> None:
    rates = {}
    for controller in ("impedance", "impact"):
        env = gym.make(BARE_ID, controller=controller)
        for mass in (0.5, 8.0):
            wins = 0
            for seed in range(40):
                env.reset(seed=seed, options={"object_mass": mass})
                for _ in range(MAX_STEPS):
                    *_, term, trunc, info = env.step(np.ones(10, np.float32))
                    if term or trunc:
                        break
                wins += info["is_success"]
            rates[controller, mass] = wins / 40
    assert rates["impedance", 0.5] > rates["impedance", 8.0]
    assert rates["impact", 8.0] > rates["impedance", 8.0]


def test_a_preset_a_plugin_env_cannot_take_is_a_one_line_error() -> None:
    from impact_envs.errors import InvalidArgumentError
    from impact_eval.envs import make_env

    make_env(ENV_ID, "impact").close()  # the default preset needs no argument
    with pytest.raises(InvalidArgumentError, match="controller_preset") as err:
        make_env(ENV_ID, "impact", preset="paper")  # not silently run with another config
    assert "\n" not in str(err.value)
