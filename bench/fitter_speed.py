"""Benchmark of `fitter run`: measurement error against wall time, per method and budget.

    python -m bench.fitter_speed SETS/in SETS/out --first 2
    python -m bench.fitter_speed SETS/in SETS/out --first 2 --device cuda:0
    python -m bench.fitter_speed SETS/in SETS/out --first 2 --only bodyfit --plot OTHER.png

Subjects: the first N rows of accuracy benchmark sets (``python -m bench.accuracy make``;
in-space and out-of-space bodies photographed through a phone camera, calibrated into
SET/camera.json by ``python -m bench.accuracy fit`` or ``calib capture``). Each is
fitted by the `fitter run` command itself with ``--camera``, start-up included, once per
setting, one after another on this machine. Error: the 7 important measurements' mean
|fitted - true|, mm. Prints Markdown (docs/fitter.md holds the output) and writes the
error-against-time plot.
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np

from bench.subjects import fit_each_setting, settings_table
from bodyfit.calib.images import write_image
from bodyfit.fitter.measure.measurements import IMPORTANT, MEASUREMENTS
from bodyfit.fitter.output.plots import line_chart

#: name -> `fitter run` options: bodyfit's default (the local solver from the learned
#: start, 40 iterations at most, the front photo's hands fitted, the cameras' pitch
#: searched), the same with the hands at rest (the default before), with the cameras
#: level and at other iteration budgets, the learned start alone,
#: the solver from the mean body (40 iterations, the default before the learned start), the
#: population search that was the default before that (``thorough``) at its full budget
#: and at one search alone, and the paper's method at two budgets.
SETTINGS = {
    "bodyfit: the learned start alone": ["--iterations", "0"],
    "bodyfit: 5 iterations, cameras level": ["--iterations", "5", "--pitch", "level"],
    "bodyfit: 10 iterations, cameras level": ["--iterations", "10", "--pitch", "level"],
    "bodyfit: 10 iterations, cameras level, the elbows at rest": [
        "--iterations", "10", "--pitch", "level", "--elbows", "rest"],
    "bodyfit: 40 iterations, cameras level": ["--pitch", "level"],
    "bodyfit: 40 iterations, the hands at rest (the default before)": ["--hands", "rest"],
    "bodyfit (default): 40 iterations, the hands fitted, the cameras' pitch searched": [],
    "bodyfit from the mean body: 40 iterations": ["--start", "mean", "--iterations", "40",
                                                  "--pitch", "level"],
    "thorough: one search 30 x 150": ["--method", "thorough", "--searches", "1",
                                      "--refine-components", "0"],
    "thorough (the default before)": ["--method", "thorough"],
    "paper: GA 30 x 25": ["--method", "paper"],
    "paper: GA 30 x 200": ["--method", "paper", "--generations", "200"],
}
#: The curves of the error-against-time plot: name -> the settings on it.
CURVES = {family: [name for name in SETTINGS if name.startswith(prefixes)]
          for family, prefixes in (("bodyfit (local solver, learned start)",
                                    ("bodyfit:", "bodyfit (default)")),
                                   ("bodyfit from the mean body", ("bodyfit from",)),
                                   ("thorough (CMA-ES)", ("thorough",)),
                                   ("paper (GA)", ("paper",)))}


def _subjects(set_folder: Path, first: int) -> list[tuple[Path, dict[str, float]]]:
    """(subject folder, true measurements key -> mm) of the set's first ``first`` rows."""
    with open(set_folder / "subjects.csv", newline="") as table:
        rows = list(csv.DictReader(table))[:first]
    return [(set_folder / row["id"],
             json.loads((set_folder / row["id"] / "truth.json").read_text())["measurements"])
            for row in rows]


def main() -> None:
    parser = argparse.ArgumentParser(prog="python -m bench.fitter_speed",
                                     description=__doc__.splitlines()[0])
    parser.add_argument("sets", nargs="+", type=Path, help="subject set folders")
    parser.add_argument("--first", type=int, default=2, help="subjects of each set")
    parser.add_argument("--plot", type=Path, default=Path("docs/fitter_error_vs_time.png"),
                        help="error-against-time plot to write")
    parser.add_argument("--device", default="cpu", help="`fitter run --device` (cpu, cuda:0)")
    parser.add_argument("--only", metavar="PREFIX",
                        help="only the settings whose name starts with PREFIX (bodyfit, "
                             "thorough, paper)")
    args = parser.parse_args()
    settings = {name: options for name, options in SETTINGS.items()
                if name.startswith(args.only or "")}
    errors = {name: [] for name in settings}
    seconds = {name: [] for name in settings}
    for set_folder in args.sets:
        for folder, truth in _subjects(set_folder, args.first):
            fit_each_setting(folder, truth, settings,
                             ["--camera", str(set_folder / "camera.json"), "--device",
                              args.device], errors, seconds, photo_suffix=".jpg")
    keys = list(MEASUREMENTS)
    important = [keys.index(k) for k in IMPORTANT]
    count = len(next(iter(errors.values())))
    print(f"`python -m bench.fitter_speed {' '.join(map(str, args.sets))} --first {args.first}"
          f"{'' if args.device == 'cpu' else ' --device ' + args.device}"
          f"{'' if args.only is None else ' --only ' + args.only}` on "
          f"{time.strftime('%Y-%m-%d')}: {platform.machine()}, {os.cpu_count()} logical CPUs, "
          f"`fitter run --camera` on {args.device}, start-up included, {count} subjects.\n")
    print("\n".join(settings_table("setting", seconds, errors, np.median)))
    mean7 = {name: np.abs(np.array(errors[name]))[:, important].mean() for name in settings}
    curves = {curve: [n for n in names if n in settings] for curve, names in CURVES.items()}
    curves = {curve: names for curve, names in curves.items() if names}
    chart = line_chart({curve: [mean7[n] for n in names] for curve, names in curves.items()},
                       f"fitter run --camera, {count} subjects", "wall seconds per subject "
                       "(median)", "7 important measurements, mean abs. error (mm)",
                       log_y=True, x_values={curve: [np.median(seconds[n]) for n in names]
                                             for curve, names in curves.items()})
    write_image(args.plot, chart)
    print(f"\nPlot: `{args.plot}`.")
    sys.stdout.flush()


if __name__ == "__main__":
    main()
