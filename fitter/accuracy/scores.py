"""A benchmark run's errors against the truth, and their statistics.

A run is ``fitter batch``'s output folder for a subject set (:mod:`.subject_set`): its
summary.csv holds each fitted subject's 16 measurements and spreads, failures.csv each
failed subject's reason. Errors are estimate - truth, millimetres, ``MEASUREMENTS`` order.
The truths are the set's truth.json files, or a run folder's own truths.json (``{id:
record}``, written by ``tools/bench_accuracy.py keep``) when it has one: a kept run is
reported against the truths it was fitted to, whatever machine remade the set.
"""

from __future__ import annotations

import csv
import dataclasses
import json
from pathlib import Path

import numpy as np
from scipy import stats

from bodyfit.fitter.batch.tables import FAILURES_FILE, SUMMARY_FILE
from bodyfit.fitter.measurements import IMPORTANT, MEASUREMENTS

__all__ = ["RunScores", "ErrorStats", "read_scores", "truth_records", "error_stats", "KEYS",
           "IMPORTANT_COLUMNS", "TRUTHS_FILE"]

KEYS = list(MEASUREMENTS)
IMPORTANT_COLUMNS = [KEYS.index(key) for key in IMPORTANT]
_FITTED = ("fitted", "fitted earlier")
TRUTHS_FILE = "truths.json"


@dataclasses.dataclass(frozen=True)
class RunScores:
    """One run's subjects, row-aligned.

    Attributes:
        ids: (N,) fitted subjects' ids.
        errors: (N, 16) estimate - truth, mm.
        spreads: (N, 16) the fit's reported spread, mm.
        seconds: (N,) each subject's job in its batch worker, s (NaN when unknown).
        failures: (id, reason) of every subject that failed.
        hard: (N,) bool, drawn from the out-of-space hard share.
    """

    ids: list[str]
    errors: np.ndarray
    spreads: np.ndarray
    seconds: np.ndarray
    failures: list[tuple[str, str]]
    hard: np.ndarray


def truth_records(set_folder: Path, ids: list[str]) -> dict[str, dict]:
    """id -> that subject's truth.json record in the set ``set_folder``."""
    return {i: json.loads((Path(set_folder) / i / "truth.json").read_text()) for i in ids}


def read_scores(set_folder: Path, run_folder: Path) -> RunScores:
    """The scores of the run in ``run_folder`` on the subject set in ``set_folder`` (the
    truths from the run's truths.json instead, when it has one)."""
    set_folder, run_folder = Path(set_folder), Path(run_folder)
    with open(run_folder / SUMMARY_FILE, newline="", encoding="utf-8") as file:
        rows = [row for row in csv.DictReader(file) if row["status"] in _FITTED]
    with open(run_folder / FAILURES_FILE, newline="", encoding="utf-8") as file:
        failures = [(row["id"], row["reason"]) for row in csv.DictReader(file)]
    kept = run_folder / TRUTHS_FILE
    records = (json.loads(kept.read_text()) if kept.exists()
               else truth_records(set_folder, [row["id"] for row in rows]))
    names = [name for name, _ in MEASUREMENTS.values()]
    errors, spreads, seconds, hard = [], [], [], []
    for row in rows:
        record = records[row["id"]]
        truth = record["measurements"]
        errors.append([float(row[f"{name}_mm"]) - truth[key] for key, name in zip(KEYS, names)])
        spreads.append([float(row[f"{name}_spread_mm"] or "nan") for name in names])
        seconds.append(float(row["seconds"] or "nan"))
        hard.append(record["hard"])
    shape = (len(rows), len(KEYS))
    return RunScores([row["id"] for row in rows], np.array(errors).reshape(shape),
                     np.array(spreads).reshape(shape), np.array(seconds), failures,
                     np.array(hard, bool))


@dataclasses.dataclass(frozen=True)
class ErrorStats:
    """Statistics of (N, M) errors, per column (M,), mm.

    Attributes:
        count: N.
        mae, mae_sd: mean and standard deviation of |error|.
        mae_ci: half-width of the 95 % confidence interval of the mean |error| (Student t).
        bias, bias_ci: mean signed error and its 95 % interval's half-width.
        covered: share (0-1) of subjects whose |error| <= the reported spread.
    """

    count: int
    mae: np.ndarray
    mae_sd: np.ndarray
    mae_ci: np.ndarray
    bias: np.ndarray
    bias_ci: np.ndarray
    covered: np.ndarray


def error_stats(errors: np.ndarray, spreads: np.ndarray | None = None) -> ErrorStats:
    """:class:`ErrorStats` of ``errors`` (N, M), N >= 2; ``spreads`` (N, M) or None."""
    errors = np.asarray(errors, dtype=float)
    n = len(errors)
    if n < 2:
        raise ValueError(f"statistics need at least 2 subjects, got {n}")
    t = stats.t.ppf(0.975, n - 1) / np.sqrt(n)
    absolute = np.abs(errors)
    covered = (np.full(errors.shape[1], np.nan) if spreads is None
               else np.mean(absolute <= spreads, axis=0))
    return ErrorStats(n, absolute.mean(axis=0), absolute.std(axis=0, ddof=1),
                      t * absolute.std(axis=0, ddof=1), errors.mean(axis=0),
                      t * errors.std(axis=0, ddof=1), covered)
