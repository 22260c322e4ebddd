"""``IMPACT/Disturbance-v1``."""

from __future__ import annotations

from impact_envs.envs.base import ImpactEnv
from impact_envs.tasks.disturbance import DisturbanceTask


class DisturbanceEnv(ImpactEnv):
    """Carry-and-hold under external disturbance forces and a mid-episode load change.

    ## Description
    The paper's disturbance-compensation task. An open trough (16 × 5 × 6 cm, 0.3 kg) lies on
    the table; the robot grasps it across its long walls at the centre (= its centre of mass),
    lifts it, carries it to a goal point in the air and holds it there. Once the trough is
    lifted, an external force acts on its centre of mass (``xfrc_applied``, every 1 kHz tick)
    with a per-episode profile: **constant** (from the lift), **step** (on 1.0–2.5 s after the
    lift) or **slow** (a smooth ramp ``A (1 − cos(π t / T)) / 2`` over T = 3–5 s, then
    constant), of peak magnitude
    ``disturbance_n`` (the sweep axis) along a random direction (any azimuth, elevation ±30°).
    3–4 s after the lift the object dynamics change: ``added_mass`` is added to the trough
    (sand appears in it; mass and inertia are written directly, without ``mj_setConst``). The
    controller model knows neither the trough nor the forces.

    ## Action space
    ``Box(10,)`` float32: TCP target position [m, world] (clipped to the workspace box
    x 0.15–0.70, y −0.45–0.45, z 0.0–0.60), rot6d of the TCP target orientation, gripper
    command in [−1 open, +1 close with the grasp force].

    ## Observation space
    ``Dict`` of flat float32 Boxes: ``ee_pos`` (3) [m], ``ee_rot6d`` (6), ``gripper_width``
    (1) [m], ``joint_pos`` (7) [rad], ``joint_vel`` (7) [rad/s] (noisy robot sensors),
    ``object_pos`` (3) [m] trough centre of mass, ``object_rot6d`` (6) trough orientation
    (x along its length), ``goal_pos`` (3) [m] goal point for the centre of mass. No force
    sensing in observations.

    Pixel modes, ``observation=ObservationOptions(obs_mode=...)``: ``"rgb"`` adds
    ``"<camera>_rgb"`` uint8 Boxes (H, W, 3) in [0, 255], one per camera (default
    ``("overview", "wrist")`` at 96x96 px, rendered once per step); ``"rgbd"`` adds
    ``"<camera>_depth"`` float32 (H, W, 1) [m] too; ``"state+rgb"`` keeps every entry above.
    ``"rgb"`` and ``"rgbd"`` leave out ``object_pos``, ``object_rot6d`` and
    ``goal_pos`` (the policy sees the object and the goal marker in the images).

    ## Rewards
    Sparse (default, ``reward_type="sparse"``): 1.0 on steps where the task is
    accomplished, else 0.0. ``reward_type="dense"``: a shaped reward in [0, 1], 1.0
    exactly on success: reach, grasp, lift and carry the trough to the goal
    (``pick_place_reward``), plus the time held.

    ## Success
    Once the load has been added and the disturbance has reached its final value (step on,
    ramp done), the trough has been grasped (both fingers touching) with its centre of mass
    within 3 cm of the goal continuously for 2 s (``info["hold_s"]`` ≥ 2). ``info`` also has
    ``disturbance_kind``, ``disturbance_force_world`` [N] (the force applied on the last
    tick), ``lifted``, ``load_added``, ``goal_error_m``, ``is_grasped``.

    ## Randomization
    From ``env.np_random`` at reset: trough centre x ∈ [0.36, 0.42] m, y ∈ [0.10, 0.18] m,
    yaw ±30°; goal x ∈ [0.36, 0.44] m, y ∈ [−0.12, 0.00] m, z ∈ [0.20, 0.28] m; disturbance
    kind, direction, step onset, ramp time; load time 3–4 s after the lift; initial joints
    home ± 0.03 rad; torque-sensor offsets. Magnitude and masses from kwargs / options.

    ## Episode end
    Truncation after 540 steps (18 s); termination on success only with
    ``terminate_on_success=True``. ``SimulationError`` if the physics diverges.

    ## Arguments
    ``controller`` ("impact" | "impedance"), ``task_params={"disturbance_n": N,
    "object_mass": kg, "added_mass": kg}`` or ``reset(options=...)`` (defaults 2 N, 0.3 kg,
    0.3 kg; ranges 0–40 N, 0.05–5 kg, 0–5 kg), ``object_mass`` [kg] (shortcut),
    ``controller_preset``, ``robot``, ``persist_internal_model``, ``terminate_on_success``,
    ``reward_type``, ``render_mode`` ("rgb_array"), ``render``, ``observation`` (as for
    ``IMPACT/Hammer-v1``).

    ## Version history
    In ``impact_envs/versions.py`` (``VERSIONS["Disturbance"]``, the table in docs/envs.md), one
    history for every env. v2 (current, 2026-12-02): the robot as imperfect as a real FR3
    by default (``RobotOptions.realism`` unset means ``"fr3"``) and preset revision 2
    (``default`` = ``keep_carried``). v1: the behaviour of the last v0 (2026-11-28), kept
    registered with its ideal robot and preset revision 1 pinned, so its tables reproduce.
    v0: retired (it changed behaviour under one name; a one-line error names v1).
    """

    @classmethod
    def make_task(cls) -> DisturbanceTask:
        return DisturbanceTask()
