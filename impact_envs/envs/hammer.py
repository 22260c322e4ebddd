"""``IMPACT/Hammer-v1``."""

from __future__ import annotations

from impact_envs.envs.base import ImpactEnv
from impact_envs.tasks.hammer import HammerTask


class HammerEnv(ImpactEnv):
    """Hammer pick-and-place with a torque-controlled Franka FR3 + Franka Hand.

    ## Description
    The paper's simulation benchmark. A hammer (square 2.5 cm handle and a flat head, 60 % of
    the mass in the head) lies on the table; the robot must grasp it at its centre of mass,
    carry it and place it inside an open basket. The hammer mass is the varying parameter
    (0.1–10 kg in the paper's sweep); inertia scales with mass (uniform density, fixed COM).
    A policy acts at 30 Hz with absolute TCP pose targets; inside the env a 1 kHz torque
    controller (``controller="impact"`` or ``"impedance"``) tracks them on noisy encoder and
    joint-torque readings, with FR3 torque limits (87/12 Nm) and torque-rate limit (1000 Nm/s).

    ## Action space
    ``Box(10,)`` float32: TCP target position [m, world] (clipped to the workspace box
    x 0.15–0.70, y −0.45–0.45, z 0.0–0.60), rot6d of the TCP target orientation (first two
    columns of the rotation matrix, column-major, re-orthonormalized by Gram–Schmidt),
    gripper command in [−1 open, +1 close with the grasp force].

    ## Observation space
    ``Dict`` of flat float32 Boxes: ``ee_pos`` (3) [m], ``ee_rot6d`` (6), ``gripper_width``
    (1) [m], ``joint_pos`` (7) [rad], ``joint_vel`` (7) [rad/s] (all from the noisy robot
    sensors, TCP pose by forward kinematics), ``object_pos`` (3) [m] hammer centre of mass,
    ``object_rot6d`` (6) hammer orientation (x axis points to the head), ``goal_pos`` (3) [m]
    basket centre. No force sensing in observations.

    Pixel modes, ``observation=ObservationOptions(obs_mode=...)``: ``"rgb"`` adds
    ``"<camera>_rgb"`` uint8 Boxes (H, W, 3) in [0, 255], one per camera (default
    ``("overview", "wrist")`` at 96x96 px, rendered once per step); ``"rgbd"`` adds
    ``"<camera>_depth"`` float32 (H, W, 1) [m] too; ``"state+rgb"`` keeps every entry above.
    ``"rgb"`` and ``"rgbd"`` leave out ``object_pos``, ``object_rot6d`` and
    ``goal_pos`` (the policy sees the object and the basket in the images).

    ## Rewards
    Sparse (default, ``reward_type="sparse"``): 1.0 on steps where the task is
    accomplished, else 0.0. ``reward_type="dense"``: a shaped reward in [0, 1], 1.0
    exactly on success: reach the hammer's centre of mass, grasp, lift 2 cm, carry it over
    the basket (``tasks/base.py::pick_place_reward``).

    ## Success
    The hammer's centre of mass lies inside the basket's inner footprint below the wall top
    (6 cm) and no finger touches it (released). ``info["is_success"]`` every step,
    ``info["success_once"]`` whether it ever held this episode.

    ## Randomization
    From ``env.np_random`` at reset: hammer COM x ∈ [0.36, 0.44] m, y ∈ [0.14, 0.22] m, yaw
    ±30°; basket centre x ∈ [0.33, 0.38] m, y ∈ [−0.27, −0.21] m; initial joints home ± 0.03 rad;
    torque-sensor offsets. The mass comes from ``object_mass`` or ``reset(options=...)``.

    ## Episode end
    Truncation after 750 steps (25 s); termination on success only with
    ``terminate_on_success=True``. ``SimulationError`` if the physics diverges.

    ## Arguments
    ``controller`` ("impact" | "impedance"), ``object_mass`` [kg] (default 0.2, range
    0.05–12), ``controller_preset`` ("default" | "paper" | "authors_sim" | "authors_real",
    docs/controller.md, or a ``ControllerConfig``, e.g.
    ``preset_config("default", estimator="momentum")`` for the momentum-observer wrench
    estimator; reported as
    ``info["controller_preset"]``, a config as its preset's name or "custom"), ``robot``
    (``RobotOptions``: ``sensor_noise`` bool, ``grasp_force_n`` default 70 N,
    ``model_mass_error`` relative error of the controller's link masses, ``realism`` "fr3" |
    "ideal", unset: the version's), ``env_version`` (set by the registered id: 2 for
    ``-v2``, 1 for ``-v1``; None: the current version),
    ``persist_internal_model`` (keep the learned internal model across resets),
    ``terminate_on_success``, ``reward_type`` ("sparse" | "dense"), ``render_mode``
    ("rgb_array"), ``render`` (``RenderOptions``: ``width``, ``height``, ``camera``
    "overview" (default since 2026-11-25: arm, objects and goal in view) | "front" | "side" |
    "wrist"), ``observation`` (``ObservationOptions``: ``obs_mode`` "state" (default) | "rgb" |
    "rgbd" | "state+rgb", ``cameras``, ``image_width``, ``image_height``, ``shadows``;
    docs/envs.md).

    ## Version history
    In ``impact_envs/versions.py`` (``VERSIONS["Hammer"]``, the table in docs/envs.md), one
    history for every env. v2 (current, 2026-12-02): the robot as imperfect as a real FR3
    by default (``RobotOptions.realism`` unset means ``"fr3"``) and preset revision 2
    (``default`` = ``keep_carried``). v1: the behaviour of the last v0 (2026-11-28), kept
    registered with its ideal robot and preset revision 1 pinned, so its tables reproduce.
    v0: retired (it changed behaviour under one name; a one-line error names v1).
    """

    @classmethod
    def make_task(cls) -> HammerTask:
        return HammerTask()
