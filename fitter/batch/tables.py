"""The batch's tables in OUT: summary.csv and failures.csv, and what a rerun reads back.

``summary.csv``: one row per row of the subjects table, in its order: ``id``, ``status``,
``best_cost`` (the fit's best cost, weighted mm), ``seconds`` (the subject's job, photos
to written results, in the batch that fitted it), then each of the 16 measurements'
value and spread, millimetres (``chest_circumference_mm``,
``chest_circumference_spread_mm``, ...: the names of measurements.json), read back from
OUT/<id>/, and ``warning``: the fit's warning that it matched the silhouettes poorly
(run.json's ``photos.fit_warning``; empty for a sound fit). The status is one of
``STATUSES``:

- ``fitted``: fitted by this run; ``fitted earlier``: OUT/<id>/ was complete already;
- ``failed``: failed in this run; ``failed earlier``: failed in an earlier run and not
  tried again (``--retry-failed`` tries it);
- ``bad row``: a row skipped with ``--skip-bad-rows``;
- ``not run``: the batch stopped (interrupted) before it.

``failures.csv``: ``id``, ``reason``: every subject failed (now or earlier) and every
skipped bad row (its reason starts with its line in the subjects table).

Both are rewritten whole and atomically as the batch goes on.
"""

from __future__ import annotations

import csv
import dataclasses
import io
import json
import math
from collections.abc import Sequence
from pathlib import Path

from bodyfit.common.errors import UserError
from bodyfit.fitter.measure.measurements import MEASUREMENTS
from bodyfit.fitter.output.result_files import write_text
from bodyfit.fitter.run.results import RUN_FILES

__all__ = ["SUMMARY_FILE", "FAILURES_FILE", "STATUSES", "MEASURED_COLUMNS", "SUMMARY_COLUMNS",
           "FAILURES_COLUMNS",
           "SummaryRow", "PreviousBatch", "missing_results", "summary_row", "csv_text",
           "write_tables", "read_table", "read_previous"]

SUMMARY_FILE, FAILURES_FILE = "summary.csv", "failures.csv"
STATUSES = ("fitted", "fitted earlier", "failed", "failed earlier", "bad row", "not run")
_NAMES = [name for name, _ in MEASUREMENTS.values()]
#: summary.csv's columns before the warning: the subject, its status, cost, time and
#: measurements (what the accuracy benchmark keeps of a run).
MEASURED_COLUMNS = ["id", "status", "best_cost", "seconds"] + [
    column for name in _NAMES for column in (f"{name}_mm", f"{name}_spread_mm")]
SUMMARY_COLUMNS = MEASURED_COLUMNS + ["warning"]
FAILURES_COLUMNS = ["id", "reason"]


@dataclasses.dataclass(frozen=True)
class SummaryRow:
    """One row of summary.csv (module docstring); ``reason`` goes to failures.csv.

    Attributes:
        measurements: measurement name -> (value, spread), mm; empty unless fitted.
        warning: the fit's poor-match warning, or "".
    """

    subject_id: str
    status: str
    best_cost: float | None = None
    seconds: float | None = None
    measurements: dict[str, tuple[float, float]] = dataclasses.field(default_factory=dict)
    reason: str = ""
    warning: str = ""


def missing_results(folder: Path) -> list[str]:
    """The files of a `fitter run` (``RUN_FILES``) that ``folder`` lacks: none when the
    subject is done."""
    return [name for name in RUN_FILES if not (folder / name).is_file()]


def summary_row(folder: Path, status: str, seconds: float | None) -> SummaryRow:
    """The row of a fitted subject, its values read from its results in ``folder``
    (measurements.json, run.json); unreadable results give a row without values."""
    try:
        table = json.loads((folder / "measurements.json").read_text())["measurements"]
        record = json.loads((folder / "run.json").read_text())
        best_cost = float(record["result"]["best_cost"])
        values = {name: (float(table[name]["value_mm"]), float(table[name]["spread_mm"]))
                  for name in _NAMES}
        warning = str(record.get("photos", {}).get("fit_warning", ""))
    except (OSError, ValueError, KeyError, TypeError, AttributeError):
        return SummaryRow(folder.name, status, seconds=seconds)
    return SummaryRow(folder.name, status, best_cost, seconds, values, warning=warning)


def _number(value: float | None, digits: int | None = None) -> str:
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return ""
    return repr(float(value)) if digits is None else f"{value:.{digits}f}"


def csv_text(header: list[str], records: list[list[str]]) -> str:
    """A CSV file's text: ``header``, then ``records`` (rows of cells)."""
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(header)
    writer.writerows(records)
    return buffer.getvalue()


def write_tables(out_dir: Path, rows: list[SummaryRow]) -> tuple[Path, Path]:
    """Write summary.csv and failures.csv of ``rows`` into ``out_dir``, each atomically;
    return their paths."""
    summary = []
    for row in rows:
        cells = [row.subject_id, row.status, _number(row.best_cost), _number(row.seconds, 1)]
        for name in _NAMES:
            value, spread = row.measurements.get(name, (None, None))
            cells += [_number(value, 2), _number(spread, 2)]
        summary.append(cells + [row.warning])
    failures = [[row.subject_id, row.reason] for row in rows
                if row.status in ("failed", "failed earlier", "bad row")]
    paths = out_dir / SUMMARY_FILE, out_dir / FAILURES_FILE
    # failures first: a rerun takes a subject's failure from summary.csv, its reason from here
    write_text(paths[1], csv_text(FAILURES_COLUMNS, failures))
    write_text(paths[0], csv_text(SUMMARY_COLUMNS, summary))
    return paths


@dataclasses.dataclass(frozen=True)
class PreviousBatch:
    """What an earlier run into the same OUT recorded.

    Attributes:
        failed: id -> reason of the subjects that failed (not bad rows).
        seconds: id -> the job's seconds of the subjects it fitted.
    """

    failed: dict[str, str]
    seconds: dict[str, float]


def read_table(path: Path, columns: Sequence[str]) -> list[dict[str, str]]:
    """The rows of the batch table ``path`` (none when there is no file).

    Raises:
        UserError: it lacks ``columns`` or cannot be read.
    """
    try:
        with open(path, newline="", encoding="utf-8") as stream:
            reader = csv.DictReader(stream)
            if not set(columns) <= set(reader.fieldnames or ()):
                raise UserError(f"{path} is not a fitter batch table (it lacks "
                                f"{', '.join(columns)}); move it out of the output folder")
            return list(reader)
    except FileNotFoundError:
        return []
    except (OSError, UnicodeDecodeError, csv.Error) as error:
        raise UserError(f"{path}: cannot read it ({error}); move it out of the output "
                        "folder") from None


def read_previous(out_dir: Path) -> PreviousBatch:
    """The failures and seconds an earlier batch wrote into ``out_dir`` (empty when none).

    Raises:
        UserError: summary.csv or failures.csv is there but is not a batch's table.
    """
    summary = read_table(out_dir / SUMMARY_FILE, ("id", "status", "seconds"))
    reasons = {row["id"]: row["reason"]
               for row in read_table(out_dir / FAILURES_FILE, FAILURES_COLUMNS)}
    failed, seconds = {}, {}
    for row in summary:
        if row["status"] in ("failed", "failed earlier"):
            failed[row["id"]] = reasons.get(row["id"]) or "failed in an earlier run"
        elif row["status"] in ("fitted", "fitted earlier") and row["seconds"]:
            try:
                seconds[row["id"]] = float(row["seconds"])
            except ValueError:
                pass
    return PreviousBatch(failed, seconds)
