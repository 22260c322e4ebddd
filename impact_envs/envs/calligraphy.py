"""``IMPACT/Calligraphy-v1``."""

from __future__ import annotations

from impact_envs.envs.base import ImpactEnv
from impact_envs.tasks.calligraphy import CalligraphyTask


class CalligraphyEnv(ImpactEnv):
    """Calligraphy: write a character with a hand-held pen, pressing on the paper.

    ## Description
    The paper's hybrid position–force task. A pen (tip 0.10 m below the TCP, mass
    ``tool_mass``) is welded to the hand; the robot writes one character (a few lines and
    arcs: 十 口 人 大 工 〇) on paper lying on a 1 cm felt pad while pressing with 15 N along
    the surface normal. The policy commands the pen-tip trajectory through TCP pose targets;
    whenever the commanded tip is on the paper (within 2 mm) and the real tip within 3 cm of
    it, the env adds an explicit pressing wrench (0, 0, −15 N) (ramped at 60 N/s) and freezes
    internal-model learning on the normal axis, so IMPACT learns the tool weight in free air
    and the paper drag while writing but never the intended contact force (docs/envs.md). The
    controller's model does not include the pen: the tool weight is an unmodelled load.

    ## Action space
    ``Box(10,)`` float32: TCP target position [m, world] (clipped to the workspace box
    x 0.15–0.70, y −0.45–0.45, z 0.0–0.60), rot6d of the TCP target orientation, gripper
    command in [−1, +1] (the pen is welded, the gripper only closes around it).

    ## Observation space
    ``Dict`` of flat float32 Boxes: ``ee_pos`` (3) [m], ``ee_rot6d`` (6), ``gripper_width``
    (1) [m], ``joint_pos`` (7) [rad], ``joint_vel`` (7) [rad/s] (noisy robot sensors),
    ``object_pos`` (3) [m] pen-tip point, ``object_rot6d`` (6) pen orientation (z along the
    pen toward the tip), ``goal_pos`` (3) [m] pen-tip reference at the end of the coming
    policy step (hover above the paper between strokes, on the paper while writing). No force
    sensing in observations.

    Pixel modes, ``observation=ObservationOptions(obs_mode=...)``: ``"rgb"`` adds
    ``"<camera>_rgb"`` uint8 Boxes (H, W, 3) in [0, 255], one per camera (default
    ``("overview", "wrist")`` at 96x96 px, rendered once per step); ``"rgbd"`` adds
    ``"<camera>_depth"`` float32 (H, W, 1) [m] too; ``"state+rgb"`` keeps every entry above.
    ``"rgb"`` and ``"rgbd"`` leave out ``object_pos`` and ``object_rot6d``;
    ``goal_pos`` stays (a command: no camera sees a character before it is written).

    ## Rewards
    Sparse (default, ``reward_type="sparse"``): 1.0 on steps where the task is
    accomplished, else 0.0. ``reward_type="dense"``: a shaped reward in [0, 1], 1.0
    exactly on success: follow the pen-tip reference (1 cm error halves that part) and,
    while writing, keep the normal force in its band.

    ## Success
    After the last stroke (``info["writing_done"]``), over all samples taken at 100 Hz while
    a stroke is being written: RMS distance of the pen tip from the intended stroke
    ≤ 5 mm (``stroke_rms_m``), tip normal force in [7.5, 22.5] N for ≥ 90 % of them
    (``in_band_frac``), and no contact gap longer than 50 ms (``contact_lost``). Per step,
    ``info`` also has ``normal_force_n``, ``in_band``, ``pressing``, ``writing``,
    ``character``, ``tool_mass`` and (v1 only) its alias ``object_mass``; once writing is done,
    ``failure_reason`` names the missed criteria ("" if none; impact-eval records it).

    ## Randomization
    From ``env.np_random`` at reset: the character (6), its centre x ∈ [0.38, 0.44] m,
    y ∈ [−0.06, 0.06] m, rotation ±15°, scale 0.9–1.1 (≈6 cm tall); initial joints home
    ± 0.03 rad; torque-sensor offsets. Tool mass and paper friction from the kwargs/options.
    The reference is time-indexed: 3 s at 8 cm above the first stroke, then per stroke
    descend (5 cm/s), dwell 0.6 s, write at 3 cm/s, lift, travel; 11–18 s in total.

    ## Episode end
    Truncation after 600 steps (20 s); termination on success only with
    ``terminate_on_success=True``. ``SimulationError`` if the physics diverges.

    ## Arguments
    ``controller`` ("impact" | "impedance"), ``task_params={"tool_mass": kg,
    "surface_friction": μ}`` or ``reset(options=...)`` (tool_mass default 0.1, range
    0.02–5 kg, the sweep axis; surface_friction default 0.3, range 0.05–1.5),
    ``controller_preset``, ``robot``, ``persist_internal_model``, ``terminate_on_success``,
    ``reward_type``, ``render_mode`` ("rgb_array"), ``render``, ``observation`` (as for
    ``IMPACT/Hammer-v1``).

    ## Version history
    In ``impact_envs/versions.py`` (``VERSIONS["Calligraphy"]``, the table in docs/envs.md), one
    history for every env. v2 (current, 2026-12-02): the robot as imperfect as a real FR3
    by default (``RobotOptions.realism`` unset means ``"fr3"``) and preset revision 2
    (``default`` = ``keep_carried``). v1: the behaviour of the last v0 (2026-11-28), kept
    registered with its ideal robot and preset revision 1 pinned, so its tables reproduce.
    v0: retired (it changed behaviour under one name; a one-line error names v1).
    """

    @classmethod
    def make_task(cls) -> CalligraphyTask:
        return CalligraphyTask()
