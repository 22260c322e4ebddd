"""``IMPACT/HammerBasket-v1``."""

from __future__ import annotations

from impact_envs.envs.base import ImpactEnv
from impact_envs.tasks.hammer_basket import HammerBasketTask


class HammerBasketEnv(ImpactEnv):
    """The paper authors' hammer-basket benchmark, rebuilt in our env.

    ## Description
    The scene and protocol of the IMPACT authors' released simulation (their
    ``scene_hammer_basket.xml`` and mass-sweep script; ../shared/reference/authors_impact.md),
    rebuilt here from their published facts (docs/hammer_basket.md lists each value and its
    source): a work table 0.23 m above the robot base; a 0.29 × 0.095 × 0.06 m hammer whose
    centre of mass lies 4.4 cm from its body origin, toward the head; a free 2.2 kg basket with
    a 0.4 × 0.4 m floor; friction 4.0 / 1.0 / 0.001 with condim 6 on the hammer, also against
    the fingers; their simulated fingers' 200 N grasp force (``robot.hand="authors_sim"``);
    their home posture; 60 s episodes. Unlike ``IMPACT/Hammer-v1`` success is judged at the
    end of the episode only, by their test. The hammer mass is the varying parameter (their
    bins 0.1–10 kg; ``impact-eval --mass-bins``); inertia scales with mass (uniform density,
    fixed COM). A policy acts at 30 Hz with absolute TCP pose targets; inside, a 1 kHz torque
    controller (``controller="impact"`` or ``"impedance"``) tracks them on noisy encoder and
    joint-torque readings, with the FR3's torque limits.

    ## Action space
    ``Box(10,)`` float32: TCP target position [m, world] (clipped to the workspace box
    x 0.10–0.80, y −0.55–0.55, z 0.22–0.85), rot6d of the TCP target orientation, gripper
    command in [−1 open, +1 close with the grasp force].

    ## Observation space
    ``Dict`` of flat float32 Boxes: the robot's ``ee_pos`` (3) [m], ``ee_rot6d`` (6),
    ``gripper_width`` (1) [m], ``joint_pos`` (7) [rad], ``joint_vel`` (7) [rad/s] (noisy
    sensors), then ``object_pos`` (3) [m] hammer centre of mass, ``object_rot6d`` (6) hammer
    orientation (x axis toward the head), ``object_origin_pos`` (3) [m] the hammer's body
    origin (their grasp point and the point their success test reads), ``goal_pos`` (3) [m]
    basket centre. Pixel modes as for ``IMPACT/Hammer-v1``; the scene adds their two policy
    cameras, ``"basket_front"`` and ``"basket_side"``.

    ## Rewards
    Sparse (default): 1.0 on steps where their success test holds, else 0.0.
    ``reward_type="dense"``: ``tasks/base.py::pick_place_reward`` toward 5 cm above the
    basket centre, from the hammer's body origin.

    ## Success
    Their test: the hammer's body origin lies within ±0.1875 m of the basket centre in x and
    y (no height, release or contact check). ``info["is_success"]`` every step; an episode's
    outcome is its value at the end (``success_once``: whether it ever held).

    ## Randomization
    From ``env.np_random`` at reset: hammer body origin x ∈ [0.25, 0.40] m, y ∈ [−0.40, −0.20]
    m, no yaw, dropped from 5 mm above its resting height (their spawn rule); basket centre
    x ∈ [0.30, 0.40] m, y ∈ [0.10, 0.30] m; joints exactly at their home posture (0, −π/4,
    0, −3π/4, 0, π/2, π/4); torque-sensor offsets. The mass comes from ``object_mass`` or
    ``reset(options=...)`` (``impact-eval --mass-bins`` draws it within a bin).

    ## Episode end
    Truncation after 1800 steps (60 s). Never terminated early: ``terminate_on_success`` has
    no effect here (their protocol runs every episode for 60 s and reads the end).
    ``SimulationError`` if the physics diverges.

    ## Arguments
    As for ``IMPACT/Hammer-v1``; ``object_mass`` [kg] default 0.1 (their nominal), range
    0.05–12; ``robot=RobotOptions(...)``'s ``grasp_force_n`` defaults to 200 N and may not
    exceed it (their fingers; ``hand="franka_hand"`` gives the Franka Hand's 70 / 140 N).

    ## Version history
    In ``impact_envs/versions.py`` (``VERSIONS["HammerBasket"]``, the table in docs/envs.md), one
    history for every env. v2 (current, 2026-12-02): preset revision 2 (``default`` =
    ``keep_carried``); the robot stays the authors' ideal one. v1: the behaviour of the last
    v0 (2026-11-28), kept registered with preset revision 1 pinned, so its tables reproduce.
    v0: retired (it changed behaviour under one name; a one-line error names v1).
    """

    @classmethod
    def make_task(cls) -> HammerBasketTask:
        return HammerBasketTask()
