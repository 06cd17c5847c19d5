"""A run's errors against the truth, and their statistics.

Errors are estimate - truth, millimetres, ``MEASUREMENTS`` order. Where the estimates and
the truths are read from: :mod:`bench.accuracy.runs`.
"""

from __future__ import annotations

import dataclasses

import numpy as np
from scipy import stats

from bodyfit.fitter.measure.measurements import IMPORTANT, MEASUREMENTS

__all__ = ["RunScores", "ErrorStats", "error_stats", "KEYS", "IMPORTANT_COLUMNS"]

KEYS = list(MEASUREMENTS)
IMPORTANT_COLUMNS = [KEYS.index(key) for key in IMPORTANT]


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
        answer_costs: (N,) the fit's answer cost, weighted mm (NaN when unknown;
            :func:`~bodyfit.fitter.fit.spreads.recorded_answer_cost`).
    """

    ids: list[str]
    errors: np.ndarray
    spreads: np.ndarray
    seconds: np.ndarray
    failures: list[tuple[str, str]]
    hard: np.ndarray
    answer_costs: np.ndarray


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
