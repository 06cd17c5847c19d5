"""Where the benchmark's numbers come from: runs of ``fit``, and the kept settings in git.

A **run** is ``fitter batch``'s output folder for a subject set, ``SET/runs/NAME``: its
summary.csv and failures.csv, one folder per subject with its run.json, and bench.json
(``fit``'s record of the machine and the peak memory). The truths are the set's
``SUBJECT/truth.json`` files.

A **kept setting** is what the docs' tables are computed from, in git: one CSV per set and
setting, ``docs/accuracy-runs/<kind>/<setting>.csv`` (:data:`KEPT_COLUMNS`: the run's
summary.csv columns, each fit's answer cost, each failure's reason), beside the set's
truths, ``truths.csv`` (:data:`TRUTH_COLUMNS`). ``keep`` merges a run's subjects into
one (replacing rows of the same subjects); a set is remade from its seed by ``make``.

A report source is either; several sources are joined into one (a setting fitted in
parts, in several sessions or on several machines): each subject from the first source
that holds it. Rows are the set's order: subject ``s0042-male`` is row 42.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from bench.accuracy.scores import KEYS, RunScores
from bodyfit.fitter.batch.orchestration import BATCH_FILE
from bodyfit.fitter.batch.tables import (FAILURES_FILE, MEASURED_COLUMNS, SUMMARY_COLUMNS,
                                         SUMMARY_FILE, csv_text, read_table)
from bodyfit.fitter.fit.spreads import recorded_answer_cost
from bodyfit.fitter.measure.measurements import MEASUREMENTS
from bodyfit.fitter.output.result_files import write_text

__all__ = ["KEPT_COLUMNS", "TRUTH_COLUMNS", "TRUTHS_FILE", "FITTED", "subject_row",
           "run_folder", "read_source", "joined_scores", "concatenated", "window", "subset",
           "record_holders", "source_timing", "read_truths", "keep_run"]

_NAMES = [name for name, _ in MEASUREMENTS.values()]
#: A kept setting's columns: summary.csv's but its warning, then the fit's answer cost
#: (weighted mm, :func:`~bodyfit.fitter.fit.spreads.recorded_answer_cost`) and a failure's
#: reason.
KEPT_COLUMNS = MEASURED_COLUMNS + ["answer_cost", "reason"]
#: truths.csv's columns: the subject, its sex, whether it was drawn from the out-of-space
#: hard share, and its 16 true measurements (mm, the names of measurements.json).
TRUTH_COLUMNS = ["id", "sex", "hard"] + [f"{name}_mm" for name in _NAMES]
TRUTHS_FILE = "truths.csv"
#: summary.csv's statuses of a subject fitted (by this run or an earlier one).
FITTED = ("fitted", "fitted earlier")


def subject_row(subject_id: str) -> int:
    """The set's row of a subject: ``s0042-male`` -> 42."""
    return int(subject_id[1:5])


def run_folder(set_folder: Path, name: str) -> Path:
    """A run's folder: ``SET/runs/NAME`` for a bare name, else the path as given."""
    return Path(name) if "/" in name else Path(set_folder) / "runs" / name


def read_truths(path: Path) -> dict[str, dict]:
    """A truths.csv as ``{id: {"measurements": {key: mm}, "sex": str, "hard": bool}}``,
    the form of the set's truth.json files."""
    truths = {}
    for row in read_table(path, TRUTH_COLUMNS):
        truths[row["id"]] = {"measurements": {key: float(row[f"{name}_mm"])
                                              for key, name in zip(KEYS, _NAMES)},
                             "sex": row["sex"], "hard": row["hard"] == "True"}
    return truths


def _set_truths(set_folder: Path, ids: list[str]) -> dict[str, dict]:
    return {i: json.loads((set_folder / i / "truth.json").read_text()) for i in ids}


def _scores(rows: list[dict[str, str]], truths: dict[str, dict],
            failures: list[tuple[str, str]], answer_costs: list[float]) -> RunScores:
    """RunScores of summary-like ``rows`` (the fitted subjects) against ``truths``."""
    errors, spreads, seconds, hard = [], [], [], []
    for row in rows:
        truth = truths[row["id"]]["measurements"]
        errors.append([float(row[f"{name}_mm"]) - truth[key] for key, name in zip(KEYS, _NAMES)])
        spreads.append([float(row[f"{name}_spread_mm"] or "nan") for name in _NAMES])
        seconds.append(float(row["seconds"] or "nan"))
        hard.append(truths[row["id"]]["hard"])
    shape = (len(rows), len(KEYS))
    return RunScores([row["id"] for row in rows], np.array(errors).reshape(shape),
                     np.array(spreads).reshape(shape), np.array(seconds), failures,
                     np.array(hard, bool), np.array(answer_costs, float))


def _answer_cost(run: Path, subject: str) -> float:
    record = run / subject / "run.json"
    return recorded_answer_cost(json.loads(record.read_text())) if record.exists() else np.nan


def _run_rows(run: Path) -> tuple[list[dict[str, str]], list[tuple[str, str]]]:
    rows = [row for row in read_table(run / SUMMARY_FILE, SUMMARY_COLUMNS)
            if row["status"] in FITTED]
    failures = [(row["id"], row["reason"]) for row in read_table(run / FAILURES_FILE,
                                                                   ("id", "reason"))]
    return rows, failures


def read_source(source: Path) -> RunScores:
    """The scores of a report source: a kept setting (a .csv, its truths.csv beside it) or
    a run's folder (its set two folders up)."""
    source = Path(source)
    if source.suffix == ".csv":
        table = read_table(source, KEPT_COLUMNS)
        rows = [row for row in table if row["status"] in FITTED]
        failures = [(row["id"], row["reason"]) for row in table if row["status"] not in FITTED]
        return _scores(rows, read_truths(source.parent / TRUTHS_FILE), failures,
                       [float(row["answer_cost"] or "nan") for row in rows])
    rows, failures = _run_rows(source)
    ids = [row["id"] for row in rows]
    return _scores(rows, _set_truths(source.parents[1], ids), failures,
                   [_answer_cost(source, i) for i in ids])


def subset(scores: RunScores, ids: set[str]) -> RunScores:
    """The scores of the subjects ``ids`` (fitted or failed) only."""
    keep = np.array([i in ids for i in scores.ids], bool)
    return RunScores([i for i in scores.ids if i in ids], scores.errors[keep],
                     scores.spreads[keep], scores.seconds[keep],
                     [f for f in scores.failures if f[0] in ids], scores.hard[keep],
                     scores.answer_costs[keep])


def window(scores: RunScores, first: int | None, skip: int = 0) -> RunScores:
    """The scores of the set's rows ``skip`` to ``first`` - 1 (all when ``first`` is None)."""
    if not first:
        return scores
    held = scores.ids + [s for s, _ in scores.failures]
    return subset(scores, {s for s in held if skip <= subject_row(s) < first})


def joined_scores(sources: list[Path], first: int | None = None,
                  skip: int = 0) -> list[tuple[Path, RunScores]]:
    """Each source with the scores of the subjects (fitted or failed) that no source before
    it holds, over the rows ``skip`` to ``first`` - 1 (:func:`window`)."""
    seen, parts = set(), []
    for source in sources:
        scores = window(read_source(source), first, skip)
        own = set(scores.ids + [s for s, _ in scores.failures]) - seen
        parts.append((Path(source), subset(scores, own)))
        seen |= own
    return parts


def concatenated(parts: list[tuple[Path, RunScores]]) -> RunScores:
    """The scores of :func:`joined_scores`' parts as one."""
    fields = ("errors", "spreads", "seconds", "hard", "answer_costs")
    return RunScores(ids=[i for _, s in parts for i in s.ids],
                     failures=[f for _, s in parts for f in s.failures],
                     **{field: np.concatenate([getattr(s, field) for _, s in parts])
                        for field in fields})


def record_holders(runs: list[Path], subjects: list[str]) -> dict[str, Path]:
    """subject -> the first of the run folders ``runs`` holding its fit record (run.json),
    for the ``subjects`` any of them holds."""
    holders = {}
    for run in runs:
        for subject in subjects:
            if subject not in holders and (Path(run) / subject / "run.json").exists():
                holders[subject] = Path(run)
    return holders


def source_timing(source: Path, scores: RunScores) -> str:
    """How fast a source's subjects went, and where: a run's batch.json and bench.json
    (the machine, the peak memory) when it has them, else its subjects' own times."""
    text = (f"{len(scores.ids)} fitted, {len(scores.failures)} failed; each subject's job "
            f"(photos to written results) {np.nanmedian(scores.seconds):.1f} s median"
            if len(scores.ids) else f"0 fitted, {len(scores.failures)} failed")
    batch, bench = Path(source) / BATCH_FILE, Path(source) / "bench.json"
    if not batch.exists():  # a kept setting, or fitter batch stopped before its end
        return text
    batch = json.loads(batch.read_text())
    fitted, wall = batch["subjects"]["fitted"], batch["seconds"]["total"]
    text += (f"; the last batch fitted {fitted} in {wall:.0f} s wall ({wall / max(fitted, 1):.2f}"
             f" s per subject, {batch['workers']} workers, "
             f"`fitter batch {' '.join(batch['command'][3:])}`)")
    if not bench.exists():  # fitter batch run by hand
        return text
    record = json.loads(bench.read_text())["runs"]
    return (f"{text} on {record[-1]['machine']}; peak memory of one process "
            f"{max(r['peak_rss_mb'] for r in record)} MB")


def _number(value) -> str:
    return "" if value is None or value != value else repr(float(value))


def keep_run(run: Path, kept: Path) -> int:
    """Merge the subjects of ``run`` (a run folder, its set two folders up) into the kept
    setting ``kept`` (a .csv), replacing its rows of the same subjects, and their truths
    into the truths.csv beside it; rows in the set's order. Returns the subjects kept.

    Raises:
        ValueError: a truth differs from the one kept already (another set's subject).
    """
    rows, failures = _run_rows(run)
    new = {row["id"]: {**row, "answer_cost": _number(_answer_cost(run, row["id"])),
                       "reason": ""} for row in rows}
    new.update({subject: {"id": subject, "status": "failed", "reason": reason}
                for subject, reason in failures})
    table = {row["id"]: row for row in read_table(kept, KEPT_COLUMNS)}
    table.update(new)
    truth_path = kept.parent / TRUTHS_FILE
    known = {row["id"]: row for row in read_table(truth_path, TRUTH_COLUMNS)}
    for subject, record in _set_truths(run.parents[1], list(new)).items():
        row = {"id": subject, "sex": record["sex"], "hard": str(bool(record["hard"])),
               **{f"{name}_mm": repr(float(record["measurements"][key]))
                  for key, name in zip(KEYS, _NAMES)}}
        if subject in known and known[subject] != row:
            raise ValueError(f"{subject}: its truth differs from {truth_path}'s (another set?)")
        known[subject] = row
    for path, header, records in ((truth_path, TRUTH_COLUMNS, known),
                                  (kept, KEPT_COLUMNS, table)):
        ordered = sorted(records.values(), key=lambda row: subject_row(row["id"]))
        write_text(path, csv_text(header, [[row.get(c, "") for c in header] for row in ordered]))
    return len(new)
