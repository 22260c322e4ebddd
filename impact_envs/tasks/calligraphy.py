"""Calligraphy task: write a character with a hand-held pen while pressing on the paper.

Hybrid position–force objective (docs/envs.md): the policy commands the pen-tip pose; while
the commanded tip is on the paper (and the real tip is near it) the task adds an explicit
pressing force along −z (robot-on-environment sign) and freezes internal-model learning on the
normal axis, so the model learns the tool weight in free air and the tangential drag while
writing, but never the commanded pressing force (``calligraphy_force.py``).
"""

from __future__ import annotations

from collections.abc import Mapping

import mujoco
import numpy as np

from impact_control.ik import HOME_Q
from impact_control.lie import matrix_from_rot6d, rot6d_from_matrix
from impact_control.rates import POLICY_HZ
from impact_envs.robot.sim import FrankaSim
from impact_envs.tasks.base import BodyMass, ObsEntry, Task, TaskParam
from impact_envs.tasks.calligraphy_force import NormalForceCommand
from impact_envs.tasks.calligraphy_strokes import (
    CHARACTERS,
    Reference,
    WritingMetrics,
    build_reference,
    distance_to_path,
    place_strokes,
)
from impact_envs.versions import current_id

PEN_TIP_OFFSET_M = 0.10
"""Pen tip along the TCP z axis [m] (0.10 m below the TCP when the hand points down)."""
PAPER_TOP_M = 0.01
"""Height of the writing surface (paper on a 1 cm felt pad) [m]."""
FORCE_DESIRED_N = 15.0
"""Commanded normal (pressing) force [N]; above the ±5 N that the simulated joint Coulomb
friction (invisible to the link-side torque sensors) adds while the arm moves."""
FORCE_BAND_N = (7.5, 22.5)
"""A writing sample is "in band" when the tip's normal force lies in this range [N]."""
IN_BAND_MIN_FRAC = 0.9
STROKE_RMS_TOL_M = 0.005


def missed_criteria(summary: dict[str, float | bool]) -> str:
    """The success criteria a finished writing misses ("" if none), e.g. for ``failure_reason``.

    ``summary``: ``StrokeMetrics.summary()`` (stroke RMS [m], in-band fraction, contact lost).
    """
    missed = []
    if summary["in_band_frac"] < IN_BAND_MIN_FRAC:
        missed.append(f"force in band {summary['in_band_frac']:.0%} < {IN_BAND_MIN_FRAC:.0%}")
    if summary["stroke_rms_m"] > STROKE_RMS_TOL_M:
        missed.append(f"stroke rms {1e3 * summary['stroke_rms_m']:.1f} mm > "
                      f"{1e3 * STROKE_RMS_TOL_M:.0f} mm")
    if summary["contact_lost"]:
        missed.append("contact lost")
    return "; ".join(missed)
"""Tolerance on the RMS distance of the written trace from the intended strokes [m]."""
CONTACT_MIN_N = 0.2
"""Below this normal force the pen is off the paper [N]."""
CONTACT_GAP_MAX_S = 0.05
"""A contact gap longer than this during a stroke is a loss of contact [s]."""
CMD_ON_SURFACE_M = 0.005
"""Pressing starts when the commanded tip comes within this height of the paper [m]."""
CMD_OFF_SURFACE_M = 0.01
"""Pressing stops when the commanded tip rises above this height (hysteresis: a learned
policy's commanded tip jitters a few mm while writing; strokes are joined 3 cm up) [m]."""
TIP_NEAR_SURFACE_M = 0.03
"""Guard: no force command unless the actual tip is within this height of the paper [m]."""
SAMPLE_TICKS = 10
"""Writing metrics are sampled every 10 control ticks (100 Hz)."""


class CalligraphyTask(Task):
    """Write one randomly chosen, placed and rotated character with a hand-held pen."""

    has_tick_hook = True
    env_id = current_id("Calligraphy")
    env_entry_point = "impact_envs.envs.calligraphy:CalligraphyEnv"
    observations = (
        ObsEntry("object_pos", 3, -2.0, 2.0, "m", "pen-tip point, world frame"),
        ObsEntry("object_rot6d", 6, -1.0, 1.0, "", "pen orientation (z along the pen)"),
        ObsEntry("goal_pos", 3, -2.0, 2.0, "m",
                 "pen-tip reference at the end of the coming policy step"),
    )
    privileged_observations = ("object_pos", "object_rot6d")
    """The pen's pose is hidden in the image modes; ``goal_pos`` stays: it is the command of
    what to write (no camera sees a character before it is written)."""

    name = "calligraphy"
    scene_xml = "calligraphy_scene.xml"
    object_bodies = ("pen",)
    params = (TaskParam("tool_mass", 0.1, 0.02, 5.0, "kg", is_mass=True),
              TaskParam("surface_friction", 0.3, 0.05, 1.5, ""))
    max_episode_steps = 600
    workspace_low = np.array([0.15, -0.45, 0.0])
    workspace_high = np.array([0.70, 0.45, 0.60])

    center_xy_low = np.array([0.38, -0.06])
    center_xy_high = np.array([0.44, 0.06])
    rot_max_rad = np.deg2rad(15.0)
    scale_range = (0.9, 1.1)
    char_names = tuple(CHARACTERS)

    def bind(self, sim: FrankaSim) -> None:
        m = sim.model
        self.mass = BodyMass(m, "pen")
        self.pen = m.body("pen").id
        self.tip_site = m.site("pen_tip").id
        self.tip_geom = m.geom("pen_tip").id
        self.paper_geom = m.geom("paper_geom").id
        joint = m.joint("pen_free").id
        self.qpos_adr = int(m.jnt_qposadr[joint])
        self.dof_adr = int(m.jnt_dofadr[joint])
        self.tool_mass = self.params[0].default
        self.press = NormalForceCommand(FORCE_DESIRED_N)
        self.metrics = WritingMetrics(FORCE_BAND_N, CONTACT_MIN_N, CONTACT_GAP_MAX_S)
        self.char_index, self._tick, self._stroke, self._force_n = 0, 0, -1, 0.0

    def apply_params(self, sim: FrankaSim, values: dict[str, float]) -> None:
        self.tool_mass = values["tool_mass"]
        self.mass.set(sim.model, values["tool_mass"])
        sim.model.geom_friction[self.paper_geom, 0] = values["surface_friction"]

    # ------------------------------------------------------------------ episode
    def initialize_episode(self, sim: FrankaSim, rng: np.random.Generator) -> np.ndarray:
        self.char_index = int(rng.integers(len(self.char_names)))
        center = rng.uniform(self.center_xy_low, self.center_xy_high)
        rot = rng.uniform(-self.rot_max_rad, self.rot_max_rad)
        scale = rng.uniform(*self.scale_range)
        paths = place_strokes(CHARACTERS[self.char_names[self.char_index]], center, rot, scale)
        self.reference: Reference = build_reference(paths, PAPER_TOP_M)
        q0 = HOME_Q + rng.uniform(-0.03, 0.03, size=7)
        self._place_pen_at_tcp(sim, q0)
        self.press.reset()
        self.metrics.reset()
        self._tick, self._stroke, self._force_n = 0, -1, 0.0
        return q0

    def _place_pen_at_tcp(self, sim: FrankaSim, q0: np.ndarray) -> None:
        """Put the pen's free joint where the weld holds it for the arm at ``q0``."""
        m, d = sim.model, sim.data
        d.qpos[sim.arm_qpos] = q0
        mujoco.mj_kinematics(m, d)
        quat = np.zeros(4)
        mujoco.mju_mat2Quat(quat, d.site_xmat[sim.tcp_site])
        d.qpos[self.qpos_adr:self.qpos_adr + 3] = d.site_xpos[sim.tcp_site]
        d.qpos[self.qpos_adr + 3:self.qpos_adr + 7] = quat
        d.qvel[self.dof_adr:self.dof_adr + 6] = 0.0

    # ------------------------------------------------------------------ sensing
    def tip_force_n(self, sim: FrankaSim) -> float:
        """Normal contact force [N] on the pen tip (privileged, for metrics only)."""
        d = sim.data
        n = d.ncon
        if n == 0:
            return 0.0
        geoms = d.contact.geom[:n]
        adr = d.contact.efc_address[:n]
        hit = ((geoms[:, 0] == self.tip_geom) | (geoms[:, 1] == self.tip_geom)) & (adr >= 0)
        return float(d.efc_force[adr[hit]].sum()) if hit.any() else 0.0

    def tip_pos(self, sim: FrankaSim) -> np.ndarray:
        """Pen tip point [m, world] (true pose)."""
        return sim.data.site_xpos[self.tip_site].copy()

    # ------------------------------------------------------------------ hooks
    def before_tick(self, sim: FrankaSim, time_s: float) -> None:
        """Every tick: update the pressing command; at 100 Hz: sample the writing metrics."""
        tip = sim.data.site_xpos[self.tip_site]
        self.press.tick(sim.dt)
        self._tick += 1
        if self._tick % SAMPLE_TICKS:
            return
        _, self._stroke = self.reference.at(time_s)
        if self._stroke < 0:
            self.metrics.end_stroke()
            return
        self._force_n = self.tip_force_n(sim)
        dist = distance_to_path(tip[:2], self.reference.paths[self._stroke])
        self.metrics.add(self._force_n, dist, SAMPLE_TICKS * sim.dt)

    def control_inputs(self, sim: FrankaSim, action: np.ndarray
                       ) -> tuple[np.ndarray | None, np.ndarray | None]:
        """Press (ramped) and freeze normal-axis learning (the controller holds its feedforward).

        On when the commanded tip (action pose + pen offset) comes within ``CMD_ON_SURFACE_M``
        of the paper, and stays on until it rises above ``CMD_OFF_SURFACE_M``; only while the
        actual tip is within ``TIP_NEAR_SURFACE_M`` of the paper. Otherwise pure pose tracking.
        """
        a = np.asarray(action, dtype=float)
        pos = np.clip(a[:3], self.workspace_low, self.workspace_high)
        cmd_tip_z = (pos + matrix_from_rot6d(a[3:9])[:, 2] * PEN_TIP_OFFSET_M)[2]
        tip_z = sim.data.site_xpos[self.tip_site, 2]
        on_paper = CMD_OFF_SURFACE_M if self.press.engaged else CMD_ON_SURFACE_M
        if cmd_tip_z <= PAPER_TOP_M + on_paper and tip_z <= PAPER_TOP_M + TIP_NEAR_SURFACE_M:
            return self.press.engage()
        self.press.release()
        return None, None

    # ------------------------------------------------------------- observation
    def observation(self, sim: FrankaSim) -> dict[str, np.ndarray]:
        goal, _ = self.reference.at(float(sim.data.time) + 1.0 / POLICY_HZ)
        return {
            "object_pos": self.tip_pos(sim),
            "object_rot6d": rot6d_from_matrix(sim.data.xmat[self.pen].reshape(3, 3)),
            "goal_pos": goal,
        }

    def is_success(self, sim: FrankaSim) -> bool:
        if sim.data.time < self.reference.t_end_s or self.metrics.n == 0:
            return False
        return not missed_criteria(self.metrics.summary())

    def dense_reward(self, sim: FrankaSim) -> float:
        """Trace and press, in [0, 1]: 0.5 (1 - tanh(100 |tip - reference|)) for following the
        pen-tip reference (a 1 cm error halves it), plus, while a stroke is being written, 0.5
        when the normal force is in the band (7.5-22.5 N) and 0.5 (1 - tanh(|F - 15 N| / 7.5 N))
        outside it; 1.0 on success."""
        if self.is_success(sim):
            return 1.0
        goal, _ = self.reference.at(float(sim.data.time))
        trace = 0.5 * (1.0 - np.tanh(100.0 * np.linalg.norm(self.tip_pos(sim) - goal)))
        if self._stroke < 0:
            return float(trace)
        force = self._force_n
        press = 0.5 if self.metrics.in_band(force) else 0.5 * (1.0 - np.tanh(
            abs(force - 15.0) / 7.5))
        return float(min(0.99, trace + press))

    def supported_weight_n(self, values: Mapping[str, float]) -> float:
        """0 N: the brush's contact with the paper is what the task asks for, and the
        evaluation counts it in full (writing too hard shows in the contact columns)."""
        return 0.0

    def info(self, sim: FrankaSim) -> dict[str, float | bool | str]:
        force = self._force_n if self._stroke >= 0 else self.tip_force_n(sim)
        done = sim.data.time >= self.reference.t_end_s
        summary = self.metrics.summary()
        return {
            # v1's alias of tool_mass (which info reports under its declared name): no consumer
            # of ours reads it (bins.mass_info_key); kept for v1's users, dropped in v2
            "object_mass": float(self.tool_mass),
            "normal_force_n": float(force),
            "in_band": self.metrics.in_band(force),
            "pressing": self.press.engaged,
            "writing": self._stroke >= 0,
            "character": self.char_names[self.char_index],
            "writing_done": bool(done),
            "failure_reason": missed_criteria(summary) if done else "",
            **summary,
        }
