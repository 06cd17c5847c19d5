"""Ablations of the population search's choices (`--method thorough`, the default before
the local solver): each row changes one choice, same subjects, seeds.

    python -m bench.choices                       # 4 subjects, CMA-ES 30 x 150
    python -m bench.choices --subjects 6 --generations 200

In-space subjects as bench/subjects.py draws them (studio photos, the side with the
arms down), fitted through `fitter run`'s own path (calib's silhouettes, then
``fit_person``). Besides the measurement errors it reports the cost of the found body and
of the true one (its betas and front pose; with the stature conditioned, the true body as
the conditioning makes it: the same shape stood as tall as the stature) on the same
canvases: a found cost below the truth's means the cost's minimum is not at the truth (a
bias of the cost or the photos); above it, that the search stopped short. The last
column is how often the truth lies within the reported +- spread. Prints Markdown.
"""

from __future__ import annotations

import argparse
import dataclasses
import tempfile
import time
from pathlib import Path

import numpy as np
import warp

from bench.subjects import draw_subject
from bodyfit import kernels
from bodyfit.fitter.demo.studio_photos import write_subject
from bodyfit.fitter.fit.canvas import extreme_bodies
from bodyfit.fitter.fit.person import PersonInputs, person_masks
from bodyfit.fitter.fit.person_fit import METHODS, FitSettings, fit_person, stature_conditioner
from bodyfit.fitter.fit.weights import cost_settings
from bodyfit.fitter.measure.measurements import IMPORTANT, MEASUREMENTS
from bodyfit.fitter.model.cache import load_model


def _variants(base: FitSettings) -> dict[str, FitSettings]:
    """Row name -> settings: the defaults, then one choice changed per row."""
    replace = dataclasses.replace
    return {
        "defaults": base,
        "vertical anchor on the centroid": replace(
            base, cost=replace(base.cost, vertical_anchor="centroid")),
        "person -> model matching": replace(
            base, cost=replace(base.cost, matching="person_to_model")),
        "paper weights (top, bottom 5)": replace(
            base, cost=cost_settings("paper", (), base.cost)),
        "stature searched": replace(
            base, search=replace(base.search, condition_stature=False)),
        "CMA-ES initial step 0.25 (before)": replace(
            base, search=replace(base.search, sigma0=0.25)),
        "CMA-ES initial step 0.15": replace(base, search=replace(base.search, sigma0=0.15)),
        "full render mesh (no clustering)": replace(base, render_cell_mm=0.0),
    }


def _true_cost(model, fit, settings: FitSettings, betas, pose, stature_m) -> float:
    s = settings.search
    bodies = extreme_bodies(model, s.components, s.pose_lower_deg, s.pose_upper_deg,
                            s.beta_limit)
    conditioner = stature_conditioner(model, settings, stature_m, bodies)
    if conditioner is not None:
        betas = conditioner.complete(betas[None, 1:], pose[None])[0]
    arrays = kernels.ModelArrays.from_body_model(model, s.components)
    evaluator = kernels.PopulationEvaluator(arrays, list(fit.views.values()), settings.cost)
    return float(evaluator.evaluate(betas[None], pose[None]).costs[0])


def main() -> None:
    warp.config.log_level = warp.LOG_WARNING  # no initialisation banner in the Markdown
    parser = argparse.ArgumentParser(prog="python -m bench.choices",
                                     description=__doc__.splitlines()[0])
    parser.add_argument("--subjects", type=int, default=4)
    parser.add_argument("--seed", type=int, default=7)
    parser.add_argument("--generations", type=int, default=150)
    args = parser.parse_args()
    model = load_model()
    base = METHODS["thorough"]
    base = dataclasses.replace(base, projection="orthographic", search=dataclasses.replace(
        base.search, generations=args.generations))  # the studio photos are orthographic
    variants = _variants(base)
    rng = np.random.default_rng(args.seed)
    rows = {name: {"err": [], "spread": [], "found": [], "true": [], "s": []}
            for name in variants}
    keys = list(MEASUREMENTS)
    with tempfile.TemporaryDirectory() as scratch:
        for i in range(args.subjects):
            folder = Path(scratch) / f"s{i}"
            folder.mkdir()
            betas, pose = draw_subject(rng)
            truth = write_subject(folder, model, betas, pose)
            stature_m = truth["O"] / 1000
            masks = person_masks(PersonInputs(str(folder / "front.png"),
                                              str(folder / "side.png"), truth["O"] / 10))
            for name, settings in variants.items():
                start = time.perf_counter()
                fit = fit_person(model, masks, stature_m, settings, progress=False)
                rows[name]["s"].append(time.perf_counter() - start)
                rows[name]["err"].append([fit.measurements[k] - truth[k] for k in keys])
                rows[name]["spread"].append([fit.spreads[k] for k in keys])
                rows[name]["found"].append(fit.search.cost)
                rows[name]["true"].append(_true_cost(model, fit, settings, betas, pose,
                                                     stature_m))
    important = [keys.index(k) for k in IMPORTANT]
    print(f"`python -m bench.choices --subjects {args.subjects} --seed {args.seed} "
          f"--generations {args.generations}` on {time.strftime('%Y-%m-%d')}: CMA-ES "
          f"{base.search.population} x {args.generations}, search seed 0, on the CPU.\n")
    print("| choice | fit s (mean) | found cost | true body's cost | 7 important, mean abs. "
          "error (mm) | their mean signed error (mm) | truth within +- spread (16) |")
    print("|---|---|---|---|---|---|---|")
    for name, row in rows.items():
        err = np.array(row["err"])
        inside = np.abs(err) <= np.array(row["spread"])
        err = err[:, important]
        print(f"| {name} | {np.mean(row['s']):.1f} | {np.mean(row['found']):.1f} | "
              f"{np.mean(row['true']):.1f} | {np.abs(err).mean():.1f} | {err.mean():+.1f} | "
              f"{inside.mean():.0%} |")


if __name__ == "__main__":
    main()
