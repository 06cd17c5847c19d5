"""A batch from plan to tables: which subjects are done, which to fit, and the records.

A subject is done when OUT/<id>/ holds every file of a `fitter run`
(:func:`~bodyfit.fitter.batch.tables.missing_results`); a rerun keeps it. Since a job
moves its results into place in one rename, a batch killed at any moment loses at most
the subjects in flight; a rerun removes what they left (staging folders beside OUT/<id>/,
temporary files of the tables) and fits them again. A subject that failed in an earlier
run is not tried again unless ``retry_failed``. Only one batch at a time writes into an
OUT (a lock file, ``OUT/.batch.lock``, while it runs).

Besides the tables (:mod:`~bodyfit.fitter.batch.tables`), OUT/batch.json records how the
batch ran: the command, the version, the engine and its workers, the wall seconds (and
of them the engine's start-up, until the first subject started) and the count of each
status.
"""

from __future__ import annotations

import contextlib
import dataclasses
import datetime
import logging
import shutil
import sys
import time
from collections.abc import Sequence
from pathlib import Path

from tqdm import tqdm

from bodyfit.common.command_line import bodyfit_version
from bodyfit.common.errors import UserError
from bodyfit.common.files import TEMP_FILE_PATTERN, created_folders
from bodyfit.fitter.output.result_files import STAGE_PATTERN, write_json

from bodyfit.fitter.batch.job import SubjectJob, SubjectOutcome
from bodyfit.fitter.batch.subjects import SubjectTable
from bodyfit.fitter.batch.tables import (FAILURES_FILE, STATUSES, SUMMARY_FILE, SummaryRow,
                                         missing_results, read_previous, summary_row, write_tables)

__all__ = ["BATCH_FILE", "LOCK_FILE", "BatchResult", "run_batch"]

logger = logging.getLogger(__name__)

BATCH_FILE, LOCK_FILE = "batch.json", ".batch.lock"
#: The tables are rewritten at most this often while subjects finish, seconds (and at the
#: end): a killed batch loses at most this much of its records, which a rerun rebuilds.
_TABLES_EVERY_S = 2.0


@dataclasses.dataclass(frozen=True)
class BatchResult:
    """How a batch ended: its rows (one per row of the subjects table, in order), the
    files it wrote (summary.csv, failures.csv, batch.json) and its wall seconds."""

    rows: list[SummaryRow]
    written: list[Path]
    seconds: float

    def count(self, status: str) -> int:
        return sum(row.status == status for row in self.rows)


@contextlib.contextmanager
def _batch_lock(out_dir: Path):
    """Hold OUT/.batch.lock for the block; UserError when another batch holds it."""
    try:
        import fcntl
    except ImportError:  # not POSIX: no lock
        yield
        return
    path = out_dir / LOCK_FILE
    with open(path, "a") as stream:
        try:
            fcntl.flock(stream, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            raise UserError(f"another fitter batch is writing into {out_dir} (it holds "
                            f"{path}); wait for it to end") from None
        try:
            yield
        finally:
            path.unlink(missing_ok=True)


def _remove_leftovers(out_dir: Path, subject_ids: set[str]) -> None:
    """Remove what killed jobs and writes left in OUT: staging folders of the subjects'
    results and temporary files of the batch's own files."""
    own_files = {SUMMARY_FILE, FAILURES_FILE, BATCH_FILE}
    for entry in out_dir.iterdir():
        stage = STAGE_PATTERN.fullmatch(entry.name)
        temp = TEMP_FILE_PATTERN.fullmatch(entry.name)
        if stage and stage.group(1) in subject_ids and entry.is_dir():
            logger.info("removing %s, left by a batch stopped while writing", entry)
            shutil.rmtree(entry, ignore_errors=True)
        elif temp and temp.group(1) in own_files and entry.is_file():
            entry.unlink(missing_ok=True)


def _plan(table: SubjectTable, out_dir: Path, retry_failed: bool
          ) -> tuple[dict[int, SummaryRow], list[int]]:
    """(line -> row of the subjects not to fit now, lines of those to fit)."""
    previous = read_previous(out_dir)
    known: dict[int, SummaryRow] = {
        bad.line: SummaryRow(bad.subject_id, "bad row", reason=f"line {bad.line}: {bad.reason}")
        for bad in table.bad_rows}
    to_fit = []
    for row in table.rows:
        folder = out_dir / row.subject_id
        missing = missing_results(folder)
        if not missing:
            known[row.line] = summary_row(folder, "fitted earlier",
                                          previous.seconds.get(row.subject_id))
        elif folder.exists() and any(folder.iterdir()):
            known[row.line] = SummaryRow(row.subject_id, "failed", reason=(
                f"{folder} holds files but not all of a fit's (no {missing[0]}); move it "
                "away to fit the subject again"))
        elif row.subject_id in previous.failed and not retry_failed:
            known[row.line] = SummaryRow(row.subject_id, "failed earlier",
                                         reason=previous.failed[row.subject_id])
        else:
            to_fit.append(row.line)
    return known, to_fit


def run_batch(table: SubjectTable, jobs: dict[str, SubjectJob], out_dir: Path, engine,
              retry_failed: bool = False, progress: bool | None = None,
              command: Sequence[str] = ()) -> BatchResult:
    """Fit the table's subjects that are not done into ``out_dir`` on ``engine``.

    Args:
        table: the subjects table; its bad rows are recorded, not run.
        jobs: id -> job of each good row (:func:`~bodyfit.fitter.batch.job.subject_job`).
        out_dir: OUT (created).
        engine: a :class:`~bodyfit.fitter.batch.engines.LocalEngine` or
            :class:`~bodyfit.fitter.batch.ray_engine.RayEngine`.
        retry_failed: fit again the subjects an earlier run recorded as failed.
        progress: show a progress bar over the subjects (None: when stderr is a terminal).
        command: the command line, recorded in batch.json.

    Raises:
        UserError: another batch writes into OUT, OUT's tables are not a batch's, or the
            engine cannot start.
        KeyboardInterrupt: after the tables are written (the subjects not reached are
            ``not run``).
    """
    out_dir = Path(out_dir)
    started, start = datetime.datetime.now().astimezone(), time.perf_counter()
    with created_folders(out_dir), _batch_lock(out_dir):
        _remove_leftovers(out_dir, set(jobs))
        known, to_fit = _plan(table, out_dir, retry_failed)
        lines = sorted([*known, *to_fit])
        id_of = {row.line: row.subject_id for row in table.rows}
        line_of = {row.subject_id: row.line for row in table.rows}
        progress_state = {"failed": 0, "written": time.monotonic(), "first_start": None}

        def rows() -> list[SummaryRow]:
            return [known.get(line) or SummaryRow(id_of[line], "not run") for line in lines]

        def report(outcome: SubjectOutcome) -> None:
            if outcome.started_at and progress_state["first_start"] is None:
                progress_state["first_start"] = outcome.started_at
            line = line_of[outcome.subject_id]
            if outcome.fitted:
                known[line] = summary_row(out_dir / outcome.subject_id, "fitted",
                                          outcome.seconds)
            else:
                logger.warning("%s: failed: %s", outcome.subject_id, outcome.reason)
                known[line] = SummaryRow(outcome.subject_id, "failed",
                                         seconds=outcome.seconds or None,
                                         reason=outcome.reason)
                progress_state["failed"] += 1
            bar.update()
            bar.set_postfix(failed=progress_state["failed"], refresh=False)
            if time.monotonic() - progress_state["written"] >= _TABLES_EVERY_S:
                write_tables(out_dir, rows())
                progress_state["written"] = time.monotonic()

        write_tables(out_dir, rows())
        others = ", ".join(f"{n} {status}" for status in STATUSES[1:]
                           if (n := sum(row.status == status for row in known.values())))
        logger.info("fitting %d subjects on the %s engine%s", len(to_fit), engine.name,
                    f" ({others})" if others else "")
        bar = tqdm(total=len(to_fit), unit="subject", desc="fitter batch", file=sys.stderr,
                   disable=None if progress is None else not progress, dynamic_ncols=True)
        engine_start = time.time()
        try:
            engine.run([jobs[id_of[line]] for line in to_fit], report)
        finally:
            bar.close()
            result = BatchResult(rows(), list(write_tables(out_dir, rows())),
                                 time.perf_counter() - start)
            first_start = progress_state["first_start"]
            write_json(out_dir / BATCH_FILE, {
                "command": list(command),
                "version": bodyfit_version(),
                "subjects_table": str(table.path),
                "engine": engine.name,
                "workers": engine.workers,
                "started": started.isoformat(timespec="seconds"),
                "seconds": {
                    "total": round(result.seconds, 3),
                    "start_up": None if first_start is None else round(first_start
                                                                       - engine_start, 3),
                    "jobs": round(sum(row.seconds or 0.0 for row in result.rows
                                      if row.status in ("fitted", "failed")), 3)},
                "subjects": {status: result.count(status) for status in STATUSES},
            })
    return dataclasses.replace(result, written=[*result.written, out_dir / BATCH_FILE])
