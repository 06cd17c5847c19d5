"""What the fitter benchmarks share: drawing in-space subjects and fitting one by command.

Imported by the tools/bench_*.py scripts (run as ``python tools/bench_X.py``, which puts
this folder on the import path).
"""

from __future__ import annotations

import json
import subprocess
import time
from pathlib import Path

import numpy as np

from bodyfit.fitter.measurements import MEASUREMENTS

__all__ = ["draw_subject", "fit_by_command"]


def draw_subject(rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """An in-space subject: (20,) betas normal, clipped at +-2 sigma; (4,) limbs 2-8
    degrees out."""
    return np.clip(rng.standard_normal(20), -2, 2), rng.uniform(2, 8, 4)


def fit_by_command(folder: Path, truth: dict[str, float], out: Path,
                   options: list[str]) -> tuple[float, list[float]]:
    """Fit the subject photographed in ``folder`` (front.png, side.png) with the `fitter run`
    command itself, start-up included; return (wall seconds, the 16 errors fitted - true
    in ``MEASUREMENTS`` order, mm)."""
    start = time.perf_counter()
    subprocess.run(["fitter", "-q", "run", "--front", str(folder / "front.png"), "--side",
                    str(folder / "side.png"), "--height-cm", f"{truth['O'] / 10:.2f}",
                    "-o", str(out), *options], check=True, stdout=subprocess.DEVNULL)
    seconds = time.perf_counter() - start
    table = json.loads((out / "measurements.json").read_text())["measurements"]
    return seconds, [table[name]["value_mm"] - truth[key]
                     for key, (name, _) in MEASUREMENTS.items()]
