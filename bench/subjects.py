"""What the fitter benchmarks share: the bodyfit commands, drawing in-space subjects,
fitting them by command, their errors' table cells.

Imported by :mod:`bench.fitter_speed`, :mod:`bench.choices`, :mod:`bench.cameras`,
:mod:`bench.side_arms` and :mod:`bench.batch_speed`.
"""

from __future__ import annotations

import json
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from bodyfit.fitter.measure.measurements import IMPORTANT, MEASUREMENTS

__all__ = ["ERROR_HEADER", "bodyfit_command", "draw_subject", "fit_by_command", "fit_each_setting", "error_cells",
           "settings_table"]

#: The Markdown header cells of :func:`error_cells`.
ERROR_HEADER = "7 important, mean abs. error (mm) | " + " | ".join(IMPORTANT) + " | O"


def bodyfit_command(name: str) -> str:
    """The bodyfit command ``name`` ("fitter", "calib") of this Python's environment
    (found even when the environment is not activated), else the one on PATH."""
    beside = Path(sys.executable).parent / name
    return str(beside) if beside.exists() else name


def draw_subject(rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """An in-space subject: (20,) betas normal, clipped at +-2 sigma; (4,) limbs 2-8
    degrees out."""
    return np.clip(rng.standard_normal(20), -2, 2), rng.uniform(2, 8, 4)


def fit_by_command(folder: Path, truth: dict[str, float], out: Path,
                   options: list[str], photo_suffix: str = ".png") -> tuple[float, list[float]]:
    """Fit the subject photographed in ``folder`` (front and side, ``photo_suffix``) with the
    `fitter run` command itself, start-up included; return (wall seconds, the 16 errors
    fitted - true in ``MEASUREMENTS`` order, mm)."""
    start = time.perf_counter()
    subprocess.run([bodyfit_command("fitter"), "-q", "run", "--front", str(folder / f"front{photo_suffix}"),
                    "--side", str(folder / f"side{photo_suffix}"),
                    "--height-cm", f"{truth['O'] / 10:.2f}",
                    "-o", str(out), *options], check=True, stdout=subprocess.DEVNULL)
    seconds = time.perf_counter() - start
    table = json.loads((out / "measurements.json").read_text())["measurements"]
    return seconds, [table[name]["value_mm"] - truth[key]
                     for key, (name, _) in MEASUREMENTS.items()]


def fit_each_setting(folder: Path, truth: dict[str, float], settings: dict[str, list[str]],
                     common: list[str], errors: dict[str, list], seconds: dict[str, list],
                     photo_suffix: str = ".png") -> None:
    """Fit the subject in ``folder`` once per setting (its options after ``common``;
    ``{camera}`` in an option stands for ``folder/camera.json``) by :func:`fit_by_command`
    into ``folder/out<i>`` (replaced), appending the wall seconds and the 16 errors to
    ``seconds[name]`` and ``errors[name]``."""
    for index, (name, options) in enumerate(settings.items()):
        options = [option.format(camera=folder / "camera.json") for option in options]
        wall, error = fit_by_command(folder, truth, folder / f"out{index}",
                                     [*common, *options, "--overwrite"], photo_suffix)
        seconds[name].append(wall)
        errors[name].append(error)


def error_cells(errors: list[list[float]]) -> str:
    """The cells of ``ERROR_HEADER`` for (subjects, 16) errors in ``MEASUREMENTS`` order:
    the 7 important measurements' mean absolute error, each one's, and the stature's, mm."""
    keys = list(MEASUREMENTS)
    important = [keys.index(k) for k in IMPORTANT]
    err = np.abs(np.array(errors))
    return " | ".join(f"{value:.1f}" for value in
                      [err[:, important].mean(), *err[:, important].mean(axis=0),
                       err[:, keys.index("O")].mean()])


def settings_table(label: str, seconds: dict[str, list[float]], errors: dict[str, list],
                   average=np.mean) -> list[str]:
    """Markdown lines: one row per setting (``label`` heads the first column) of its wall
    seconds per subject (``average`` of them, named in the header) and its
    :func:`error_cells`."""
    lines = [f"| {label} | wall s ({average.__name__}) | {ERROR_HEADER} |",
             "|---|---|---|" + "---|" * (len(IMPORTANT) + 1)]
    return lines + [f"| {name} | {average(seconds[name]):.1f} | {error_cells(errors[name])} |"
                    for name in seconds]
