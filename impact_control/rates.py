"""The two rates of every env: the 1 kHz control tick and the 30 Hz policy step (the one
definition; docs/envs.md)."""

CONTROL_HZ = 1000
"""Controller ticks per second (the FR3's 1 kHz torque interface)."""
POLICY_HZ = 30
"""Policy steps per second (the paper's 30 Hz)."""
