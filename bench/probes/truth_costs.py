"""Does the cost tell the truth from the fit's answer? Both scored on the fit's own views.

A fit's error has two possible sources: its cost cannot tell a body nearer the truth from
its answer (the photos do not hold the difference), or its search stops short of a
cheaper body nearer the truth. Scoring the truth's closest body of the fit's space on the
fit's views decides between them: cheaper than the answer, the search is short of it.

The views are rebuilt from the fit's run.json as :func:`~bodyfit.fitter.fit.person_fit.fit_person`
builds them (the same photos, camera, settings), over the refinement's components (the
search's when the run had no refinement), the cameras placed from the fit's answer as the
fit places them. The truth's closest body (:func:`~bodyfit.fitter.model.body_model.project_shape`:
least squares over its vertices and joints; its first beta solved to the stature as every
candidate's is) cannot take the truth's photo pose exactly (the out-of-space bodies bend
their limbs besides), so its four angles are searched with CMA-ES from the fit's angles
(``POSE_POPULATION`` x ``POSE_GENERATIONS``): the truth's cost is an upper bound of the
best its shape allows.
"""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import cma
import numpy as np

from bodyfit.fitter.fit.canvas import extreme_bodies
from bodyfit.fitter.fit.person import person_silhouettes
from bodyfit.fitter.fit.person_fit import person_views, place_cameras, refinement_scoring
from bodyfit.fitter.model.body_model import PART_NAMES, POSE_NAMES, BodyModel, project_shape
from bodyfit.fitter.run.config import run_config

__all__ = ["CostComparison", "POSE_POPULATION", "POSE_GENERATIONS", "POSE_SIGMA0_DEG",
           "compare_costs"]

#: The truth's angles search: CMA-ES population, generations, initial step (degrees).
POSE_POPULATION, POSE_GENERATIONS, POSE_SIGMA0_DEG = 20, 25, 2.0


@dataclasses.dataclass(frozen=True)
class CostComparison:
    """One subject's costs on the fit's views (the kernels' weighted millimetres).

    Attributes:
        fit: the fit's answer's; answers: (n,) each answer it averaged (empty: none).
        truth: the truth's closest body's, its angles searched.
        fit_parts, truth_parts: (10,) the two's part costs, ``PART_NAMES`` order.
    """

    fit: float
    answers: np.ndarray
    truth: float
    fit_parts: np.ndarray
    truth_parts: np.ndarray


def _genes(answer: dict) -> tuple[np.ndarray, np.ndarray]:
    """(betas (K,), pose (4,) degrees) of a run.json answer record."""
    return (np.asarray(answer["betas"], np.float64),
            np.array([answer["pose_deg"][name] for name in POSE_NAMES], np.float64))


def compare_costs(model: BodyModel, run_json: Path, vertices: np.ndarray,
                  joints: np.ndarray, seed: int = 1) -> CostComparison:
    """The fit of ``run_json`` against the truth (rest ``vertices`` (V, 3), ``joints``
    (4, 3), metres) on the fit's views (see the module docstring)."""
    record = json.loads(Path(run_json).read_text())
    config = run_config(record, str(run_json))
    settings, inputs, result = config.settings, config.inputs, record["result"]
    photos = person_silhouettes(inputs, settings.projection)
    masks, intrinsics = photos.masks, photos.intrinsics
    stature_m = inputs.height_cm / 100.0
    s = settings.search
    if not s.refine_components:  # score in the search's own space
        s = dataclasses.replace(s, refine_components=s.components, refinements=1)
        settings = dataclasses.replace(settings, search=s)
    bodies = extreme_bodies(model, s.components, s.pose_lower_deg, s.pose_upper_deg,
                            s.beta_limit)
    views = person_views(model, masks, stature_m, settings, intrinsics, bodies)
    evaluator, conditioner = refinement_scoring(model, views, stature_m, settings)
    fit_betas, fit_pose = _genes(result)
    if settings.projection == "pinhole":
        place_cameras(model, views, masks, intrinsics, stature_m, evaluator, settings,
                      fit_betas, fit_pose)
    shape = project_shape(model, vertices[None], joints[None], s.refine_components)[0]

    def shaped(poses: np.ndarray) -> np.ndarray:
        betas = np.repeat(shape[None], len(poses), axis=0)
        if conditioner is None:
            return betas
        return conditioner.complete(betas[:, 1:], poses)

    angles = cma.CMAEvolutionStrategy(fit_pose, POSE_SIGMA0_DEG,
                                      {"popsize": POSE_POPULATION, "maxiter": POSE_GENERATIONS,
                                       "seed": seed, "verbose": -9})
    while not angles.stop():
        poses = np.asarray(angles.ask())
        angles.tell(poses, evaluator.evaluate(shaped(poses), poses).costs.tolist())
    truth_pose = np.asarray(angles.result.xbest, np.float64)[None]
    answers = [_genes(answer) for answer in result.get("averaged", [])]
    scored = evaluator.evaluate(
        np.stack([fit_betas, shaped(truth_pose)[0]] + [b for b, _ in answers]),
        np.stack([fit_pose, truth_pose[0]] + [p for _, p in answers]))
    costs, parts = scored.costs.astype(np.float64), scored.part_costs.astype(np.float64)
    parts = parts[:, :len(PART_NAMES)]  # the top and bottom terms are not parts
    return CostComparison(float(costs[0]), costs[2:], float(costs[1]), parts[0], parts[1])
