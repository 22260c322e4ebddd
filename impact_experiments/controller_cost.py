"""Per-tick cost of ``ImpactController.compute`` excluding the dynamics update.

Run ``OMP_NUM_THREADS=1 python -m impact_experiments.controller_cost``. The model is
updated once at a
fixed state and its ``update`` is then replaced by a no-op, so the timing covers only the
controller core (impedance, estimator, slow filter, internal-model inference, limits), in mode
"impact" and in mode "impedance" (no internal model). Learning ticks (one SGD step every
``update_every`` ticks while the gate is open) are timed separately.
"""

from __future__ import annotations

import argparse
import time
import timeit

import numpy as np
import torch

from impact_control.arm_model import ArmDynamics
from impact_control.config import ControllerConfig, EstimatorConfig
from impact_control.controller import ImpactController
from impact_control.dynamics import PinocchioArm
from impact_control.lie import matrix_to_quat

Q_BENCH = np.array([0.0, -0.3, 0.0, -2.2, 0.0, 1.9, 0.785])


def _time_us(fn, number: int, repeat: int) -> float:
    """Best of ``repeat`` runs of ``number`` calls, per call [us] of process CPU time.

    CPU time rather than wall time, so that other processes on a shared machine do not count.
    """
    runs = timeit.repeat(fn, number=number, repeat=repeat, timer=time.process_time)
    return min(runs) / number * 1e6


def _compute_us(dyn: ArmDynamics, mode: str, kind: str, number: int, repeat: int) -> tuple:
    """(compute() [us], controller) at a fixed state with ``dyn.update`` already a no-op."""
    q, dq = Q_BENCH.copy(), np.full(7, 0.01)
    pos, quat = dyn.pos_ee_world.copy() + 0.01, matrix_to_quat(dyn.rot_ee_world)
    tau = dyn.gravity.copy()
    ctrl = ImpactController(dyn, ControllerConfig(estimator=EstimatorConfig(kind=kind)), mode=mode)
    ctrl.reset(q)
    for _ in range(100):
        ctrl.compute(q, dq, tau, pos, quat)
    return _time_us(lambda: ctrl.compute(q, dq, tau, pos, quat), number, repeat), ctrl


def run(kind: str, number: int, repeat: int) -> dict[str, float]:
    """Per-call timings [us]: dynamics update, ``compute`` without it (both modes), the fused
    kernel alone, the internal model's forward pass and one SGD step."""
    dyn, name = PinocchioArm(), "PinocchioArm"
    q, dq = Q_BENCH.copy(), np.full(7, 0.01)
    dyn.update(q, dq)
    t_update = _time_us(lambda: dyn.update(q, dq), number, repeat)
    dyn.update = lambda q_, dq_: None  # type: ignore[method-assign]
    t_impedance, _ = _compute_us(dyn, "impedance", kind, number, repeat)
    t_compute, ctrl = _compute_us(dyn, "impact", kind, number, repeat)
    model = ctrl.internal_model
    t_forward = _time_us(model.predict, number, repeat)
    x, target, mask = model.history_input().copy(), np.zeros(6, np.float32), np.ones(6, np.float32)
    t_sgd = _time_us(lambda: model.train_step(x, target, mask), max(number // 20, 10), repeat)
    return {
        "dynamics": name,
        "update_us": t_update,
        "compute_us": t_compute,
        "compute_impedance_us": t_impedance,
        "forward_us": t_forward,
        "sgd_step_us": t_sgd,
    }


def main(argv: list[str] | None = None) -> None:
    """CLI entry point: print the timings."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--estimator", choices=("residual", "momentum"), default="residual")
    parser.add_argument("--number", type=int, default=5000)
    parser.add_argument("--repeat", type=int, default=5)
    args = parser.parse_args(argv)
    torch.set_num_threads(1)
    res = run(args.estimator, args.number, args.repeat)
    print(
        f"{res['dynamics']} ({args.estimator}): dynamics.update {res['update_us']:.1f} us, "
        f"compute() without update {res['compute_us']:.1f} us (impact), "
        f"{res['compute_impedance_us']:.1f} us (impedance), "
        f"of which internal-model forward {res['forward_us']:.1f} us; "
        f"one SGD step {res['sgd_step_us']:.0f} us (every update_every ticks while learning)"
    )


if __name__ == "__main__":
    main()
