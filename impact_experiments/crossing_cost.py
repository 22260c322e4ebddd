"""What one call of the closed loop's compiled tick pays to cross from Python into numba.

The env's closed loop (``impact_envs/loop/closed_loop.py``) calls its compiled tick once per
1 ms tick with the same arguments (the plan, the simulator's arrays, the arm model and the
controller's named state). Passed as they are, numba unboxes every array on every call; the
loop therefore gathers them once per policy step into one ``TickArgs`` (a structref,
``impact_envs/loop/tick.py``) and a tick crosses one pointer. This measures both: a kernel
that does nothing, compiled for exactly the loop's argument types (as they are, and bundled),
timed over many calls; the bundling itself (once per step); each field of
``ControllerState`` alone; an empty call is the floor. Printed in microseconds per call
(best of ``--repeat``); ``impact-bench`` measures the env's whole cost.

    python -m impact_experiments.crossing_cost [--calls 20000] [--repeat 3]
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
from impact_envs.loop.tick import bundle_tick_args


@njit
def _ignore_one(a):  # noqa: ARG001 - only the argument's crossing is measured
    return 0


@njit
def _ignore_loop_args(i, frictionloss, plan, sim, arm, dyn, state):  # noqa: ARG001
    return 0


@njit
def _ignore_bundled(i, frictionloss, args):  # noqa: ARG001
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
    """The loop tick's arguments as they are, ``(i, frictionloss, plan, sim, arm, dyn,
    state)``, captured on one env step (the parts the loop bundles, the index and the
    simulator's friction force beside them)."""
    loop, captured = env.unwrapped.loop, {}
    entries = loop._entries

    def spy(parts: tuple, friction: object) -> object:
        captured["parts"] = parts
        return entries(parts, friction)

    loop._entries = spy
    try:
        obs = env.unwrapped._observation()
        env.step(np.concatenate([obs["ee_pos"], obs["ee_rot6d"], [-1.0]]))
    finally:
        loop._entries = entries
    return (0, env.unwrapped.sim.frictionloss_reader()(), *captured["parts"])


def main(argv: list[str] | None = None) -> None:
    """Print the crossing costs (see the module docstring)."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--calls", type=int, default=20000)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args(argv)
    if args.calls < 1 or args.repeat < 1:
        parser.error(f"--calls and --repeat must be >= 1, got {args.calls} and {args.repeat}")
    env = gym.make("IMPACT/Hammer-v1", controller="impact")
    env.reset(seed=0)
    loop_args = loop_arguments(env)
    state = loop_args[-1]
    types = tuple(numba.typeof(a) for a in loop_args)
    whole = _ignore_loop_args.compile(types)
    print(f"empty call: {_per_call_us(lambda: _ignore_one(0), args.calls, args.repeat):.2f} us")
    print(f"the loop tick's arguments, all, as they are: "
          f"{_per_call_us(lambda: whole(*loop_args), args.calls, args.repeat):.2f} us")
    parts = loop_args[2:]
    bundle = bundle_tick_args.compile(tuple(numba.typeof(a) for a in parts))
    bundled = bundle(*parts)
    print(f"bundling them into TickArgs (once per policy step): "
          f"{_per_call_us(lambda: bundle(*parts), args.calls, args.repeat):.2f} us")
    one_ref = _ignore_bundled.compile(tuple(numba.typeof(a) for a in (*loop_args[:2], bundled)))
    print(f"the loop tick's arguments, bundled (what the loop passes): "
          f"{_per_call_us(lambda: one_ref(0, loop_args[1], bundled), args.calls, args.repeat):.2f}"
          " us")
    for name in state._fields:
        value = getattr(state, name)
        one = _ignore_one.compile((numba.typeof(value),))
        print(f"  ControllerState.{name}: "
              f"{_per_call_us(lambda o=one, v=value: o(v), args.calls, args.repeat):.2f} us")
    env.close()


if __name__ == "__main__":
    main()
