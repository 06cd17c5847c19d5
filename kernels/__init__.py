"""Warp kernels: skin, project, rasterise and score whole populations of bodies.

The entry point for a fitter (one person, many generations)::

    from bodyfit import kernels

    model = kernels.ModelArrays.from_body_model(body_model, num_components=20, device="cpu")
    front = kernels.prepare_view_target("front", front_mask, front_camera, mm_per_px)
    side = kernels.prepare_view_target("side", side_mask, side_camera, mm_per_px,
                                       visible_parts=kernels.SIDE_VIEW_PARTS)
    evaluator = kernels.PopulationEvaluator(model, [front, side], kernels.CostSettings())
    costs, part_costs = evaluator.evaluate(betas, pose_deg)   # (P,), (P, 12)

Importing this package imports none of its modules (each name below is loaded on first
use) and does not initialise Warp; the first kernel launch does. So the body model can
take its part and pose names from :mod:`bodyfit.kernels.body_layout` without loading Warp.

This package is the bottom layer: it imports no other bodyfit package, takes arrays (and
a duck-typed body model, :class:`bodyfit.kernels.skinning.SkinnableModel`) from its
caller, and raises ValueError for bad arguments and unavailable devices.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING

#: Public name -> the module of this package that defines it.
_EXPORTS = {
    "PART_NAMES": "body_layout",
    "POSE_NAMES": "body_layout",
    "ViewCamera": "view_camera",
    "FRONT_VIEW_DEG": "view_camera",
    "SIDE_VIEW_DEG": "view_camera",
    "orthographic_camera": "view_camera",
    "pinhole_camera": "view_camera",
    "CostSettings": "cost",
    "MATCHING_DIRECTIONS": "cost",
    "TERM_NAMES": "cost",
    "ModelArrays": "skinning",
    "SkinnableModel": "skinning",
    "skin": "skinning",
    "rasterize": "raster",
    "ViewTarget": "target",
    "SIDE_VIEW_PARTS": "target",
    "prepare_view_target": "target",
    "PopulationCost": "evaluator",
    "PopulationEvaluator": "evaluator",
    "evaluate_population": "evaluator",
    "cpu_threads": "evaluator",
}

__all__ = list(_EXPORTS)

if TYPE_CHECKING:
    from bodyfit.kernels.body_layout import PART_NAMES, POSE_NAMES
    from bodyfit.kernels.cost import MATCHING_DIRECTIONS, TERM_NAMES, CostSettings
    from bodyfit.kernels.evaluator import (PopulationCost, PopulationEvaluator, cpu_threads,
                                            evaluate_population)
    from bodyfit.kernels.raster import rasterize
    from bodyfit.kernels.skinning import ModelArrays, SkinnableModel, skin
    from bodyfit.kernels.target import SIDE_VIEW_PARTS, ViewTarget, prepare_view_target
    from bodyfit.kernels.view_camera import (FRONT_VIEW_DEG, SIDE_VIEW_DEG, ViewCamera,
                                             orthographic_camera, pinhole_camera)


def __getattr__(name: str):
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(f"{__name__}.{module}"), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
