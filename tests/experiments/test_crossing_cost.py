"""``impact_experiments.crossing_cost``: it captures the loop tick's real arguments."""

from __future__ import annotations

import gymnasium as gym
import pytest

from impact_control.kernels import ControllerState
from impact_experiments.crossing_cost import loop_arguments, main


def test_loop_arguments_are_the_closed_loops_and_the_report_prints(capsys) -> None:
    env = gym.make("IMPACT/Hammer-v1", controller="impact")
    env.reset(seed=0)
    args = loop_arguments(env)
    assert len(args) == 7 and isinstance(args[-1], ControllerState)
    assert args[-1].tick.buffer is env.unwrapped.controller.kernel_state().tick.buffer
    env.close()
    main(["--calls", "50", "--repeat", "1"])
    out = capsys.readouterr().out
    assert "the loop tick's arguments, all, as they are:" in out
    assert "bundled (what the loop passes):" in out and "ControllerState.learner:" in out


def test_non_positive_counts_are_one_line(capsys) -> None:
    with pytest.raises(SystemExit) as exit_info:
        main(["--calls", "0"])
    assert exit_info.value.code == 2
    assert "--calls and --repeat must be >= 1" in capsys.readouterr().err
