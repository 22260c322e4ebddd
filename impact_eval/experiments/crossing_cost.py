"""What one call of the closed loop's compiled tick pays to cross from Python into numba.

The env's closed loop (``impact_envs/loop/closed_loop.py``) calls its compiled tick once per
1 ms tick with the same arguments (the plan, the simulator's arrays, the arm model and the
controller's named state); numba unboxes every argument on every call. This measures that
cost: a kernel that does nothing, compiled for exactly the loop's argument types, timed over
many calls, and the same for each field of ``ControllerState`` alone; an empty call is the
floor. Printed in microseconds per call (best of ``--repeat``), next to the env's whole cost
per tick from the same process (``impact-bench`` measures it properly).

    python -m impact_eval.experiments.crossing_cost [--calls 20000] [--repeat 3]
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable

import gymnasium as gym
import numba
import numpy as np
from numba import njit

import impact_envs  # noqa: F401 - registers the envs


@njit
def _ignore_one(a):  # noqa: ARG001 - only the argument's crossing is measured
    return 0


@njit
def _ignore_loop_args(i, frictionloss, plan, sim, arm, dyn, state):  # noqa: ARG001
    return 0


def _per_call_us(call: Callable[[], object], calls: int, repeat: int) -> float:
    best = float("inf")
    for _ in range(repeat):
        t = time.perf_counter()
        for _ in range(calls):
            call()
        best = min(best, (time.perf_counter() - t) / calls)
    return best * 1e6


def loop_arguments(env: gym.Env) -> tuple:
    """The arguments of the closed loop's compiled tick, captured on one env step."""
    loop, captured = env.unwrapped.loop, {}
    entry = loop._entry

    def spy(args: tuple) -> object:
        captured["args"] = args
        return entry(args)

    loop._entry = spy
    try:
        obs = env.unwrapped._observation()
        env.step(np.concatenate([obs["ee_pos"], obs["ee_rot6d"], [-1.0]]))
    finally:
        loop._entry = entry
    return captured["args"]


def main(argv: list[str] | None = None) -> None:
    """Print the crossing costs (see the module docstring)."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--calls", type=int, default=20000)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args(argv)
    if args.calls < 1 or args.repeat < 1:
        parser.error(f"--calls and --repeat must be >= 1, got {args.calls} and {args.repeat}")
    env = gym.make("IMPACT/Hammer-v0", controller="impact")
    env.reset(seed=0)
    loop_args = loop_arguments(env)
    state = loop_args[-1]
    types = tuple(numba.typeof(a) for a in loop_args)
    whole = _ignore_loop_args.compile(types)
    print(f"empty call: {_per_call_us(lambda: _ignore_one(0), args.calls, args.repeat):.2f} us")
    print(f"the loop tick's arguments, all: "
          f"{_per_call_us(lambda: whole(*loop_args), args.calls, args.repeat):.2f} us")
    for name in state._fields:
        value = getattr(state, name)
        one = _ignore_one.compile((numba.typeof(value),))
        print(f"  ControllerState.{name}: "
              f"{_per_call_us(lambda o=one, v=value: o(v), args.calls, args.repeat):.2f} us")
    env.close()


if __name__ == "__main__":
    main()
