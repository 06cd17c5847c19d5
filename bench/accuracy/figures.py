"""The accuracy benchmark's figures: error per generation (the paper's Fig. 12) and fitted
bodies coloured by their distance from the truth (its Figs. 16 and 17).

Both start from a run's run.json files, which record after every generation the betas the
search would have answered with had it stopped there (``best_betas_per_generation``:
CMA-ES's mean, averaged over the searches; the GA's best candidate so far; the best
candidate so far in runs before commit c5ea503), and the set's true bodies.
"""

from __future__ import annotations

import json
from pathlib import Path

import cv2
import numpy as np

from bench.accuracy.bodies import Bodies
from bench.accuracy.fit_photos import FitPhotos, answer_pose
from bench.accuracy.scores import IMPORTANT_COLUMNS, KEYS
from bench.accuracy.subject_set import subject_ids
from bodyfit.fitter.fit.stature import scaled_to_stature
from bodyfit.fitter.measure.measurements import Measurer
from bodyfit.fitter.model.body_model import BodyModel, rest_shape
from bodyfit.fitter.output.render import render_colours

__all__ = ["errors_per_generation", "distance_panel", "colour_bar", "fitted_rest_body"]


def _answers(run_folder: Path, subject: str,
             generations: list[int] | None = None) -> tuple[dict, np.ndarray]:
    """(the fit's run.json payload, (G, K) the betas answered after each of
    ``generations`` (1-based; None: the last))."""
    record = json.loads((Path(run_folder) / subject / "run.json").read_text())
    betas = np.array(record["result"]["best_betas_per_generation"], np.float32)
    return record, betas[np.minimum(generations or [len(betas)], len(betas)) - 1]


def errors_per_generation(model: BodyModel, bodies: Bodies, set_folder: Path,
                          run_folder: Path, generations: list[int],
                          subjects: set[str]) -> np.ndarray:
    """(S, len(generations), 7) |error| (mm) of the 7 important measurements of the body
    answered after each of ``generations`` (1-based), for the S ``subjects`` (ids whose
    run.json the run has) in the set's order, each measured as the fit measures its
    answer (:class:`.fit_photos.FitPhotos`: the subject's photos in ``set_folder``; the
    answer's angles, which the run records for its end only); ``bodies``: the set's
    (:func:`.subject_set.read_bodies`); the last generation's is the run's own error."""
    measurer = Measurer.from_model(model)
    errors = []
    for index, subject in enumerate(subject_ids(len(bodies.sex), bodies.sex)):
        if subject not in subjects:
            continue
        truth = measurer.measure(bodies.vertices[index])
        record, betas = _answers(run_folder, subject, generations)
        photos = FitPhotos.of(model, set_folder, subject, record)
        rows = []
        for answer in betas:
            measured = photos.measure(model, measurer, answer, answer_pose(record))[1]
            rows.append([abs(measured[KEYS[j]] - truth[KEYS[j]]) for j in IMPORTANT_COLUMNS])
        errors.append(rows)
    return np.array(errors)


def fitted_rest_body(model: BodyModel, run_folder: Path, subject: str) -> np.ndarray:
    """(V, 3) the fitted rest body of ``subject`` (the last generation's best), as the fit
    measures it: stood as tall as the person when the run solved every candidate to the
    stature (``fitter.fit.fit_person``)."""
    record, betas = _answers(run_folder, subject)
    rest = rest_shape(model, betas)[0]
    if record["settings"]["search"]["condition_stature"]:
        rest = scaled_to_stature(rest, record["inputs"]["height_cm"] / 100.0)
    return rest[0]


def distance_panel(model: BodyModel, truth: np.ndarray, fitted: list[np.ndarray],
                   height_px: int = 420, top_mm: float = 20.0) -> np.ndarray:
    """(H, W, 3) BGR: the true rest body in grey, then each fitted body (same topology)
    coloured by each vertex's distance from its true place after the translation that
    aligns the two best (their centroids; 0 to ``top_mm`` mm, the colour map's ends),
    front views at one scale, bottoms level."""
    grey = np.full((len(model.faces), 3), 170.0)
    pictures = [render_colours(truth, model.faces, grey, "front", height_px)]
    for body in fitted:
        body = body - body.mean(axis=0) + truth.mean(axis=0)  # the best translation
        distance_mm = 1000 * np.linalg.norm(body - truth, axis=1)
        level = np.clip(distance_mm[model.faces].mean(axis=1) / top_mm * 255, 0, 255)
        colours = cv2.applyColorMap(level.astype(np.uint8)[:, None], cv2.COLORMAP_JET)[:, 0]
        # the same scale as the truth: the fitted body drawn inside the truth's frame
        scale = np.ptp(body[:, 2]) / np.ptp(truth[:, 2])
        picture = render_colours(body, model.faces, colours, "front",
                                 int(round(20 + (height_px - 20) * scale)))
        pictures.append(picture)
    height = max(p.shape[0] for p in pictures)
    padded = [np.vstack([np.full((height - p.shape[0], p.shape[1], 3), 255, np.uint8), p])
              for p in pictures]
    return np.hstack(padded)


def colour_bar(width_px: int, top_mm: float = 20.0) -> np.ndarray:
    """(40, width_px, 3) BGR: the colour map of :func:`distance_panel` with its scale."""
    ramp = np.linspace(0, 255, width_px - 80).astype(np.uint8)[None].repeat(16, axis=0)
    bar = np.full((40, width_px, 3), 255, np.uint8)
    bar[4:20, 40:width_px - 40] = cv2.applyColorMap(ramp, cv2.COLORMAP_JET)
    for mm, x in ((0, 40), (top_mm / 2, width_px // 2), (top_mm, width_px - 40)):
        cv2.putText(bar, f"{mm:g} mm", (x - 18, 36), cv2.FONT_HERSHEY_SIMPLEX, 0.45, (0, 0, 0),
                    1, cv2.LINE_AA)
    return bar
