"""How the cameras' pitch search was chosen (docs/accuracy.md, "People as they stand").

For each subject of a standing set, the local solver's level answer (`--pitch level`) and
eight more solves from it, each camera level or pitched ``PITCH_STEP_DEG`` down or up
(the 3 x 3 grid, ``PITCH_ITERATIONS`` each, as the fit's search solves them), each
measured against the truth. Then rules choosing among them, each paired against level:
the whole grid's best score, the side or the front camera's pitch alone, the
default's (:func:`bodyfit.fitter.fit.pitch.searched_pitches`: each camera its best
single-view step, the two together), each scored by cost + a prior per squared degree,
and the least of a quadratic surface fitted to the grid's scores
(:func:`quadratic_pitches`; its errors interpolated over the grid, not solved).

    PYTHONPATH=. python -m bench.probes.pitch_grid SETS/standing --first 72 > grid.jsonl
    PYTHONPATH=. python -m bench.probes.pitch_grid --rules grid.jsonl

Errors in mm, the 7 important measurements' mean abs.; pitch in degrees, positive down.
"""

from __future__ import annotations

import argparse
import csv
import dataclasses
import json
import sys
from pathlib import Path

import numpy as np
from threadpoolctl import threadpool_limits

from bodyfit.fitter.fit import person_fit
from bodyfit.fitter.fit.canvas import extreme_bodies
from bodyfit.fitter.fit.person import PersonInputs, person_silhouettes
from bodyfit.fitter.fit.pitch import PITCH_ITERATIONS, PITCH_STEP_DEG, searched_pitches
from bodyfit.fitter.measure.measurements import IMPORTANT, Measurer
from bodyfit.fitter.model.cache import load_model

STEPS = (-PITCH_STEP_DEG, 0.0, PITCH_STEP_DEG)
PRIORS = (0.0, 0.1, 0.2, 0.3, 0.5)


def subject_grid(model, measurer, set_folder: Path, row: dict) -> dict:
    """One subject's record: its true pitches and, per grid point, the answer's cost and
    its errors (mm) by measurement letter."""
    settings = dataclasses.replace(person_fit.METHODS["bodyfit"], threads=1)
    settings = dataclasses.replace(settings, solver=dataclasses.replace(settings.solver,
                                                                        pitch="level"))
    short = dataclasses.replace(settings, solver=dataclasses.replace(
        settings.solver, iterations=PITCH_ITERATIONS))
    truth = json.loads((set_folder / row["id"] / "truth.json").read_text())
    shots = truth["standing"]["shots"]
    inputs = PersonInputs(str(set_folder / row["front"]), str(set_folder / row["side"]),
                          float(row["height_cm"]),
                          str(set_folder / row["camera"]) if row["camera"] else None,
                          sex=row["sex"])
    photos = person_silhouettes(inputs, settings.projection)
    masks, intrinsics, stature = photos.masks, photos.intrinsics, inputs.height_cm / 100
    s = settings.search
    bodies = extreme_bodies(model, person_fit._canvas_components(settings), s.pose_lower_deg,
                            s.pose_upper_deg, s.beta_limit)
    views = person_fit.person_views(model, masks, stature, settings, intrinsics, bodies)
    level = person_fit._solved(model, views, masks, intrinsics, stature, inputs.sex,
                               settings, None, bodies)

    def errors(result, solved_views) -> dict:
        _, rest, view_bodies = person_fit.fitted_bodies(
            model, result.betas, result.pose_deg, solved_views, stature, True,
            result.elbow_deg, result.hand_twist_deg)
        fitted = person_fit.fitted_measurements(model, measurer, settings, rest, view_bodies,
                                                solved_views, masks, intrinsics)
        return {k: float(fitted[k] - truth["measurements"][k]) for k in fitted}

    grid = [{"front": 0.0, "side": 0.0, "cost": level.cost, "err": errors(level, views)}]
    for front in STEPS:
        for side in STEPS:
            if front or side:
                tried = dict(views)
                result = person_fit._solved(model, tried, masks, intrinsics, stature,
                                            inputs.sex, short, None, bodies, level,
                                            {"front": front, "side": side})
                grid.append({"front": front, "side": side, "cost": result.cost,
                             "err": errors(result, tried)})
    return {"id": row["id"], "true_front": shots["front"]["pitch_deg"],
            "true_side": shots["side"]["pitch_deg"], "grid": grid}


def _important(point: dict) -> float:
    return float(np.mean([abs(point["err"][k]) for k in IMPORTANT]))


def _chosen(record: dict, rule: str, prior: float) -> dict:
    """The grid point ``rule`` chooses by cost + prior * (sum of squared pitches): the
    default's (:func:`searched_pitches` over the grid's solves), the best of the whole
    grid, of the side camera's pitches alone or of the front camera's; or, for
    ``"quadratic"``, the point :func:`quadratic_pitches` interpolates."""
    points = {(p["front"], p["side"]): p for p in record["grid"]}
    if rule == "quadratic":
        return _interpolated(record, *quadratic_pitches(record, prior))
    if rule == "default":
        def solved(pitches, start):
            point = points[(pitches["front"], pitches["side"])]
            return point["cost"], point
        return searched_pitches(solved, (points[(0.0, 0.0)]["cost"], points[(0.0, 0.0)]),
                                prior=prior)[0]
    score = {key: p["cost"] + prior * (key[0] ** 2 + key[1] ** 2) for key, p in points.items()}
    keys = [key for key in points if rule == "grid" or
            (rule == "side" and key[0] == 0.0) or (rule == "front" and key[1] == 0.0)]
    return points[min(keys, key=score.get)]


def _quadratic_weights(front: float, side: float) -> np.ndarray:
    """(9,) weights of the grid points (``STEPS`` x ``STEPS``, front-major) whose sum
    interpolates a value at the pitches (``front``, ``side``): Lagrange's quadratic in
    each view's pitch."""
    def lagrange(x: float) -> np.ndarray:
        return np.array([np.prod([(x - o) / (s - o) for o in STEPS if o != s]) for s in STEPS])
    return np.outer(lagrange(front), lagrange(side)).ravel()


def quadratic_pitches(record: dict, prior: float) -> tuple[float, float]:
    """(front, side) degrees: the least of the quadratic surface fitted (least squares) to
    the grid's scores (cost + prior * squared pitches), within one step of level; the
    grid's best point where the surface has no least point."""
    x = np.array([p["front"] for p in record["grid"]]) / PITCH_STEP_DEG
    y = np.array([p["side"] for p in record["grid"]]) / PITCH_STEP_DEG
    score = np.array([p["cost"] + prior * (p["front"] ** 2 + p["side"] ** 2)
                      for p in record["grid"]])
    a = np.column_stack([np.ones_like(x), x, y, x * x, x * y, y * y])
    c = np.linalg.lstsq(a, score, rcond=None)[0]
    hessian = np.array([[2 * c[3], c[4]], [c[4], 2 * c[5]]])
    if np.all(np.linalg.eigvalsh(hessian) > 0):
        least = np.clip(np.linalg.solve(hessian, -c[1:3]), -1.0, 1.0)
    else:
        best = int(np.argmin(score))
        least = np.array([x[best], y[best]])
    return float(least[0] * PITCH_STEP_DEG), float(least[1] * PITCH_STEP_DEG)


def _interpolated(record: dict, front: float, side: float) -> dict:
    """A grid point at the pitches (``front``, ``side``): its errors interpolated over the
    grid (:func:`_quadratic_weights`), as an approximation of a solve there."""
    points = {(p["front"], p["side"]): p for p in record["grid"]}
    ordered = [points[(f, s)] for f in STEPS for s in STEPS]
    weights = _quadratic_weights(front, side)
    return {"front": front, "side": side,
            "err": {k: float(weights @ [p["err"][k] for p in ordered])
                    for k in ordered[0]["err"]}}


def rules_table(records: list[dict]) -> str:
    """Markdown: each rule and prior's mean of the 7, paired against level."""
    level = np.array([_important(r["grid"][0]) for r in records])
    lines = [f"{len(records)} subjects, level {level.mean():.2f} mm", "",
             "| rule | " + " | ".join(f"prior {p}" for p in PRIORS) + " |",
             "|---|" + "---|" * len(PRIORS)]
    for rule in ("default", "grid", "side", "front", "quadratic"):
        cells = []
        for prior in PRIORS:
            diff = np.array([_important(_chosen(r, rule, prior)) for r in records]) - level
            half = 1.96 * diff.std(ddof=1) / np.sqrt(len(diff))
            cells.append(f"{level.mean() + diff.mean():.2f} ({diff.mean():+.2f} ± {half:.2f})")
        lines.append(f"| {rule} | " + " | ".join(cells) + " |")
    nearest = [min(r["grid"], key=lambda p: (p["front"] - r["true_front"]) ** 2
                   + (p["side"] - r["true_side"]) ** 2) for r in records]
    lines += ["", f"the grid point nearest the true pitches: "
                  f"{np.mean([_important(p) for p in nearest]):.2f} mm"]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("source", type=Path, help="a standing set's folder, or with "
                                                  "--rules the records it wrote")
    parser.add_argument("--first", type=int, default=72)
    parser.add_argument("--rules", action="store_true",
                        help="read the records (JSON lines) and print the rules' table")
    args = parser.parse_args(argv)
    if args.rules:
        records = [json.loads(line) for line in args.source.read_text().splitlines()
                   if line.startswith("{")]  # not Warp's start-up lines
        print(rules_table(records))
        return
    threadpool_limits(1)
    model = load_model()
    measurer = Measurer.from_model(model)
    with open(args.source / "subjects.csv", newline="") as table:
        rows = list(csv.DictReader(table))[:args.first]
    for row in rows:
        print(json.dumps(subject_grid(model, measurer, args.source, row)), flush=True)


if __name__ == "__main__":
    sys.exit(main())
