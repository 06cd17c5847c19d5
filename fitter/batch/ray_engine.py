"""The Ray engine of `fitter batch` (``--ray``, ``--ray-address``): jobs on Ray actors.

Ray is an optional extra (``pip install 'bodyfit[ray]'``), imported only here and only
when the engine starts. Each worker is an actor (:class:`SubjectWorker`) that loads the
body model (and compiles or loads the kernels) once and then fits subject after subject,
one at a time, with the same :func:`~bodyfit.fitter.batch.job.run_subject` as the local
engine. Each actor reserves ``cpus_per_worker`` CPUs and, for ``--device cuda``,
``gpus_per_worker`` GPUs (a fraction lets several workers share one GPU; Ray makes the
GPU it gives an actor its ``cuda:0``).

Without an address the engine starts a Ray instance on this machine (or uses the one
this process has started already) and stops it at the end; with one it joins that
cluster. On a cluster the subjects' files and OUT must lie on a file system every node
sees at the same path, and every node needs bodyfit and the same body model (a worker
whose model differs refuses to start). An actor that dies (a crash, the node lost) fails
its subject's task with ``RayActorError``: the subject is tried again once on a fresh
actor (:class:`~bodyfit.fitter.batch.engines.WorkerDeaths`).
"""

from __future__ import annotations

import collections
import dataclasses
import logging
import math
from collections.abc import Callable, Iterable

from bodyfit.common.errors import UserError
from bodyfit.fitter.batch.engines import WorkerDeaths, WorkerSetup, start_worker
from bodyfit.fitter.batch.job import SubjectJob, SubjectOutcome, one_line, run_subject

__all__ = ["RayEngine", "SubjectWorker", "import_ray"]

logger = logging.getLogger(__name__)


def import_ray():
    """The ``ray`` module, or UserError saying how to install it."""
    try:
        import ray
    except ImportError:
        raise UserError("--ray needs Ray, an optional extra: pip install 'bodyfit[ray]' (in "
                        "a checkout: pip install -e '.[ray]')") from None
    return ray


class SubjectWorker:
    """A Ray actor's state: the body model, loaded once, the device it fits on and its
    threads (its reserved CPUs)."""

    def __init__(self, setup: WorkerSetup):
        self.model = start_worker(setup)
        self.device = setup.devices[0] if setup.devices else None
        self.threads = setup.threads

    def ready(self) -> bool:
        return True

    def run(self, job: SubjectJob) -> SubjectOutcome:
        return run_subject(job, self.model, self.device, self.threads)


class RayEngine:
    """Jobs on Ray actors (module docstring).

    Args:
        address: a cluster's address (``ray.init(address=...)``), or None for a local
            instance.
        workers: actors (None: as many as the cluster's CPUs, or GPUs with a cuda device,
            hold, and no more than there are jobs).
        setup: the workers' setup (its devices are replaced: an actor with a GPU uses
            ``cuda:0``, the one Ray gives it).
        cpus_per_worker, gpus_per_worker: what Ray reserves per actor.
    """

    name = "ray"

    def __init__(self, address: str | None, workers: int | None, setup: WorkerSetup,
                 cpus_per_worker: float = 1.0, gpus_per_worker: float = 0.0):
        if workers is not None and workers < 1:
            raise UserError(f"--workers must be at least 1, got {workers}")
        if cpus_per_worker <= 0 or gpus_per_worker < 0:
            raise UserError("--cpus-per-worker must be > 0 and --gpus-per-worker >= 0")
        self.address, self.workers, self.setup = address, workers, setup
        self.cpus_per_worker, self.gpus_per_worker = cpus_per_worker, gpus_per_worker
        self._ray = import_ray()
        self._started_ray = False
        self._actor_class = None

    def _connect(self):
        ray = self._ray
        if ray.is_initialized():
            return ray
        options = {"logging_level": logging.ERROR, "log_to_driver": False}
        if self.address is None:
            options["include_dashboard"] = False
        try:
            ray.init(address=self.address, **options)
        except (ConnectionError, ValueError, RuntimeError) as error:
            raise UserError(f"cannot start or join Ray ({self.address or 'local'}): "
                            f"{one_line(error)}") from None
        self._started_ray = True
        return ray

    def _worker_count(self, ray, jobs: int) -> int:
        if self.workers is not None:
            return self.workers
        resources = ray.cluster_resources()
        if self.gpus_per_worker > 0:
            fit = math.floor(resources.get("GPU", 0) / self.gpus_per_worker + 1e-9)
            if fit < 1:
                raise UserError(f"the Ray cluster has {resources.get('GPU', 0):g} GPUs, less "
                                f"than --gpus-per-worker {self.gpus_per_worker:g}")
        else:
            fit = math.floor(resources.get("CPU", 0) / self.cpus_per_worker + 1e-9)
        return max(1, min(fit, jobs))

    def run(self, jobs: Iterable[SubjectJob], report: Callable[[SubjectOutcome], None]) -> None:
        """Run every job, calling ``report`` with each outcome as it comes; returns when
        every job has an outcome (Ray stopped again if this engine started it).

        Raises:
            UserError: Ray cannot start or be joined, or its workers cannot start.
        """
        queue = collections.deque(jobs)
        if not queue:
            return
        ray = self._connect()
        try:
            self._run(ray, queue, report)
        finally:
            if self._started_ray:
                ray.shutdown()

    def _new_actor(self, ray):
        setup = self.setup
        if self.gpus_per_worker > 0:
            setup = dataclasses.replace(setup, devices=("cuda:0",))
        if self._actor_class is None:
            self._actor_class = ray.remote(SubjectWorker).options(
                num_cpus=self.cpus_per_worker, num_gpus=self.gpus_per_worker)
        return self._actor_class.remote(setup)

    def _run(self, ray, queue: collections.deque, report) -> None:
        self.workers = count = self._worker_count(ray, len(queue))
        actors = [self._new_actor(ray) for _ in range(count)]
        try:
            ray.get([actor.ready.remote() for actor in actors])
        except ray.exceptions.RayError as error:
            raise UserError(f"the Ray workers could not start: {_cause(error)}") from None
        logger.info("%d Ray workers ready", count)
        deaths, idle, in_flight = WorkerDeaths(), list(actors), {}
        while queue or in_flight:
            while queue and idle:
                actor, job = idle.pop(), queue.popleft()
                in_flight[actor.run.remote(job)] = (actor, job)
            (ref,), _ = ray.wait(list(in_flight), num_returns=1)
            actor, job = in_flight.pop(ref)
            try:
                report(ray.get(ref))
                idle.append(actor)
            except ray.exceptions.RayActorError as error:
                ray.kill(actor)
                idle.append(self._new_actor(ray))
                outcome = deaths.died(job, _cause(error))
                if outcome is None:
                    logger.warning("%s: its Ray worker died; trying it again", job.subject_id)
                    queue.appendleft(job)
                else:
                    report(outcome)
            except ray.exceptions.RayError as error:  # e.g. the job could not be sent
                idle.append(actor)
                report(SubjectOutcome(job.subject_id, f"Ray: {_cause(error)}", 0.0, 0.0, ""))


def _cause(error: Exception) -> str:
    """The last line of a Ray error's message: its cause, without Ray's traceback."""
    lines = [line.strip() for line in str(error).splitlines() if line.strip()]
    return lines[-1][:300] if lines else type(error).__name__
