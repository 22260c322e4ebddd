"""Policies: one small protocol shared by scripted experts, diffusion policies and SB3 policies."""
