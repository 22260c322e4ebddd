"""Gymnasium environments (registered on ``import impact_envs``)."""
