"""The scripted expert of ``IMPACT/HammerBasket-v0``, as the paper authors' demonstrator:
grasp the hammer at its body origin, carry it over the basket, release.

Their demonstrator adds a privileged ``m g / K`` height offset after the grasp under
impedance (../shared/reference/authors_impact.md): ``compensation="privileged"`` here.
It keeps the home orientation, so its fingers close 6.9 deg off square to the handle; ours
turn with the handle (``grasp_yaw_obj_rad``): with our finger model the skewed 200 N squeeze
pops the handle out of a quarter of the grasps (docs/hammer_basket.md,
``python -m impact_eval.experiments.hammer_basket_grasp``).
"""

from __future__ import annotations

from impact_envs.policies.scripted import PickPlaceExpert, PickPlaceSpec


def hammer_basket_expert(compensation: str = "none",
                         grasp_yaw_obj_rad: float | None = None) -> PickPlaceExpert:
    """The pick-and-place expert of ``IMPACT/HammerBasket-v0``: grasp point the hammer's body
    origin (the scene's centre of mass less its offset), released over the basket centre."""
    from impact_envs.tasks.hammer_basket import (
        GRASP_OFFSET_FROM_COM_M,
        HANDLE_YAW_RAD,
        TABLE_TOP_M,
    )

    spec = PickPlaceSpec(
        grasp_offset_obj=GRASP_OFFSET_FROM_COM_M,
        grasp_z=TABLE_TOP_M + 0.027,  # the handle's centre at the origin, pads 12 mm clear
        hover_z=TABLE_TOP_M + 0.12,
        carry_z=TABLE_TOP_M + 0.18,
        place_z=TABLE_TOP_M + 0.07,
        place_offset_goal=0.0,  # their test reads the body origin: put it over the centre
        grasp_yaw_obj_rad=HANDLE_YAW_RAD if grasp_yaw_obj_rad is None else grasp_yaw_obj_rad,
    )
    return PickPlaceExpert(spec, compensation=compensation)
