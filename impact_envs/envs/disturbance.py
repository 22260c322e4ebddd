"""``IMPACT/Disturbance-v0``."""

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
    ``IMPACT/Hammer-v0``).

    ## Version history
    - v0: initial release (unreleased; tables in docs/ are regenerated on change). 2026-11-22:
      the disturbance acts only while the trough is held. 2026-11-24: the ``default``
      controller preset replaces the paper-literal one (``controller_preset="paper"``).
      2026-11-25: bad input only: an action must have shape ``(10,)`` (others were
      flattened) and a parameter value must be a real number (bools and strings were coerced).
      2026-11-25: constructor arguments grouped (no number changes): ``sensor_noise``,
      ``grasp_force_n`` and ``model_mass_error`` are now fields of
      ``robot=RobotOptions(...)``, ``width``, ``height`` and ``camera`` of
      ``render=RenderOptions(...)``, and ``controller_preset`` also takes a
      ``ControllerConfig`` (replacing ``controller_config``).
      2026-11-25: ``reward_type="dense"`` added (sparse stays the default).
      2026-11-26: pixel observations (``observation=ObservationOptions(...)``) and a
      ``"wrist"`` camera added; the default ``"state"`` mode is unchanged bit for bit.
      2026-11-26: ``estimator`` removed from the constructor (no number changes): the
      wrench estimator is a field of the controller's config, chosen with
      ``controller_preset=preset_config("default", estimator="momentum")``.
      2026-11-27: ``controller_preset`` also takes ``"authors_sim"`` and ``"authors_real"``
      (the paper authors' released controller) and ``RobotOptions`` gains ``torque_reading``
      (default ``"link_side"``, unchanged). The ``default`` preset gains the saturated-lift
      release (docs/controller.md): with a load the wrist cannot hold, the learned
      feedforward is let go after 0.5 s at a torque bound without the load rising; episodes
      that never stall at a bound are unchanged bit for bit, ``paper`` is unchanged.
    """

    @classmethod
    def make_task(cls) -> DisturbanceTask:
        return DisturbanceTask()
