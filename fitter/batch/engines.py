"""Where `fitter batch`'s jobs run: local worker processes (here) or Ray actors
(:mod:`bodyfit.fitter.batch.ray_engine`).

An engine only places jobs: every worker loads the body model once
(:func:`start_worker`) and runs each job it is given with
:func:`~bodyfit.fitter.batch.job.run_subject`, which turns every problem of a subject into
its outcome. What an engine adds is the one failure a worker cannot report itself: its own
death (a crash of the interpreter, the kernel's out-of-memory killer, ``kill -9``). A
subject whose worker died is tried again once, alone (:class:`WorkerDeaths`); if its
worker dies again it is recorded as failed, and the batch goes on.

The local engine is a :class:`concurrent.futures.ProcessPoolExecutor` whose workers are
started with "spawn" (a fresh interpreter, no state copied from the driver): a worker that
dies breaks the pool (:class:`~concurrent.futures.process.BrokenProcessPool`), its jobs in
flight are sorted as above, and a fresh pool takes over.
"""

from __future__ import annotations

import collections
import dataclasses
import logging
import multiprocessing
import os
import platform
import threading
import time
from collections.abc import Callable, Iterable
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool

from bodyfit.common.errors import UserError
from bodyfit.common.files import file_sha256
from bodyfit.fitter.batch.job import SubjectJob, SubjectOutcome, run_subject

__all__ = ["WorkerSetup", "WorkerDeaths", "LocalEngine", "local_pool", "run_local_job",
           "start_worker"]

logger = logging.getLogger(__name__)

#: How often a local worker checks that the batch that started it is still alive, seconds.
_PARENT_CHECK_S = 0.5


@dataclasses.dataclass(frozen=True)
class WorkerSetup:
    """What every worker is started with.

    Attributes:
        model_sha256: the driver's body model file's SHA-256; a worker that would load
            another model (another machine's cache) refuses to start, so that every
            subject is fitted with the same model.
        threads: the worker's share of the CPU cores: the threads its fits score
            candidates on (unless ``--threads`` says), and torch's and OpenCV's (None:
            their defaults; BLAS gets one in every fit, ``fitter.fit.fit_person``).
        log_level: the workers' logging level.
        devices: the kernels' devices the workers take in turn (worker i gets
            ``devices[i % len(devices)]``); empty: each job's own device.
    """

    model_sha256: str
    threads: int | None = None
    log_level: int = logging.WARNING
    devices: tuple[str, ...] = ()


def start_worker(setup: WorkerSetup):
    """Make this process a worker: quiet logging, thread counts, the body model loaded.

    Returns:
        The body model.

    Raises:
        UserError: the body model this worker would load is not the driver's.
    """
    logging.basicConfig(level=setup.log_level, format="%(message)s")
    logging.getLogger("bodyfit").setLevel(setup.log_level)
    from bodyfit.kernels.device import init_warp

    init_warp()  # Warp's banner, module loads and no-driver warning: errors only
    if setup.threads is not None:
        import cv2
        import torch

        torch.set_num_threads(setup.threads)
        cv2.setNumThreads(setup.threads)
    from bodyfit.fitter.model.cache import active_model_path, load_model

    path = active_model_path()
    if file_sha256(path) != setup.model_sha256:
        raise UserError(f"the worker on {platform.node()} would fit with the body model "
                        f"{path}, which is not the batch's; give every machine the same "
                        "model")
    return load_model()


class WorkerDeaths:
    """The rule for subjects whose worker died while fitting them: the first time, the
    subject is run again, alone (with several in flight, any of them may have killed the
    worker); the second time it is recorded as failed."""

    LIMIT = 2

    def __init__(self) -> None:
        self.counts: collections.Counter[str] = collections.Counter()

    def suspect(self, subject_id: str) -> bool:
        """Whether the subject was in flight when a worker died (it then runs alone)."""
        return self.counts[subject_id] > 0

    def died(self, job: SubjectJob, detail: str = "") -> SubjectOutcome | None:
        """Count a death of ``job``'s worker: None to run it again, or its failed outcome."""
        self.counts[job.subject_id] += 1
        if self.counts[job.subject_id] < self.LIMIT:
            return None
        return SubjectOutcome(job.subject_id,
                              f"its worker process died while fitting it, {self.LIMIT} times"
                              + (f" ({detail})" if detail else "") + "; a crash in native "
                              "code or the system out of memory?", 0.0, 0.0, "")


# --- the local engine's workers ------------------------------------------------------------

_worker_model = None
_worker_device = None
_worker_threads = None


def _watch_parent(parent_pid: int) -> None:
    """Exit when the batch that started this worker is gone (killed), rather than fit on."""
    while True:
        time.sleep(_PARENT_CHECK_S)
        if os.getppid() != parent_pid:
            os._exit(1)


def _init_local_worker(setup: WorkerSetup, counter, parent_pid: int) -> None:
    global _worker_model, _worker_device, _worker_threads
    threading.Thread(target=_watch_parent, args=(parent_pid,), daemon=True).start()
    if setup.devices:
        with counter.get_lock():
            index = counter.value
            counter.value += 1
        _worker_device = setup.devices[index % len(setup.devices)]
    _worker_threads = setup.threads
    _worker_model = start_worker(setup)


def run_local_job(job: SubjectJob) -> SubjectOutcome:
    """Run ``job`` in a worker of :func:`local_pool`."""
    return run_subject(job, _worker_model, _worker_device, _worker_threads)


def _local_worker_ready() -> int:
    return os.getpid()


def local_pool(workers: int, setup: WorkerSetup) -> ProcessPoolExecutor:
    """``workers`` worker processes, started with "spawn", each with the body model loaded
    (:func:`start_worker`): submit :func:`run_local_job` to them."""
    context = multiprocessing.get_context("spawn")
    counter = context.Value("i", 0) if setup.devices else None
    return ProcessPoolExecutor(workers, context, initializer=_init_local_worker,
                               initargs=(setup, counter, os.getpid()))


class LocalEngine:
    """``workers`` worker processes on this machine (module docstring)."""

    name = "local"

    def __init__(self, workers: int, setup: WorkerSetup):
        if workers < 1:
            raise UserError(f"--workers must be at least 1, got {workers}")
        self.workers, self.setup = workers, setup

    def run(self, jobs: Iterable[SubjectJob], report: Callable[[SubjectOutcome], None]) -> None:
        """Run every job, calling ``report`` with each outcome as it comes (in the order
        they finish); returns when every job has an outcome.

        Raises:
            UserError: the workers cannot start (not a subject's failure: it would fail
                every subject).
        """
        self._run(collections.deque(jobs), WorkerDeaths(), report)

    def _run(self, queue, deaths: WorkerDeaths, report) -> None:
        while queue:
            pool = local_pool(self.workers, self.setup)
            try:
                try:
                    pool.submit(_local_worker_ready).result()
                except BrokenProcessPool:
                    raise UserError("the local worker processes could not start (see the "
                                    "messages above)") from None
                self._drain(pool, queue, deaths, report)
            except BaseException:  # KeyboardInterrupt too: stop the fits in flight now
                _stop_workers(pool)
                raise
            finally:
                pool.shutdown(wait=True, cancel_futures=True)

    def _drain(self, pool, queue, deaths: WorkerDeaths, report) -> None:
        """Run jobs from ``queue`` on ``pool`` until it is empty or the pool breaks (a
        worker died; the jobs to try again are back at the queue's head)."""
        in_flight = {}
        while queue or in_flight:
            broken = False
            while queue and len(in_flight) < self.workers:
                alone = deaths.suspect(queue[0].subject_id)
                if in_flight and (alone or any(deaths.suspect(job.subject_id)
                                               for job in in_flight.values())):
                    break  # a suspect runs alone
                job = queue.popleft()
                try:
                    in_flight[pool.submit(run_local_job, job)] = job
                except BrokenProcessPool:  # a worker died since the last wait: the job
                    queue.appendleft(job)  # waits, the futures in flight say who died
                    broken = True
                    break
            done, _ = wait(in_flight, return_when=FIRST_COMPLETED)
            if broken or any(isinstance(future.exception(), BrokenProcessPool)
                             for future in done):
                wait(in_flight)  # a broken pool fails every future in flight at once
                again = []
                for future, job in in_flight.items():
                    if future.exception() is None:
                        report(future.result())
                        continue
                    if not isinstance(future.exception(), BrokenProcessPool):
                        raise future.exception()
                    outcome = deaths.died(job)
                    if outcome is None:
                        again.append(job)
                    else:
                        report(outcome)
                logger.warning("a worker died with %s in flight; %s",
                               ", ".join(job.subject_id for job in in_flight.values()),
                               f"trying {', '.join(j.subject_id for j in again)} again alone"
                               if again else "no subject left to try again")
                queue.extendleft(reversed(again))
                return
            for future in done:
                job = in_flight.pop(future)
                report(future.result())  # a worker's own exception here is a bodyfit bug


def _stop_workers(pool: ProcessPoolExecutor) -> None:
    """Terminate the pool's worker processes (Python 3.14 has a method for it)."""
    if hasattr(pool, "terminate_workers"):
        pool.terminate_workers()
        return
    for process in list(getattr(pool, "_processes", {}).values()):
        process.terminate()
