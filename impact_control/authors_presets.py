"""The authors' released IMPACT controller as two presets, ``authors_sim`` and
``authors_real``, written from the facts of their repository (``Winston-Gu/IMPACT`` @ 3437426,
Apache-2.0; read, not copied). Paths below are inside it:

- CPP = ``ros_ws/src/predictive_controller/src/cerebellum_predictive_controller.cpp``
- SCHEMA = ``.../src/cerebellum_predictive_controller.yaml`` (parameter defaults)
- RUN = ``ros_ws/src/system_bringup/config/controller/predictive_controllers.yaml`` (the
  runtime values, lines 117-182)
- SIM = ``ros_ws/src/sim_bringup/config/mujoco_overrides.yaml`` (their simulation's
  overrides, lines 11-21)

Each value below cites where it is set; docs/presets.md ("The authors' controller") has
the table. Where their code does something other than its own description, the presets
run it as coded and the intended variant is one field away:

- null-space damping: SCHEMA 126-131 says "if negative, then 2 sqrt(stiffness)", CPP 952-959
  tests ``if (params_.nullspace.damping)`` (true for -1) and multiplies by -1: the presets
  run d_n = -1 Nm s/rad; ``impedance.nullspace_damping_nms_per_rad=none`` is 2 sqrt(k_n);
- gripper hold-off in simulation: RUN 180 subscribes the controller to
  ``/fr3_right/gripper/gripper_position_controller/commands``, their simulation's policy and
  gripper use ``/gripper/gripper_position_controller/commands``
  (``sim_bringup/sim_bringup/policy_deployment.py`` 106-108,
  ``sim_bringup/launch/franka_mujoco.launch.py`` 183-185, no namespace in
  ``scripts/run_mass_sweep.sh`` 94-107): the hold-off never fires there, so ``authors_sim``
  runs ``payload.gripper_holdoff=False``; ``True`` is the intended variant.
"""

from __future__ import annotations

import math
from dataclasses import replace

from impact_control.config import ControllerConfig
from impact_control.contact_guard import ContactGuardConfig
from impact_control.impedance_config import ImpedanceConfig
from impact_control.joint_limits import JointLimitConfig
from impact_control.limits import LimitsConfig
from impact_control.payload_model import PayloadModelConfig
from impact_control.saturation_release import SaturationReleaseConfig
from impact_control.slow_filter import SlowWrenchConfig
from impact_control.target_filter import TargetFilterConfig
from impact_control.wrench_observer import WrenchObserverConfig

AUTHORS_PRESETS: tuple[str, ...] = ("authors_sim", "authors_real")
"""The presets of the authors' controller: their simulation's and their robot's values."""
SIM_ONLY: dict[str, str] = {
    "authors_sim": "it compensates gravity in the controller and rate-limits the command with "
                   "gravity, as the authors' simulation does; on an FR3 use authors_real",
}
"""Presets that must not run on a real FR3, with the reason (``impact-robot`` refuses them)."""


def _impedance(robot: bool) -> ImpedanceConfig:
    d_rot = 2.0 * math.sqrt(30.0)  # SCHEMA d_* = -1 -> 2 sqrt(k) (CPP 933-939)
    return ImpedanceConfig(
        stiffness_translational_n_per_m=(400.0, 400.0, 400.0),  # RUN 137-139
        stiffness_rotational_nm_per_rad=(30.0, 30.0, 30.0),  # RUN 140-142
        damping_translational_ns_per_m=(40.0, 40.0, 40.0),
        damping_rotational_nms_per_rad=(d_rot, d_rot, d_rot),
        nullspace_stiffness_nm_per_rad=2.0,  # RUN 145 (weights 1: SCHEMA 132-139)
        nullspace_damping_nms_per_rad=-1.0,  # as coded: CPP 952-959 (SCHEMA 126-131 default)
        nullspace_pinv_damping=1e-6,  # SCHEMA 140-145; kinematic projector CPP 236-239
        compensate_gravity=True, compensate_coriolis=True,  # SIM 13 / robot adds its own; RUN 148
        gains_frame="tcp",  # RUN 149 use_local_jacobian (CPP 198-204, 220-222)
        pose_error_clip_m=0.1 if robot else None,  # SCHEMA 93-105, limit_error 486-489; SIM 14
        pose_error_clip_rad=0.5 if robot else None,  # SCHEMA 106-117 (CPP 212-217)
        nullspace_torque_max_nm=5.0,  # SCHEMA 152-155 (CPP 274-278)
    )


def _optional(config: ControllerConfig, robot: bool) -> ControllerConfig:
    return replace(
        config,
        # CPP 193-194 (filters.hpp 24-27), SCHEMA 459-465: 0.1 on the previous pose
        target_filter=TargetFilterConfig(enabled=True, weight_new=0.9),
        observer=WrenchObserverConfig(
            enabled=True, lowpass_alpha_per_tick=0.02,  # RUN 154-155 (CPP 366-374)
            force_norm_max_n=80.0 if robot else 120.0,  # SCHEMA 215-220; SIM 18
            torque_norm_max_nm=15.0 if robot else 50.0,  # SCHEMA 222-227; SIM 19
            warmup_ticks=100, frame="tcp"),  # SCHEMA 236-241 (CPP 336-341)
        payload=PayloadModelConfig(
            enabled=True,  # RUN 176 (CPP 411-472)
            hold_on_n=2.0, update_min_force_n=1.0,  # SCHEMA 341-346, 334-339
            feedforward_holdoff_s=0.5, reset_ratio=0.8,  # RUN 177-178
            surprise_lowpass_alpha=1e-4, surprise_threshold_n=5.0,  # RUN 182; SCHEMA 369-374
            learning_rate=0.01, estimate_max_n=100.0,  # SCHEMA 327-332, 400-405
            slow_rate_max=0.2,  # RUN 181
            gripper_holdoff=robot,  # SCHEMA 383-393 on; sim: never fires (module docstring)
            gripper_open_above=0.1,  # SCHEMA 388-393
            feedforward="estimate" if robot else "slow_wrench"),  # RUN 179; SIM 17 (CPP 496-513)
        joint_limits=JointLimitConfig(torque_max_nm=5.0, range_rad=0.3),  # CPP 264-272
    )


def authors_config(robot: bool) -> ControllerConfig:
    """The authors' controller: their robot's values (``robot``, preset ``authors_real``) or
    their simulation's (``authors_sim``)."""
    config = ControllerConfig(
        impedance=_impedance(robot),
        slow_wrench=SlowWrenchConfig(
            rate_force_per_s=0.5 if robot else 2.0,  # RUN 163; SIM 15 (CPP 86-95)
            rate_torque_per_s=0.5 if robot else 1.0,  # RUN 164; SIM 16
            clip_force_n=10.0, clip_torque_nm=1.0,  # RUN 166-167
            frame="tcp", leak_per_s=0.01,  # RUN 169 (CPP 97-101)
            force_norm_max_n=50.0 if robot else 120.0,  # RUN 171; SIM 20 (CPP 103-108)
            torque_norm_max_nm=8.0 if robot else 50.0),  # RUN 172; SIM 21
        limits=LimitsConfig(
            torque_rate_max_nm_per_s=500.0,  # SCHEMA 491-499: 0.5 Nm per 1 ms tick
            rate_limiter="per_tick_clip",  # torque_rate_saturation.hpp 19-26 (CPP 635-638)
            rate_limit_includes_gravity=not robot),  # SIM 13: gravity in tau_d (CPP 327-330)
        guard=ContactGuardConfig(enabled=False),  # not theirs (and unused: no internal model)
        saturation_release=SaturationReleaseConfig(enabled=False),  # ours (issue 37 item 5)
    )
    return _optional(config, robot)
