"""Benchmark of `fitter run`: measurement error against time, per search setting.

    python -m bench.fitter_speed                    # 4 subjects, the settings below
    python -m bench.fitter_speed --subjects 8 --seed 3 --plot docs/fitter_error_vs_time.png
    python -m bench.fitter_speed --device cuda:0    # the kernels on a GPU

In-space subjects: bodies drawn from the model's own 20-component space (betas normal,
clipped at +-2 sigma; limbs 2-8 degrees out), photographed front and side (the side
with the arms hanging down) by :mod:`bodyfit.fitter.demo.studio_photos` (a painter's renderer,
not the kernels; orthographic, 700 px tall), then fitted by the `fitter run` command
itself, start-up included, once per setting. Error: |fitted - true| of the 16
measurements, mm. Prints Markdown (docs/fitter.md holds the output) and writes the
error-against-time plot.
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from bench.subjects import ERROR_HEADER, draw_subject, error_cells, fit_each_setting
from bodyfit.calib.images import write_image
from bodyfit.fitter.demo.studio_photos import write_subject
from bodyfit.fitter.measure.measurements import IMPORTANT, MEASUREMENTS
from bodyfit.fitter.model.cache import load_model
from bodyfit.fitter.output.plots import line_chart

#: name -> `fitter run` options: the paper's method and bodyfit's defaults at several
#: budgets (candidates = population x generations), for error against time.
SETTINGS = {
    "paper: GA 30 x 25": ["--method", "paper"],
    "paper: GA 30 x 200": ["--method", "paper", "--generations", "200"],
    "bodyfit: CMA-ES 30 x 50": ["--generations", "50"],
    "bodyfit: CMA-ES 30 x 100": ["--generations", "100"],
    "bodyfit (default): CMA-ES 30 x 150": [],
    "bodyfit: CMA-ES 30 x 200": ["--generations", "200"],
    "bodyfit: CMA-ES 30 x 400": ["--generations", "400"],
}
#: The studio photos are orthographic: every setting fits them so (the paper's method
#: does by default; bodyfit's default is a pinhole camera, for real photos).
PHOTO_OPTIONS = ["--projection", "orthographic"]
#: The curves of the error-against-time plot: name -> the settings on it.
CURVES = {"paper's method (GA)": [name for name in SETTINGS if name.startswith("paper")],
          "bodyfit (CMA-ES)": [name for name in SETTINGS if name.startswith("bodyfit")]}


def _candidates(options: list[str]) -> int:
    paper = "paper" in options
    generations = int(options[options.index("--generations") + 1]) \
        if "--generations" in options else (25 if paper else 150)
    return 30 * generations


def main() -> None:
    parser = argparse.ArgumentParser(prog="python -m bench.fitter_speed",
                                     description=__doc__.splitlines()[0])
    parser.add_argument("--subjects", type=int, default=4)
    parser.add_argument("--seed", type=int, default=7)
    parser.add_argument("--plot", type=Path, default=Path("docs/fitter_error_vs_time.png"),
                        help="error-against-time plot to write")
    parser.add_argument("--device", default="cpu", help="`fitter run --device` (cpu, cuda:0)")
    args = parser.parse_args()
    model = load_model()
    rng = np.random.default_rng(args.seed)
    errors = {name: [] for name in SETTINGS}
    seconds = {name: [] for name in SETTINGS}
    with tempfile.TemporaryDirectory() as scratch:
        for i in range(args.subjects):
            folder = Path(scratch) / f"s{i}"
            folder.mkdir()
            truth = write_subject(folder, model, *draw_subject(rng))
            fit_each_setting(folder, truth, SETTINGS, [*PHOTO_OPTIONS, "--device", args.device],
                             errors, seconds)
    keys = list(MEASUREMENTS)
    important = [keys.index(k) for k in IMPORTANT]
    device = "" if args.device == "cpu" else f" --device {args.device}"
    print(f"`python -m bench.fitter_speed --subjects {args.subjects} --seed {args.seed}{device}` "
          f"on {time.strftime('%Y-%m-%d')}: {platform.machine()}, {os.cpu_count()} logical CPUs, "
          f"`fitter run` on {args.device}, start-up included.\n")
    print(f"| setting | candidates | wall s (mean) | {ERROR_HEADER} |")
    print("|---|---|---|---|" + "---|" * (len(IMPORTANT) + 1))
    for name, options in SETTINGS.items():
        print(f"| {name} | {_candidates(options)} | {np.mean(seconds[name]):.1f} | "
              f"{error_cells(errors[name])} |")
    mean7 = {name: np.abs(np.array(errors[name]))[:, important].mean() for name in SETTINGS}
    chart = line_chart({curve: [mean7[n] for n in names] for curve, names in CURVES.items()},
                       f"fitter run, {args.subjects} in-space subjects", "wall seconds per subject",
                       "7 important measurements, mean abs. error (mm)", log_y=True,
                       x_values={curve: [np.mean(seconds[n]) for n in names]
                                 for curve, names in CURVES.items()})
    write_image(args.plot, chart)
    print(f"\nPlot: `{args.plot}`.")
    sys.stdout.flush()


if __name__ == "__main__":
    main()
