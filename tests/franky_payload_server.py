"""franky-sim on 127.0.0.1:1337 with an undeclared payload handed over on request.

Run with franky-sim's own python (a virtualenv of its own, ``IMPACT_FRANKY_SIM_PYTHON``):
``python franky_payload_server.py MASS_KG FLAG_FILE``. Once ``FLAG_FILE`` exists, a downward
force of MASS_KG x 9.81 N acts on the hand's centre of mass before every physics step: the
weight of a load the robot was not told about (franky-sim's gravity compensation knows only
the hand). The test creates the file while the controller holds the pose.
"""

from __future__ import annotations

import os
import sys

import franky_sim
import mujoco
from franky_sim.mujoco_simulator import MujocoSimulator


def main() -> None:
    mass_kg, flag = float(sys.argv[1]), sys.argv[2]
    state = {"on": False}
    with MujocoSimulator() as sim:
        sim.add_robot()

        def weight(s: MujocoSimulator) -> None:
            if not state["on"]:
                state["on"] = os.path.exists(flag)
                if not state["on"]:
                    return
            hand = mujoco.mj_name2id(s.model, mujoco.mjtObj.mjOBJ_BODY, "robot0_hand")
            s.data.xfrc_applied[hand, 2] = -mass_kg * 9.81

        sim.register_pre_step_callback(weight)
        with franky_sim.SimulationServer(sim, hostname_candidates=["127.0.0.1"]) as server:
            server.run_forever()


if __name__ == "__main__":
    main()
