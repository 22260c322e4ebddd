"""IMPACT on a real FR3 through Franka's own client library, pylibfranka (extra ``[franka]``).

``fci.py``: the FCI conventions a runner must own (gravity added by the robot, link-side
``tau_J``, column-major ``O_T_EE``, the configuration meant for an FR3); ``runner.py``: the
1 kHz torque loop and its target sources; ``pick_place.py`` / ``gripper.py`` / ``poses.py``:
the taught pick-and-place task and the Franka Hand beside the loop; ``policy_loop.py``: a
policy at 30 Hz; ``cli.py`` / ``checks.py`` (every argument, before connecting) /
``commands.py`` / ``connection.py`` (the one-client lock, the connection watchdog) /
``session.py``: ``impact-robot``. Proven against
libfranka-protocol simulators on loopback (tests/franka/); docs/franka.md, docs/hardware.md.
"""
