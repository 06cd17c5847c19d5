"""The studio's fits, queued onto worker processes, one per core.

A fit asked for is a row of the store (:mod:`.store`) and a folder, DATA/fits/<fit id>/,
holding the two photos as stored (:mod:`.uploads`), fitted through the registered camera
it names or else the photos' EXIF focal length; its outputs go to its ``result/``
exactly as `fitter run` writes them, by `fitter batch`'s workers
(:func:`bodyfit.fitter.batch.engines.local_pool`). The fit runs in the server, not in the
browser's request: a client that goes away loses nothing, and a server started again fits
what was queued or fitting when it stopped.

The pool runs fits in the order asked; the first ``workers`` unfinished ones are fitting.
A worker that dies fails the fits it may have been running, not the others.
"""

from __future__ import annotations

import dataclasses
import json
import statistics
import threading
import time
from concurrent.futures.process import BrokenProcessPool
from pathlib import Path

from bodyfit.fitter.batch.engines import WorkerSetup, local_pool, run_local_job
from bodyfit.fitter.batch.job import SubjectJob, SubjectOutcome
from bodyfit.fitter.fit.person import PersonInputs
from bodyfit.fitter.fit.person_fit import METHODS
from bodyfit.fitter.serve.pages import as_fields
from bodyfit.fitter.serve.store import FitRecord, Store

__all__ = ["FIRST_FIT_S", "FitQueue", "FitProgress", "camera_file", "fit_folder", "RESULT"]

#: The wall seconds a fit is expected to take before the studio has fitted anyone: one
#: core's fit of the default method (two cores: about 20 s).
FIRST_FIT_S = 40.0
#: The done fits whose median time predicts the next one's.
_RECENT = 10
RESULT = "result"


def fit_folder(data: Path, fit_id: int) -> Path:
    """DATA/fits/<fit id>/: the fit's photos (front.jpg, side.jpg) and its result/."""
    return Path(data) / "fits" / str(int(fit_id))


def camera_file(data: Path, camera_id: int) -> Path:
    """DATA/cameras/<camera id>/camera.json: a registered camera's `calib capture` file."""
    return Path(data) / "cameras" / str(int(camera_id)) / "camera.json"


@dataclasses.dataclass(frozen=True)
class FitProgress:
    """Where a fit stands: its ``state`` (:data:`~bodyfit.fitter.serve.store.FIT_STATES`),
    ``ahead`` (fits before it in the queue), ``elapsed_s`` (fitting for) and ``left_s``
    (the time left, from the studio's recent fits; 0 when overdue)."""

    state: str
    ahead: int = 0
    elapsed_s: float = 0.0
    left_s: float = 0.0

    def as_json(self) -> dict:
        return {"state": self.state, "ahead": self.ahead, "elapsed_s": round(self.elapsed_s, 1),
                "left_s": round(self.left_s, 1)}


class FitQueue:
    """Fits of ``store`` run on ``workers`` processes (module docstring)."""

    def __init__(self, store: Store, data: Path, workers: int, setup: WorkerSetup):
        self.store, self.data, self.workers = store, Path(data), workers
        self._setup = WorkerSetup(setup.model_sha256, threads=1, log_level=setup.log_level)
        self._pool = local_pool(workers, self._setup)
        self._jobs: dict[int, SubjectJob] = {}
        self._lock = threading.RLock()  # a done job's callback may run inside _place
        self._pending: list[int] = []  # asked-for order, unfinished
        self._began: dict[int, float] = {}
        self._lost: set[int] = set()  # fitting when their pool broke
        for record in store.fits(states=("queued", "fitting")):
            self.submit(record)

    def submit(self, record: FitRecord) -> None:
        """Queue the fit of ``record`` (its photos in :func:`fit_folder`)."""
        folder = fit_folder(self.data, record.fit_id)
        if (folder / RESULT / "measurements.json").exists():  # done before a stop
            self._finished(record.fit_id, SubjectOutcome(str(record.fit_id), "", 0.0, 0.0, ""))
            return
        camera = None if record.camera is None else str(camera_file(self.data, record.camera))
        inputs = PersonInputs(str(folder / "front.jpg"), str(folder / "side.jpg"),
                              record.height_cm, camera, sex=record.sex, mass_kg=record.mass_kg)
        job = SubjectJob(str(record.fit_id), inputs, METHODS["bodyfit"], folder / RESULT)
        with self._lock:
            self._pending.append(record.fit_id)
            self._jobs[record.fit_id] = job
            self._advance()
            self._place(record.fit_id)

    def _place(self, fit_id: int) -> None:
        """Give the fit's job to the pool (lock held)."""
        pool = self._pool
        future = pool.submit(run_local_job, self._jobs[fit_id])
        future.add_done_callback(lambda f: self._done(fit_id, f, pool))

    def _advance(self) -> None:
        """Mark the first ``workers`` pending fits as fitting (lock held)."""
        for fit_id in self._pending[:self.workers]:
            if fit_id not in self._began:
                self._began[fit_id] = time.time()
                self.store.set_state(fit_id, "fitting")

    def _done(self, fit_id: int, future, pool) -> None:
        """A job's end. A worker that died (a crash, the system out of memory) breaks its
        pool: a fresh pool takes the fits that were waiting, and those that were fitting
        fail (any of them may have killed it)."""
        if future.cancelled():
            return  # the server stops: fitted again at the next start
        error = future.exception()
        if isinstance(error, BrokenProcessPool):
            with self._lock:
                if pool is self._pool:  # the first of its jobs to tell
                    self._pool = local_pool(self.workers, self._setup)
                    self._lost = set(self._began)
                if fit_id not in self._lost:
                    self._place(fit_id)
                    return
                self._lost.discard(fit_id)
            error = "its worker process died while fitting it (a crash, or the computer " \
                    "out of memory)"
        outcome = (future.result() if error is None else
                   SubjectOutcome(str(fit_id), f"the fit failed: {error}; measure again",
                                  0.0, 0.0, ""))
        self._finished(fit_id, outcome)

    def _finished(self, fit_id: int, outcome: SubjectOutcome) -> None:
        result = fit_folder(self.data, fit_id) / RESULT
        if outcome.fitted:
            measured = json.loads((result / "measurements.json").read_text())["measurements"]
            self.store.set_state(fit_id, "done", seconds=outcome.seconds or None,
                                 measurements=measured)
        else:
            self.store.set_state(fit_id, "failed", as_fields(outcome.reason))
        with self._lock:
            if fit_id in self._pending:
                self._pending.remove(fit_id)
            self._began.pop(fit_id, None)
            self._jobs.pop(fit_id, None)
            self._advance()

    def typical_s(self) -> float:
        """The median wall seconds of the studio's recent fits (:data:`FIRST_FIT_S` before
        any)."""
        seconds = [r.seconds for r in self.store.fits(states=("done",)) if r.seconds]
        return statistics.median(seconds[-_RECENT:]) if seconds else FIRST_FIT_S

    def progress(self, record: FitRecord) -> FitProgress:
        if record.state in ("done", "failed"):
            return FitProgress(record.state)
        typical = self.typical_s()
        with self._lock:
            if record.fit_id not in self._pending:
                return FitProgress(record.state)
            ahead = self._pending.index(record.fit_id)
            began = self._began.get(record.fit_id)
        if began is None:  # waits for a worker: the fits ahead of it, shared by the workers
            rounds = (ahead - self.workers) // self.workers + 1
            return FitProgress("queued", ahead, 0.0, typical * (rounds + 1))
        elapsed = time.time() - began
        return FitProgress("fitting", ahead, elapsed, max(typical - elapsed, 0.0))

    def close(self) -> None:
        """Stop the workers (fits in flight are fitted again at the next start)."""
        self._pool.shutdown(wait=False, cancel_futures=True)
