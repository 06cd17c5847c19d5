"""Benchmark of `fitter run`'s cameras: what the projection costs on pinhole photos.

    python -m bench.cameras                    # 4 subjects, bodyfit's default method
    python -m bench.cameras --subjects 3 --seed 5

In-space subjects as bench/subjects.py draws them (bodies of the model's 20-component space,
betas normal clipped at +-2 sigma, limbs 2-8 degrees out), photographed front and side by
:func:`bodyfit.fitter.demo.studio_photos.write_pinhole_subject` (a painter's renderer, not the
kernels) through a pinhole camera unlike the no-camera assumption (:data:`TRUE_HFOV_DEG`
across the long side, principal point off the centre), 1500 x 2000 px, 2.5-3.5 m away,
the camera 1.0-1.5 m high, its axis horizontal. Each subject is fitted by the `fitter run`
command once per way of handling the camera (:data:`SETTINGS`). Error: |fitted - true| of
the measurements, mm. Prints Markdown (docs/fitter.md, Cameras, holds the output).
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

from bench.subjects import draw_subject, fit_each_setting, settings_table
from bodyfit.fitter.demo.studio_photos import write_pinhole_subject
from bodyfit.fitter.model.cache import load_model

SIZE_PX = (1500, 2000)
#: The true camera: a 28 mm-equivalent phone camera (66 degrees across the long side),
#: principal point 12 px right of and 18 px above the centre.
TRUE_HFOV_DEG = 66.0
TRUE_CENTRE_OFFSET_PX = (12.0, -18.0)
#: The method: bodyfit's default (before the local solver, CMA-ES 30 x 150: history.md).
BUDGET: list[str] = []
#: name -> `fitter run` options (``{camera}``: the subject's camera.json).
SETTINGS = {
    "(a) orthographic, no camera (the paper's)": ["--projection", "orthographic"],
    "(b) pinhole, the true camera (--camera)": ["--camera", "{camera}"],
    "(c) pinhole, no camera (a typical phone assumed)": ["--projection", "pinhole"],
}


def true_intrinsics() -> np.ndarray:
    width, height = SIZE_PX
    focal = height / 2 / np.tan(np.deg2rad(TRUE_HFOV_DEG) / 2)
    return np.array([[focal, 0, (width - 1) / 2 + TRUE_CENTRE_OFFSET_PX[0]],
                     [0, focal, (height - 1) / 2 + TRUE_CENTRE_OFFSET_PX[1]], [0, 0, 1.0]])


def main() -> None:
    parser = argparse.ArgumentParser(prog="python -m bench.cameras",
                                     description=__doc__.splitlines()[0])
    parser.add_argument("--subjects", type=int, default=4)
    parser.add_argument("--seed", type=int, default=7)
    args = parser.parse_args()
    model = load_model()
    rng = np.random.default_rng(args.seed)
    errors = {name: [] for name in SETTINGS}
    seconds = {name: [] for name in SETTINGS}
    scenes = []
    with tempfile.TemporaryDirectory() as scratch:
        for i in range(args.subjects):
            folder = Path(scratch) / f"s{i}"
            folder.mkdir()
            betas, pose = draw_subject(rng)
            distance, height = rng.uniform(2.5, 3.5), rng.uniform(1.0, 1.5)
            scenes.append(f"{distance:.2f} m / {height:.2f} m")
            truth = write_pinhole_subject(folder, model, betas, pose, true_intrinsics(), SIZE_PX,
                                          distance, height)
            fit_each_setting(folder, truth, SETTINGS, BUDGET, errors, seconds)
    print(f"`python -m bench.cameras --subjects {args.subjects} --seed {args.seed}` on "
          f"{time.strftime('%Y-%m-%d')}: {platform.machine()}, {os.cpu_count()} logical CPUs, "
          f"`fitter run {' '.join(BUDGET)}` on the CPU, start-up included; camera distance / "
          f"height per subject: {', '.join(scenes)}.\n")
    print("\n".join(settings_table("camera handling", seconds, errors)))
    sys.stdout.flush()


if __name__ == "__main__":
    main()
