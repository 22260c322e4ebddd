"""franka-sim 1.1.7 on 127.0.0.1:1337 with the real robot's checks on, for tests/franka/.

Run with franka-sim's own python (it pins numpy 1.26 and MuJoCo < 3.3: a virtualenv of its
own, ``IMPACT_FRANKA_SIM_PYTHON``). Its command-line server binds 0.0.0.0; this script binds
loopback only, offline, on this project's FR3 + hand model (``FR3_MJCF``, no gripper
server), with ``enforce_comm_constraints`` and ``enforce_motion_limits`` (missed cycles and
torque-rate or limit violations abort the motion, as on the robot). SIGTERM stops it.

``--gripper``: franka-sim's gripper server on port 1338 as well (the hand's fingers of our
model; no graspable object). ``--no-joint-friction``: the arm's joints without the Coulomb
friction (``frictionloss``) of our model; franka-sim's ``tau_J`` echoes the command, so the
controller cannot tell friction from an external force, which a real FR3's link-side torque
sensors can.
"""

from __future__ import annotations

import os
import signal
import sys
from pathlib import Path

ASSET = Path(__file__).resolve().parents[2] / "impact_control" / "assets" / "fr3_hand.xml"


def main() -> None:
    os.environ.setdefault("FR3_MJCF", str(ASSET))
    from franka_sim.franka_sim_server import FrankaSimServer

    if "--no-joint-friction" in sys.argv[1:]:
        from franka_sim.mujoco_franka_sim import MujocoFrankaSim

        configure = MujocoFrankaSim._configure_model

        def frictionless(self: MujocoFrankaSim) -> None:
            configure(self)
            self.model.dof_frictionloss[self.arm_dofs_idx] = 0.0

        MujocoFrankaSim._configure_model = frictionless

    server = FrankaSimServer(host="127.0.0.1", enable_gripper="--gripper" in sys.argv[1:],
                             enforce_comm_constraints=True, enforce_motion_limits=True)
    signal.signal(signal.SIGTERM, lambda *_: server.stop())
    signal.signal(signal.SIGINT, lambda *_: server.stop())
    server.start()
    sys.exit(0)


if __name__ == "__main__":
    main()
