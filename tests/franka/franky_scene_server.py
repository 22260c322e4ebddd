"""franky-sim on 127.0.0.1:1337 (robot) and :1338 (Franka Hand) with what a test needs.

Run with franky-sim's own python (a virtualenv of its own, ``IMPACT_FRANKY_SIM_PYTHON``):

    python franky_scene_server.py [--load-kg M] [--push-n FX,FY,FZ] [--flag FILE [--after-s T]]
                                  [--object-kg M --object-log FILE]

- ``--load-kg`` / ``--push-n``: once ``FLAG`` exists (immediately without ``--flag``) and
  ``T`` s of simulated time (1 ms per physics step) have passed since the server first saw
  it, a force acts on the hand's centre of mass before every physics step: the weight of an
  undeclared ``M`` kg load (franky-sim's gravity compensation knows only the hand) plus a
  constant push [N, world]. The tests create the file as the torque loop starts, so the force
  arrives ``T`` s into the hold on the robot's clock, however long the client's imports and
  warm-up took (a wall-clock timer made the onset, and with it the result, depend on the
  host's load).
- ``--no-joint-friction``: the arm's joints without their Coulomb friction (franky-sim's FR3
  model has MuJoCo Menagerie's identified ``frictionloss``, 0.25-1.14 Nm; its ``tau_J`` is the
  applied torque, so static friction enters the estimate, as it does not on a real FR3's
  link-side sensors).
- ``--object-kg``: a pick-and-place scene: a 50 cm table under the reach of the start pose
  and on it a cylinder (radius 2 cm, height 10 cm, ``M`` kg: a dumbbell's handle) at
  ``OBJECT_XY``; its position and the hand's [m, world] are appended to ``--object-log``
  (JSON lines) every 50 physics steps.
"""

from __future__ import annotations

import argparse
import json
import os
import xml.etree.ElementTree as ET

import franky_sim
import mujoco
from franky_sim.mujoco_simulator import MujocoSimulator

TABLE_TOP_Z = 0.30
"""Table height [m]: the object's centre is 5 cm above it."""
OBJECT_XY = (0.55, -0.15)
"""Where the object stands [m, world]; the start TCP is at (0.554, 0, 0.521)."""


def _vector(text: str) -> list[float]:
    return [float(v) for v in text.split(",")]


def _add_pick_place_scene(sim: MujocoSimulator, object_kg: float) -> None:
    world = sim.worldbody
    ET.SubElement(world, "geom", name="table", type="box", pos=f"0.55 0 {TABLE_TOP_Z / 2}",
                  size=f"0.12 0.3 {TABLE_TOP_Z / 2}", rgba="0.6 0.5 0.4 1")
    body = ET.SubElement(world, "body", name="object",
                         pos=f"{OBJECT_XY[0]} {OBJECT_XY[1]} {TABLE_TOP_Z + 0.05}")
    ET.SubElement(body, "freejoint", name="object_free")
    ET.SubElement(body, "geom", name="object_geom", type="cylinder", size="0.02 0.05",
                  mass=str(object_kg), friction="1.5 0.05 0.0001", condim="4",
                  rgba="0.2 0.2 0.8 1")
    option = sim.scene.find("option")
    if option is None:
        option = ET.SubElement(sim.scene, "option")
    option.set("noslip_iterations", "3")  # no creep of the object through the fingers


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--load-kg", type=float, default=0.0)
    parser.add_argument("--push-n", type=_vector, default=[0.0, 0.0, 0.0])
    parser.add_argument("--flag", default=None)
    parser.add_argument("--after-s", type=float, default=0.0)
    parser.add_argument("--object-kg", type=float, default=None)
    parser.add_argument("--object-log", default=None)
    parser.add_argument("--no-joint-friction", action="store_true")
    args = parser.parse_args()
    force = [args.push_n[0], args.push_n[1], args.push_n[2] - 9.81 * args.load_kg]
    state = {"on": args.flag is None, "steps": 0, "flag_steps": 0}
    with MujocoSimulator() as sim:
        sim.add_robot()
        if args.object_kg is not None:
            _add_pick_place_scene(sim, args.object_kg)

        def pre_step(s: MujocoSimulator) -> None:
            if args.no_joint_friction and not state.get("frictionless"):
                for j in range(1, 8):
                    joint = s.model.joint(f"robot0_fr3_joint{j}")
                    s.model.dof_frictionloss[joint.dofadr[0]] = 0.0
                state["frictionless"] = True
            if not state["on"]:
                if state["flag_steps"] or os.path.exists(args.flag):
                    state["flag_steps"] += 1  # physics steps (1 ms each) since the flag
                state["on"] = state["flag_steps"] > 1000.0 * args.after_s
                if not state["on"]:
                    return
            hand = mujoco.mj_name2id(s.model, mujoco.mjtObj.mjOBJ_BODY, "robot0_hand")
            s.data.xfrc_applied[hand, :3] = force

        def post_step(s: MujocoSimulator) -> None:
            state["steps"] += 1
            if args.object_log is None or state["steps"] % 50:
                return
            obj = mujoco.mj_name2id(s.model, mujoco.mjtObj.mjOBJ_BODY, "object")
            hand = mujoco.mj_name2id(s.model, mujoco.mjtObj.mjOBJ_BODY, "robot0_hand")
            with open(args.object_log, "a") as f:
                f.write(json.dumps({"step": state["steps"], "pos_m": s.data.xpos[obj].tolist(),
                                    "hand_m": s.data.xpos[hand].tolist()}) + "\n")

        sim.register_pre_step_callback(pre_step)
        sim.register_post_step_callback(post_step)
        with franky_sim.SimulationServer(sim, hostname_candidates=["127.0.0.1"]) as server:
            server.run_forever()


if __name__ == "__main__":
    main()
