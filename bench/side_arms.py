"""Benchmark of the side photo's arms: chest, waist and hip bias of `fitter run`'s fit.

    python -m bench.side_arms                    # 4 subjects, CMA-ES 30 x 100
    python -m bench.side_arms --subjects 3 --population 24 --generations 60

In-space subjects as bench/subjects.py draws them (betas normal clipped at +-2 sigma, limbs
2-8 degrees out, the same draws for the same --seed), photographed by
:mod:`bodyfit.fitter.demo.studio_photos` twice: the side photo with the arms hidden and with
the arms hanging down (the front photo is the same A-pose). Each photo pair is fitted by
`fitter run`'s own path (calib's silhouettes of the photos, then
:func:`bodyfit.fitter.fit.person_fit.fit_person`) with the same search and seed, once per row:

- side photo arms hidden, fit ``--side-arms hidden``: no arms anywhere in the side view
  (also the best that leaving the person's arm pixels out of the side mask could do);
- side photo arms down, fit ``--side-arms hidden``: the candidates without arms, the
  person with them;
- side photo arms down, fit ``--side-arms down``: the candidates' arms hang down too.

Error: fitted - true, mm, of chest (D), waist (E) and hip (F) circumferences; "bias" is the
signed mean over the subjects. Prints Markdown (docs/fitter.md holds the output).
"""

from __future__ import annotations

import argparse
import os
import platform
import tempfile
import time
from pathlib import Path

import numpy as np
import warp

from bench.subjects import draw_subject
from bodyfit.fitter.demo.studio_photos import write_subject
from bodyfit.fitter.fit.local_solver import SolverSettings
from bodyfit.fitter.fit.person import PersonInputs
from bodyfit.fitter.fit.person_fit import FitSettings, fit_inputs
from bodyfit.fitter.fit.search import SearchSettings
from bodyfit.fitter.measure.measurements import IMPORTANT
from bodyfit.fitter.model.cache import load_model

#: row name -> (side photo's arms, fit's --side-arms)
ROWS = {
    "arms hidden in the photo, fit hidden": ("hidden", "hidden"),
    "arms down in the photo, fit hidden (before)": ("down", "hidden"),
    "arms down in the photo, fit down (default)": ("down", "down"),
}
KEYS = ("D", "E", "F")


def main() -> None:
    warp.config.log_level = warp.LOG_WARNING  # no initialisation banner in the Markdown
    parser = argparse.ArgumentParser(prog="python -m bench.side_arms",
                                     description=__doc__.splitlines()[0])
    parser.add_argument("--subjects", type=int, default=4)
    parser.add_argument("--seed", type=int, default=7, help="subjects' seed")
    parser.add_argument("--population", type=int, default=30)
    parser.add_argument("--generations", type=int, default=150)
    parser.add_argument("--search-seed", type=int, default=0)
    args = parser.parse_args()
    model = load_model()
    search = SearchSettings(optimizer="cmaes", population=args.population,
                            generations=args.generations, seed=args.search_seed)
    rng = np.random.default_rng(args.seed)
    subjects = [draw_subject(rng) for _ in range(args.subjects)]
    errors = {name: [] for name in ROWS}
    seconds = {name: [] for name in ROWS}
    with tempfile.TemporaryDirectory() as scratch:
        for i, (betas, pose) in enumerate(subjects):
            for name, (photo_arms, fit_arms) in ROWS.items():
                folder = Path(scratch) / f"s{i}_{photo_arms}"
                folder.mkdir(exist_ok=True)
                truth = write_subject(folder, model, betas, pose, side_arms=photo_arms)
                inputs = PersonInputs(str(folder / "front.png"), str(folder / "side.png"),
                                      truth["O"] / 10)
                start = time.perf_counter()
                settings = FitSettings(search=search, solver=SolverSettings(),  # the search
                                       side_arms=fit_arms, projection="orthographic")
                fit = fit_inputs(model, inputs, settings, progress=False)
                seconds[name].append(time.perf_counter() - start)
                errors[name].append({k: fit.measurements[k] - truth[k] for k in truth})
    print(f"`python -m bench.side_arms --subjects {args.subjects} --seed {args.seed} "
          f"--population {args.population} --generations {args.generations} --search-seed "
          f"{args.search_seed}` on {time.strftime('%Y-%m-%d')}: {platform.machine()}, "
          f"{os.cpu_count()} logical CPUs, CMA-ES, search seed {args.search_seed}, on the CPU.\n")
    print("| side photo / fit | fit s (mean) | D bias | E bias | F bias | D, E, F mean abs. error "
          "| 7 important, mean abs. error |")
    print("|---|---|---|---|---|---|---|")
    for name in ROWS:
        err = errors[name]
        bias = [np.mean([e[k] for e in err]) for k in KEYS]
        abs_def = np.mean([abs(e[k]) for e in err for k in KEYS])
        abs_important = np.mean([abs(e[k]) for e in err for k in IMPORTANT])
        print(f"| {name} | {np.mean(seconds[name]):.1f} | "
              + " | ".join(f"{b:+.1f}" for b in bias)
              + f" | {abs_def:.1f} | {abs_important:.1f} |")
    print(f"\nErrors in mm (fitted - true), bias = signed mean over {args.subjects} subjects; "
          "per subject, D/E/F:\n")
    for name in ROWS:
        cells = "; ".join("/".join(f"{e[k]:+.0f}" for k in KEYS) for e in errors[name])
        print(f"- {name}: {cells}")


if __name__ == "__main__":
    main()
