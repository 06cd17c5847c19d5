"""The accuracy benchmark's Markdown tables: the paper's Table 3 and Table 4 forms, the
ISO 20685-1 check, the spread's coverage, failures, time and memory.

Reference columns (mean +- sd of |error|, mm): the paper's own (Hemati & Bastanfard,
Table 3) and, per measurement, the best method's column of that table.
ISO 20685-1 allows a scanner's measurements to differ from a skilled measurer's by at
most 4 mm for heights, small girths and breadths, 5 mm for segment lengths and 9 mm for
the large girths (chest, waist, hip); it tests a bias: the 95 % confidence interval of
the mean signed error must lie within the allowance.
"""

from __future__ import annotations

import collections

import numpy as np

from bench.accuracy.scores import (IMPORTANT_COLUMNS, KEYS, ErrorStats, RunScores, error_stats)
from bodyfit.fitter.measure.measurements import IMPORTANT, MEASUREMENTS

__all__ = ["PAPER", "BEST_PUBLISHED", "ISO_ALLOWANCE_MM", "measurement_table",
           "important_table", "iso_verdicts", "failure_lines", "mean_of_important",
           "paired_difference", "paired_measurement_table"]

#: The paper's Table 3 (mean, sd of |error|, mm), and its mean of the 7 important.
PAPER = {"A": (3.1, 3.5), "B": (2.1, 2.0), "C": (2.2, 3.5), "D": (2.5, 3.2), "E": (5.1, 7.1),
         "F": (3.3, 5.5), "G": (3.0, 3.1), "H": (3.2, 3.4), "I": (3.1, 3.2), "J": (3.9, 2.8),
         "K": (3.2, 4.8), "L": (2.6, 4.4), "M": (3.2, 2.1), "N": (2.9, 1.8), "O": (5.1, 6.2),
         "P": (2.1, 2.9), "mean": (2.8, 4.0)}
#: The best column of the paper's Table 3 for each measurement: (mean, sd, method).
BEST_PUBLISHED = {
    "A": (2.0, 3.0, "HS-2-Net-MM"), "B": (1.9, 1.5, "UF-US-HKS-2"), "C": (1.5, 2.2, "BfSNet"),
    "D": (2.0, 1.0, "HS-2-Net-MM"), "E": (4.8, 7.5, "BfSNet"), "F": (3.0, 5.1, "BfSNet"),
    "G": (1.6, 1.3, "UF-US-HKS-2"), "H": (2.0, 1.0, "HS-2-Net-MM"),
    "I": (1.0, 1.0, "HS-2-Net-MM"), "J": (1.7, 2.4, "BfSNet"), "K": (1.5, 2.7, "BfSNet"),
    "L": (2.4, 4.0, "BfSNet"), "M": (2.3, 3.6, "BfSNet"), "N": (1.4, 1.1, "UF-US-HKS-2"),
    "O": (2.3, 4.6, "BfSNet"), "P": (1.9, 2.5, "BfSNet"), "mean": (3.0, 4.7, "BfSNet")}
#: ISO 20685-1's allowance, mm: large girths 9, segment lengths 5, the rest (heights,
#: small girths, breadths) 4.
ISO_ALLOWANCE_MM = {key: 9.0 if key in "DEF" else 5.0 if key in "CJK" else 4.0
                    for key in MEASUREMENTS}


def _cell(mean: float, sd: float) -> str:
    return f"{mean:.1f} ± {sd:.1f}"


def measurement_table(scores: RunScores) -> list[str]:
    """Table 3 form for one run: every measurement's |error| mean +- sd with the 95 %
    interval of the mean, the signed mean with its interval, ISO 20685-1's verdict, how
    often the spread covers the truth, and the paper's and best published columns."""
    s = error_stats(scores.errors, scores.spreads)
    lines = ["| measurement | mean ± sd of abs. error (mm) | 95 % CI of mean | signed mean "
             "[95 % CI] | ISO 20685-1 allowance | ISO bias test | truth within spread | "
             "paper | best published |",
             "|---|---|---|---|---|---|---|---|---|"]
    verdicts = iso_verdicts(s)
    for j, (key, (_, label)) in enumerate(MEASUREMENTS.items()):
        best = BEST_PUBLISHED[key]
        lines.append(
            f"| {key} {label} | {_cell(s.mae[j], s.mae_sd[j])} | ±{s.mae_ci[j]:.1f} | "
            f"{s.bias[j]:+.1f} [{s.bias[j] - s.bias_ci[j]:+.1f}, {s.bias[j] + s.bias_ci[j]:+.1f}]"
            f" | {ISO_ALLOWANCE_MM[key]:.0f} | {verdicts[key]} | {100 * s.covered[j]:.0f} % | "
            f"{_cell(*PAPER[key])} | {_cell(*best[:2])} ({best[2]}) |")
    mean, sd, ci = mean_of_important(scores.errors)
    lines.append(f"| mean of {' '.join(IMPORTANT)} | {_cell(mean, sd)} | ±{ci:.1f} | | | | | "
                 f"{_cell(*PAPER['mean'])} | {_cell(*BEST_PUBLISHED['mean'][:2])} "
                 f"({BEST_PUBLISHED['mean'][2]}) |")
    return lines


def mean_of_important(errors: np.ndarray) -> tuple[float, float, float]:
    """(mean, sd, 95 % CI half-width) of the |error| over the 7 important measurements,
    pooled over subjects and measurements as the paper's Table 4 does; the interval is
    that of the subjects' own 7-measurement means."""
    absolute = np.abs(np.asarray(errors))[:, IMPORTANT_COLUMNS]
    per_subject = error_stats(absolute.mean(axis=1, keepdims=True))
    return float(absolute.mean()), float(absolute.std(ddof=1)), float(per_subject.mae_ci[0])


def paired_difference(run: RunScores, baseline: RunScores) -> tuple[float, float, int]:
    """``run``'s 7-measurement mean |error| minus ``baseline``'s, subject by subject over
    the subjects both fitted: (mean difference, half-width of its 95 % interval (Student
    t), subjects), mm. Pairing removes the subjects' own difficulty from the comparison."""
    ours, theirs = _paired_absolute(run, baseline)
    return (*_mean_with_interval(_important(ours) - _important(theirs)), len(ours))


def _important(absolute: np.ndarray) -> np.ndarray:
    """(S,) each subject's mean |error| over the 7 important measurements of (S, 16)."""
    return absolute[:, IMPORTANT_COLUMNS].mean(axis=1)


def _mean_with_interval(differences: np.ndarray) -> tuple[float, float]:
    """(mean, half-width of its 95 % Student-t interval) of (S,) paired differences."""
    s = error_stats(differences[:, None])
    return float(s.bias[0]), float(s.bias_ci[0])


def _paired_absolute(run: RunScores, baseline: RunScores) -> tuple[np.ndarray, np.ndarray]:
    """(S, 16) |error| of ``run`` and of ``baseline`` over the S subjects both fitted, in
    the same subject order, mm."""
    common = sorted(set(run.ids) & set(baseline.ids))

    def chosen(scores: RunScores) -> np.ndarray:
        row = {subject: i for i, subject in enumerate(scores.ids)}
        return np.abs(scores.errors[[row[s] for s in common]])

    return chosen(run), chosen(baseline)


def paired_measurement_table(run: RunScores, baseline: RunScores) -> list[str]:
    """Every measurement of ``run`` against ``baseline`` over the subjects both fitted:
    each one's mean |error|, the mean of their subject-by-subject difference with its 95 %
    interval (Student t) and for how many subjects ``run`` came closer, mm; then the
    same for the 7 important measurements' mean."""
    ours, theirs = _paired_absolute(run, baseline)
    s = error_stats(ours - theirs)
    lines = [f"| measurement | baseline (mm) | this (mm) | paired difference (95 % CI) | "
             f"closer for (of {len(ours)}) |", "|---|---|---|---|---|"]
    for j, (key, (_, label)) in enumerate(MEASUREMENTS.items()):
        lines.append(f"| {key} {label} | {theirs[:, j].mean():.2f} | {ours[:, j].mean():.2f} | "
                     f"{s.bias[j]:+.2f} (±{s.bias_ci[j]:.2f}) | "
                     f"{int((ours[:, j] < theirs[:, j]).sum())} |")
    ours7, theirs7 = _important(ours), _important(theirs)
    diff, diff_ci = _mean_with_interval(ours7 - theirs7)
    lines.append(f"| mean of {' '.join(IMPORTANT)} | {theirs7.mean():.2f} | {ours7.mean():.2f} | "
                 f"{diff:+.2f} (±{diff_ci:.2f}) | {int((ours7 < theirs7).sum())} |")
    return lines


def important_table(runs: dict[str, RunScores],
                    baselines: dict[str, str] | None = None) -> list[str]:
    """Table 4 form: one row per run, the 7 important measurements' mean |error| and
    their mean (+- its 95 % interval), subjects and failures; with ``baselines`` (row
    name -> the name of the row it is compared with; none: no such column), a last
    column with the :func:`paired_difference` from that row."""
    paired = bool(baselines)
    lines = [f"| setting | subjects fitted | failed | {' | '.join(IMPORTANT)} | mean of 7 "
             "(95 % CI) |" + (" paired difference (95 % CI) |" if paired else ""),
             "|---|---|---|" + "---|" * (len(IMPORTANT) + 1 + paired)]
    for name, scores in runs.items():
        mae = np.abs(scores.errors).mean(axis=0)
        mean, _, ci = mean_of_important(scores.errors)
        line = (f"| {name} | {len(scores.ids)} | {len(scores.failures)} | "
                + " | ".join(f"{mae[KEYS.index(k)]:.1f}" for k in IMPORTANT)
                + f" | **{mean:.2f}** (±{ci:.2f}) |")
        if paired:
            baseline = baselines.get(name)
            if baseline is None:
                line += " |"
            else:
                diff, diff_ci, _ = paired_difference(scores, runs[baseline])
                line += f" {diff:+.2f} (±{diff_ci:.2f}) from {baseline} |"
        lines.append(line)
    lines.append("| paper (its own model) | 500 | | "
                 + " | ".join(f"{PAPER[k][0]:.1f}" for k in IMPORTANT)
                 + f" | {PAPER['mean'][0]:.1f} |" + (" |" if paired else ""))
    return lines


def iso_verdicts(s: ErrorStats) -> dict[str, str]:
    """key -> "pass" when the 95 % interval of the mean signed error lies within ISO
    20685-1's allowance, else "fail"."""
    return {key: "pass" if abs(s.bias[j]) + s.bias_ci[j] <= ISO_ALLOWANCE_MM[key] else "fail"
            for j, key in enumerate(KEYS)}


def failure_lines(scores: RunScores) -> list[str]:
    """The failures counted by reason, each subject's id in its reason written ``<id>``."""
    reasons = collections.Counter(reason.replace(subject, "<id>")
                                  for subject, reason in scores.failures)
    return [f"- {count} x {reason}" for reason, count in reasons.most_common()]
