"""IMPACT on a real FR3 through Franka's own client library, pylibfranka (extra ``[franka]``).

``fci.py``: the FCI conventions a runner must own (gravity added by the robot, link-side
``tau_J``, column-major ``O_T_EE``, the configuration meant for an FR3); ``runner.py``: the
1 kHz torque loop; ``cli.py``: ``impact-robot``. Proven against libfranka-protocol simulators
(franky-sim) on loopback (tests/test_franka.py). First slice of issue 27: see docs/franka.md.
"""
