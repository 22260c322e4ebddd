"""Physics acceptance experiments of the controller (``python -m impact_experiments.physics``).

1. **Wrench recovery**: the arm holds still in random poses; a known wrench is applied at the
   TCP (MuJoCo ``xfrc_applied``); after settling, the slow wrench estimate must equal it
   (robot-on-environment sign: estimate = -applied) within 1 N / 0.1 Nm, sensor noise on,
   for both estimators.
2. **Payload hold**: a 5 kg payload welded at the TCP appears at t = 0 while the arm holds a
   fixed target; report the sag at 3 s and 5 s under plain impedance (expected m g / K) and
   under IMPACT (``default`` and ``paper`` presets), and when IMPACT's error settles within 3 mm.
3. **Noise floor of the surprise**: the arm holds still with nothing attached; the force part
   of the raw estimate and of the slow wrench (what the surprise of a zero prediction reads)
   over 3 s per pose: per-axis standard deviation and the largest norm. The ``default``
   preset's 2.5 N gate threshold is set from it (docs/presets.md, "Presets").
"""

from __future__ import annotations

import argparse
from dataclasses import dataclass

import mujoco
import numpy as np

from impact_control.controller import ImpactController
from impact_control.dynamics import PinocchioArm
from impact_control.ik import HOME_Q, solve_ik
from impact_control.lie import matrix_to_quat, so3_exp
from impact_control.presets import preset_config
from impact_envs.cli import add_robot_set
from impact_envs.envs.options import RobotOptions, apply_robot_overrides
from impact_envs.envs.robot_parts import build_robot
from impact_envs.loop import control_tick
from impact_envs.robot.sim import FrankaSim

R_DOWN = np.diag([1.0, -1.0, -1.0])


@dataclass
class Rig:
    """A bare closed loop (no task): sim + controller model + controller + noise RNG."""

    sim: FrankaSim
    arm: PinocchioArm
    controller: ImpactController
    rng: np.random.Generator

    @classmethod
    def build(cls, scene: str, mode: str, estimator: str, seed: int, noise: bool = True,
              preset: str = "default", robot: RobotOptions | None = None) -> Rig:
        """``robot`` (default: the ideal robot, ``noise`` as its ``sensor_noise``) gives the
        simulator and the controller's model (``build_robot``: a profile's model errors,
        offsets, delay and encoder steps; its offsets do not drift here, a rig's runs last
        seconds)."""
        sim, arm, _ = build_robot(robot or RobotOptions(sensor_noise=noise), scene)
        cfg = preset_config(preset, estimator=estimator)
        return cls(sim, arm, ImpactController(arm, cfg, mode=mode), np.random.default_rng(seed))

    def start(self, q0: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Place the arm at rest at ``q0``; return the TCP target (position, quaternion)."""
        self.sim.reset_robot(q0, 0.04, self.rng)
        mujoco.mj_forward(self.sim.model, self.sim.data)
        self.controller.reset(q0)
        pos, rot = self.sim.tcp_pose()
        return pos, matrix_to_quat(rot)

    def run(
        self,
        pos: np.ndarray,
        quat: np.ndarray,
        seconds: float,
        wrench_on_tcp: tuple[np.ndarray, np.ndarray] | None = None,
    ) -> None:
        """Hold the target for ``seconds``, optionally applying (force, torque) at the TCP."""
        for _ in range(round(seconds / self.sim.dt)):
            if wrench_on_tcp is not None:
                _apply_wrench_at_tcp(self.sim, *wrench_on_tcp)
            control_tick(self.sim, self.controller, self.rng, pos, quat, -1.0)


def _apply_wrench_at_tcp(sim: FrankaSim, force: np.ndarray, torque: np.ndarray) -> None:
    """Apply ``force`` [N] at the TCP point and ``torque`` [Nm], both in the world frame."""
    hand = sim.model.body("hand").id
    lever = sim.tcp_pose()[0] - sim.data.xipos[hand]
    sim.data.xfrc_applied[hand] = np.concatenate([force, torque + np.cross(lever, force)])


def wrench_recovery(
    estimator: str, n_poses: int = 5, seed: int = 0, settle_s: float = 1.0, measure_s: float = 4.0,
    robot: RobotOptions | None = None,
) -> list[dict[str, float]]:
    """Force/torque estimation errors [N, Nm] at steady state in ``n_poses`` random poses."""
    rng = np.random.default_rng(seed)
    rows = []
    for i in range(n_poses):
        rig = Rig.build("payload_scene.xml", "impedance", estimator, seed + i, robot=robot)
        rig.sim.model.body_mass[rig.sim.model.body("payload").id] = 1e-6
        pos = rng.uniform([0.35, -0.2, 0.2], [0.55, 0.2, 0.5])
        rot = so3_exp(rng.uniform(-0.3, 0.3, 3)) @ R_DOWN
        target_pos, target_quat = rig.start(solve_ik(rig.arm, pos, rot))
        rig.run(target_pos, target_quat, settle_s)
        force = rng.uniform(-1.0, 1.0, 3) * 15.0
        torque = rng.uniform(-1.0, 1.0, 3) * 1.0
        rig.run(target_pos, target_quat, measure_s, (force, torque))
        est = rig.controller.signals.wrench_slow_world
        rows.append(
            {
                "pose": i,
                "estimator": estimator,
                "force_err_n": float(np.linalg.norm(est[:3] + force)),
                "torque_err_nm": float(np.linalg.norm(est[3:] + torque)),
                "force_applied_n": float(np.linalg.norm(force)),
            }
        )
    return rows


def noise_floor(n_poses: int = 5, seed: int = 0, measure_s: float = 3.0,
                robot: RobotOptions | None = None) -> dict[str, float]:
    """Force noise [N] of the raw estimate and of w_slow (default preset) at rest, no load."""
    rng = np.random.default_rng(seed)
    raw, slow = [], []
    for i in range(n_poses):
        rig = Rig.build("payload_scene.xml", "impedance", "residual", seed + i, robot=robot)
        rig.sim.model.body_mass[rig.sim.model.body("payload").id] = 1e-6
        pos = rng.uniform([0.35, -0.2, 0.2], [0.55, 0.2, 0.5])
        rot = so3_exp(rng.uniform(-0.3, 0.3, 3)) @ R_DOWN
        target_pos, target_quat = rig.start(solve_ik(rig.arm, pos, rot))
        rig.run(target_pos, target_quat, 1.0)
        sig = rig.controller.signals
        pose_raw, pose_slow = [], []
        for _ in range(round(measure_s / rig.sim.dt)):
            control_tick(rig.sim, rig.controller, rig.rng, target_pos, target_quat, -1.0)
            pose_raw.append(sig.wrench_ext_world[:3].copy())
            pose_slow.append(sig.wrench_slow_world[:3].copy())
        # each pose's own mean removed: its bias (the model's, a profile's sensor offsets at
        # that pose) is not noise
        raw.append(np.array(pose_raw) - np.mean(pose_raw, axis=0))
        slow.append(np.array(pose_slow) - np.mean(pose_slow, axis=0))
    raw_a, slow_a = np.concatenate(raw), np.concatenate(slow)
    return {"raw_std_n": float(raw_a.std(axis=0).max()),
            "raw_max_norm_n": float(np.linalg.norm(raw_a, axis=1).max()),
            "slow_std_n": float(slow_a.std(axis=0).max()),
            "slow_max_norm_n": float(np.linalg.norm(slow_a, axis=1).max())}


def payload_hold(mode: str, mass_kg: float = 5.0, hold_s: float = 5.0, seed: int = 0,
                 estimator: str = "residual", preset: str = "default",
                 robot: RobotOptions | None = None) -> dict[str, float]:
    """TCP sag [m] below a fixed target while holding ``mass_kg`` that appears at t = 0.

    Returns the sag at 3 s and at the end, the worst sag, the full position error (which also
    holds the joint-friction dead-band), and ``settle_3mm_s``: the time after which the sag
    stays within 3 mm (NaN if it never does).
    """
    rig = Rig.build("payload_scene.xml", mode, estimator, seed, preset=preset, robot=robot)
    model = rig.sim.model
    body = model.body("payload").id
    inertia = model.body_inertia[body].copy() / model.body_mass[body]
    model.body_mass[body] = 1e-6
    target_pos, target_quat = rig.start(HOME_Q)
    rig.run(target_pos, target_quat, 1.0)
    model.body_mass[body] = mass_kg  # the payload appears (rigidly welded at the TCP)
    model.body_inertia[body] = inertia * mass_kg
    n = round(hold_s / rig.sim.dt)
    sag, err = np.zeros(n), np.zeros(n)
    for k in range(n):
        control_tick(rig.sim, rig.controller, rig.rng, target_pos, target_quat, -1.0)
        pos = rig.sim.tcp_pose()[0]
        sag[k] = target_pos[2] - pos[2]
        err[k] = np.linalg.norm(target_pos - pos)
    outside = np.flatnonzero(np.abs(sag) > 3e-3)
    settle = 0.0 if outside.size == 0 else (outside[-1] + 1) * rig.sim.dt
    k3 = round(3.0 / rig.sim.dt) - 1
    return {"mode": mode, "mass_kg": mass_kg, "sag_3s_m": float(sag[k3]),
            "error_3s_m": float(err[k3]), "final_sag_m": float(sag[-1]),
            "final_error_m": float(err[-1]), "max_sag_m": float(sag.max()),
            "settle_3mm_s": float(settle) if settle < hold_s else float("nan"),
            "expected_impedance_sag_m": mass_kg * 9.81 / 400.0}


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--poses", type=int, default=5)
    parser.add_argument("--seed", type=int, default=0)
    add_robot_set(parser)
    args = parser.parse_args(argv)
    robot = apply_robot_overrides(None, args.robot_set)
    print(f"robot: {robot.resolved_realism()}\n")
    print("## Wrench recovery (noise on; tolerance 1 N / 0.1 Nm)")
    print("| estimator | pose | applied force [N] | force error [N] | torque error [Nm] |")
    print("|---|---|---|---|---|")
    for est in ("residual", "momentum"):
        for r in wrench_recovery(est, args.poses, args.seed, robot=robot):
            print(
                f"| {est} | {r['pose']} | {r['force_applied_n']:.1f} | "
                f"{r['force_err_n']:.3f} | {r['torque_err_nm']:.4f} |"
            )
    r = noise_floor(args.poses, args.seed, robot=robot)
    print("\n## Noise floor at rest, no load (force axes; per-pose mean removed)")
    print("| signal | largest per-axis std [N] | largest norm [N] |\n|---|---|---|")
    print(f"| raw estimate | {r['raw_std_n']:.3f} | {r['raw_max_norm_n']:.3f} |")
    print(f"| w_slow (default preset) | {r['slow_std_n']:.3f} | {r['slow_max_norm_n']:.3f} |")
    print("\n## 5 kg payload appears at t = 0; arm holds a fixed target (noise on)")
    print("| controller | sag at 3 s [mm] | error at 3 s [mm] | sag at 5 s [mm] | "
          "error at 5 s [mm] | max sag [mm] | sag within 3 mm after [s] | m g / K [mm] |")
    print("|---|---|---|---|---|---|---|---|")
    for mode, preset in (("impedance", "default"), ("impact", "default"), ("impact", "paper")):
        r = payload_hold(mode, seed=args.seed, preset=preset, robot=robot)
        label = mode if mode == "impedance" else f"{mode} ({preset})"
        print(f"| {label} | {1e3 * r['sag_3s_m']:.1f} | {1e3 * r['error_3s_m']:.1f} | "
              f"{1e3 * r['final_sag_m']:.1f} | {1e3 * r['final_error_m']:.1f} | "
              f"{1e3 * r['max_sag_m']:.1f} | "
              f"{r['settle_3mm_s']:.2f} | {1e3 * r['expected_impedance_sag_m']:.1f} |")


if __name__ == "__main__":
    main()
