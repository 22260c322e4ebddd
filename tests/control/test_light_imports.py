"""The controller and the robot runner import without the benchmark: what a robot PC's light
install (``pip install -e .``, README "On a robot PC") must be able to run."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

HEAVY = ("gymnasium", "mujoco", "torch", "pandas", "stable_baselines3", "diffusers", "zarr",
         "impact_envs", "impact_eval", "impact_learn")


def _loaded_after(statement: str) -> list[str]:
    code = (f"import sys, json\n{statement}\n"
            f"print(json.dumps([m for m in {list(HEAVY)!r} if m in sys.modules]))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, timeout=300)
    return json.loads(out.stdout.strip().splitlines()[-1])


def test_the_controller_core_imports_no_heavy_package() -> None:
    statement = ("import impact_control, impact_control.controller, impact_control.dynamics, "
                 "impact_control.presets, impact_control.internal_model, impact_control.policy")
    assert _loaded_after(statement) == []


@pytest.mark.parametrize("module", ["impact_franka.cli", "impact_franka.session",
                                    "impact_franka.runner", "impact_franka.policy_loop"])
def test_the_robot_runner_imports_neither_the_envs_nor_the_ml_stack(module: str) -> None:
    assert _loaded_after(f"import {module}") in ([], ["pandas"])  # the runner writes ticks.csv
