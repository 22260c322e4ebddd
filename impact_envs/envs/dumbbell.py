"""``IMPACT/Dumbbell-v1``."""

from __future__ import annotations

from impact_envs.envs.base import ImpactEnv
from impact_envs.tasks.dumbbell import DumbbellTask


class DumbbellEnv(ImpactEnv):
    """Heavy dumbbell pick-and-place with a torque-controlled Franka FR3 + Franka Hand.

    ## Description
    The paper's heavy-object task (2.5 kg and 5 kg dumbbells). A hex dumbbell (two hexagonal
    plates, 0.1 m across the corners, on a 0.205 m bar; centre of mass at the bar centre) lies
    flat on the table; the robot must grasp the bar at its centre, lift it, carry it and put it
    down flat on a green pad. The dumbbell mass is the varying parameter (default 2.5 kg, up
    to 12 kg); inertia scales with mass (uniform density, fixed COM). A policy acts at 30 Hz
    with absolute TCP pose targets; inside the env a 1 kHz torque controller
    (``controller="impact"`` or ``"impedance"``) tracks them on noisy encoder and joint-torque
    readings, with FR3 torque limits (87/12 Nm) and torque-rate limit (1000 Nm/s).

    ## Action space
    ``Box(10,)`` float32: TCP target position [m, world] (clipped to the workspace box
    x 0.15–0.70, y −0.45–0.45, z 0.0–0.60), rot6d of the TCP target orientation (first two
    columns of the rotation matrix, column-major, re-orthonormalized by Gram–Schmidt),
    gripper command in [−1 open, +1 close with the grasp force].

    ## Observation space
    ``Dict`` of flat float32 Boxes: ``ee_pos`` (3) [m], ``ee_rot6d`` (6), ``gripper_width``
    (1) [m], ``joint_pos`` (7) [rad], ``joint_vel`` (7) [rad/s] (all from the noisy robot
    sensors, TCP pose by forward kinematics), ``object_pos`` (3) [m] dumbbell centre of mass
    (= bar centre), ``object_rot6d`` (6) dumbbell orientation (x axis along the bar),
    ``goal_pos`` (3) [m] pad centre on the table. No force sensing in observations.

    Pixel modes, ``observation=ObservationOptions(obs_mode=...)``: ``"rgb"`` adds
    ``"<camera>_rgb"`` uint8 Boxes (H, W, 3) in [0, 255], one per camera (default
    ``("overview", "wrist")`` at 96x96 px, rendered once per step); ``"rgbd"`` adds
    ``"<camera>_depth"`` float32 (H, W, 1) [m] too; ``"state+rgb"`` keeps every entry above.
    ``"rgb"`` and ``"rgbd"`` leave out ``object_pos``, ``object_rot6d`` and
    ``goal_pos`` (the policy sees the object and the pad in the images).

    ## Rewards
    Sparse (default, ``reward_type="sparse"``): 1.0 on steps where the task is
    accomplished, else 0.0. ``reward_type="dense"``: a shaped reward in [0, 1], 1.0
    exactly on success: reach the bar centre, grasp, lift 2 cm, bring it to its resting
    height on the pad (``pick_place_reward``).

    ## Success
    Both plates lie above the pad's footprint (0.30 × 0.18 m), the centre of mass is within
    1 cm of the lying-flat height on the pad (0.0533 m), its speed is below 5 cm/s (resting)
    and no finger touches it (released). ``info["is_success"]`` every step,
    ``info["success_once"]``, plus ``info["is_grasped"]`` and ``info["on_pad"]``.

    ## Randomization
    From ``env.np_random`` at reset: dumbbell COM x ∈ [0.34, 0.40] m, y ∈ [0.12, 0.18] m,
    yaw ±30°; pad centre x ∈ [0.32, 0.38] m, y ∈ [−0.20, −0.14] m (everything within
    ≈0.44 m of the base, where 10 kg stays inside the joint-torque limits, docs/robot.md);
    initial joints home ± 0.03 rad; torque-sensor offsets. The mass comes from
    ``object_mass`` or ``reset(options={"object_mass": m})``.

    ## Episode end
    Truncation after 750 steps (25 s); termination on success only with
    ``terminate_on_success=True``. ``SimulationError`` if the physics diverges.

    ## Arguments
    As for ``IMPACT/Hammer-v1`` (``controller``, ``controller_preset``,
    ``robot``, ``persist_internal_model``, ``terminate_on_success``, ``reward_type``,
    ``render_mode``, ``render``, ``observation``), with ``object_mass`` [kg] defaulting to 2.5
    (range 0.1–12).

    ## Version history
    In ``impact_envs/versions.py`` (``VERSIONS["Dumbbell"]``, the table in docs/envs.md), one
    history for every env. v2 (current, 2026-12-02): the robot as imperfect as a real FR3
    by default (``RobotOptions.realism`` unset means ``"fr3"``) and preset revision 2
    (``default`` = ``keep_carried``). v1: the behaviour of the last v0 (2026-11-28), kept
    registered with its ideal robot and preset revision 1 pinned, so its tables reproduce.
    v0: retired (it changed behaviour under one name; a one-line error names v1).
    """

    @classmethod
    def make_task(cls) -> DumbbellTask:
        return DumbbellTask()
