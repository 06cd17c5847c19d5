"""One subject's job: what it is (:func:`subject_job`) and running it (:func:`run_subject`).

Every engine places jobs and calls :func:`run_subject` in a worker; nothing else decides
what a subject's fit is. A job is `fitter run` for one row of the subjects table: the
row's photos, stature, masks, camera, sex and weights, and the batch's options for all
the rest (:mod:`bodyfit.fitter.run.options`, as `fitter run` reads its own), every
subject with the batch's seed. Its outputs go to OUT/<id>/ exactly as `fitter run`
writes them (:func:`bodyfit.fitter.run.results.run_person`), moved into place in one rename, so
a worker killed at any moment leaves OUT/<id>/ complete or absent.
"""

from __future__ import annotations

import dataclasses
import logging
import os
import platform
import time
from collections.abc import Mapping
from pathlib import Path

from bodyfit.common.errors import UserError
from bodyfit.fitter.batch.subjects import SubjectRow
from bodyfit.fitter.fit.person import PersonInputs
from bodyfit.fitter.fit.person_fit import FitSettings
from bodyfit.fitter.model.body_model import BodyModel
from bodyfit.fitter.run.options import fit_settings
from bodyfit.fitter.run.results import run_person

__all__ = ["SubjectJob", "SubjectOutcome", "WORKER_EXIT_HOOK", "subject_job", "run_subject",
           "one_line"]

logger = logging.getLogger(__name__)

#: Test hook, not an option: a worker about to fit a subject this environment variable
#: names (comma-separated ids) exits at once with status 1, as a crashed or killed worker
#: would. An entry ``ID:PATH`` does so only while the file PATH does not exist (it creates
#: PATH before exiting), so the subject's second try succeeds.
WORKER_EXIT_HOOK = "BODYFIT_BATCH_TEST_EXIT"


@dataclasses.dataclass(frozen=True)
class SubjectJob:
    """One subject's fit, everything a worker needs (picklable, paths absolute).

    Attributes:
        subject_id: the subject's id; out_dir: OUT/<id>, where its results go.
        inputs: the person's inputs; settings: the fit's settings.
    """

    subject_id: str
    inputs: PersonInputs
    settings: FitSettings
    out_dir: Path


@dataclasses.dataclass(frozen=True)
class SubjectOutcome:
    """How a job ended.

    Attributes:
        subject_id: the job's subject.
        reason: why it failed, one line; "" when it was fitted.
        seconds: the job's wall seconds in its worker (photos to written results).
        started_at: when the worker started it, seconds since the epoch.
        worker: ``pid@host`` of the worker that ran it ("" when none did).
    """

    subject_id: str
    reason: str
    seconds: float
    started_at: float
    worker: str

    @property
    def fitted(self) -> bool:
        return not self.reason


def one_line(text: str) -> str:
    """``text`` with its lines joined by "; " (a reason must fit in one CSV cell and line)."""
    return "; ".join(line.strip() for line in str(text).splitlines() if line.strip()) or "?"


def subject_job(row: SubjectRow, base: FitSettings, options: Mapping[str, object],
                out_dir: Path) -> SubjectJob:
    """The job of one row: the row's inputs (its camera, background plates and sex, else
    the batch's ``options["camera"]``, ``options["background_front"]`` and
    ``["background_side"]``, and ``options["sex"]``; the batch's segmenter, photography
    check and ``--side-from``) and
    ``base`` with the batch's fit options (:func:`~bodyfit.fitter.run.options.fit_settings`),
    the row's weights replacing ``--weights`` (``--weight`` overrides still apply).

    Args:
        base: the method's or the run.json's settings
            (:func:`~bodyfit.fitter.run.options.base_settings`).
        options: the batch's options by argparse name, None when not given; paths
            absolute.
        out_dir: OUT, absolute.

    Raises:
        UserError: the row's weights file is malformed.
        ValueError: a bad matching or vertical anchor option.
    """
    given = row.inputs
    inputs = dataclasses.replace(
        given, camera=given.camera or options.get("camera"),
        background_front=given.background_front or options.get("background_front"),
        background_side=given.background_side or options.get("background_side"),
        segmenter=options.get("segmenter") or "auto",
        check=options.get("check") is not False,
        side_from=options.get("side_from") or "auto",
        sex=given.sex if given.sex != "unknown" else options.get("sex") or "unknown")
    if row.weights is not None:
        options = {**options, "weights": row.weights}
    return SubjectJob(row.subject_id, inputs, fit_settings(base, options),
                      Path(out_dir) / row.subject_id)


def _test_exit_hook(subject_id: str) -> None:
    """:data:`WORKER_EXIT_HOOK`."""
    for entry in filter(None, os.environ.get(WORKER_EXIT_HOOK, "").split(",")):
        name, _, marker = entry.partition(":")
        if name != subject_id:
            continue
        if marker:
            if Path(marker).exists():
                return
            Path(marker).touch()
        os._exit(1)


def run_subject(job: SubjectJob, model: BodyModel, device: str | None = None,
                threads: int | None = None) -> SubjectOutcome:
    """Fit one subject into ``job.out_dir``; never raises for the subject's own problems.

    Args:
        model: the body model, loaded once per worker.
        device: where this worker runs the kernels (an engine's placement, e.g. the GPU it
            was given); None: ``job.settings.device``.
        threads: the CPU threads this worker's fits score candidates on (its share of
            the machine's cores) when the job does not say (``--threads``); None: the
            fit's default, one per core. The result does not depend on it.

    Returns:
        The outcome: fitted, or the reason it failed (a bad photo, no person, any error,
        a crash's exception type and message; the traceback is logged).
    """
    started_at, start = time.time(), time.perf_counter()
    worker = f"{os.getpid()}@{platform.node()}"
    _test_exit_hook(job.subject_id)
    settings = dataclasses.replace(
        job.settings, device=device or job.settings.device,
        threads=job.settings.threads if job.settings.threads is not None else threads)
    try:
        run_person(model, job.inputs, settings, job.out_dir, progress=False)
        reason = ""
    except UserError as error:
        reason = one_line(error)
    except ValueError as error:  # the kernels' argument and device errors
        reason = one_line(error)
    except Exception as error:  # a crash must not stop the batch: it is the subject's reason
        logger.exception("%s: crashed", job.subject_id)
        reason = one_line(f"crashed: {type(error).__name__}: {error}")
    return SubjectOutcome(job.subject_id, reason, time.perf_counter() - start, started_at,
                          worker)
