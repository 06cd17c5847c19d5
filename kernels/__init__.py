"""Warp kernels: skin, project, rasterise and score whole populations of bodies.

The entry point for a fitter (one person, many generations)::

    from bodyfit import kernels

    model = kernels.ModelArrays.from_body_model(body_model, num_betas=20, device="cpu")
    front = kernels.prepare_view_target("front", front_mask, front_camera, mm_per_px)
    side = kernels.prepare_view_target("side", side_mask, side_camera, mm_per_px,
                                       visible_parts=kernels.SIDE_VIEW_PARTS)
    evaluator = kernels.PopulationEvaluator(model, [front, side], kernels.CostSettings())
    costs, part_costs = evaluator.evaluate(betas, pose_deg)   # (P,), (P, 11)

Importing this package does not initialise Warp; the first kernel launch does.
"""

from bodyfit.kernels.camera import (FRONT_VIEW_DEG, SIDE_VIEW_DEG, Camera, orthographic_camera,
                                    pinhole_camera)
from bodyfit.kernels.cost import MATCHING_DIRECTIONS, TERM_NAMES, CostSettings
from bodyfit.kernels.population import PopulationCost, PopulationEvaluator, evaluate_population
from bodyfit.kernels.raster import rasterize
from bodyfit.kernels.skinning import ModelArrays, skin
from bodyfit.kernels.target import SIDE_VIEW_PARTS, ViewTarget, prepare_view_target

__all__ = [
    "Camera",
    "FRONT_VIEW_DEG",
    "SIDE_VIEW_DEG",
    "orthographic_camera",
    "pinhole_camera",
    "CostSettings",
    "MATCHING_DIRECTIONS",
    "TERM_NAMES",
    "ModelArrays",
    "skin",
    "rasterize",
    "ViewTarget",
    "SIDE_VIEW_PARTS",
    "prepare_view_target",
    "PopulationCost",
    "PopulationEvaluator",
    "evaluate_population",
]
