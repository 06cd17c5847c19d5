"""Scoring whole populations against the person's views: the kernels' entry point.

    model = ModelArrays.from_body_model(load_model(), num_components=20, device="cpu")
    views = [prepare_view_target("front", front_mask, front_camera, mm_per_px), ...]
    evaluator = PopulationEvaluator(model, views, CostSettings())
    costs, part_costs = evaluator.evaluate(betas, pose_deg)     # every generation

For each chunk of candidates: skin once per distinct view pose (once, unless a view fixes
some pose angles, ``ViewTarget.fixed_pose_deg``, e.g. a side view with the arms down);
then per view: project, rasterise into label maps, row-scan the boundaries, align to the person, match the boundaries, and add the
view's weighted terms. The optimiser never sees the kernels: it asks for a population,
the caller evaluates it here, and tells the optimiser the costs.
"""

from __future__ import annotations

import os
import time
import weakref
from concurrent.futures import ThreadPoolExecutor
from typing import NamedTuple, Sequence

import numpy as np
import warp as wp

from bodyfit.kernels import alignment, boundary, cost, raster, skinning
from bodyfit.kernels.body_layout import POSE_NAMES
from bodyfit.kernels.alignment import launch_alignment
from bodyfit.kernels.boundary import BoundaryRuns, allocate_runs, launch_nearest, launch_row_scan
from bodyfit.kernels.cost import (TERM_NAMES, CostSettings, PartVector, cost_params,
                                  launch_model_to_person, launch_view_cost)
from bodyfit.kernels.device import device_array
from bodyfit.kernels.raster import launch_projection, launch_raster
from bodyfit.kernels.skinning import ModelArrays, launch_skinning
from bodyfit.kernels.target import ViewTarget, visible_faces

__all__ = ["STAGES", "PopulationCost", "PopulationEvaluator", "cpu_threads", "evaluate_population"]

#: Stages timed by ``PopulationEvaluator(profile=True)``.
STAGES = ("skin", "raster", "distance", "cost")

#: Candidates per kernel launch: tens on a CPU (bounded memory, maps near the cache),
#: thousands on a GPU (enough threads to fill it).
DEFAULT_CHUNK = {"cpu": 32, "cuda": 4096}
#: The modules whose kernels an evaluation launches (loaded up front for threads).
_KERNEL_MODULES = (skinning, raster, boundary, alignment, cost)


class PopulationCost(NamedTuple):
    """Costs of a population.

    Attributes:
        costs: (P,) float32, weighted millimetres (Eq. 17); +inf for a candidate whose
            silhouette is empty in a view.
        part_costs: (P, 12) float32, the terms in ``TERM_NAMES`` order (ten parts, top,
            bottom), summed over the views with their weights; rows sum to ``costs``.
    """

    costs: np.ndarray
    part_costs: np.ndarray


class _ViewData:
    """A view's constant device data, shared by every workspace."""

    def __init__(self, view: ViewTarget, model: ModelArrays, settings: CostSettings):
        dev = model.device
        faces, face_parts = visible_faces(model.faces, model.face_parts, view.visible_parts)
        self.view = view
        self.faces = wp.array(faces, dtype=wp.vec3i, device=dev)
        self.face_parts = wp.array(face_parts.astype(np.int32), dtype=wp.int32, device=dev)
        self.params = cost_params(settings, view.name, view.millimetres_per_pixel)
        self.moments = view.moments.to_warp()


class _ViewBuffers:
    """One view's per-chunk buffers for chunks of up to ``chunk`` candidates."""

    def __init__(self, data: _ViewData, num_vertices: int, chunk: int):
        view, dev = data.view, data.faces.device
        num_points = view.boundary_points.shape[0]
        size = (chunk, view.height, view.width)
        self.data = data
        self.screen = wp.empty((chunk, num_vertices), dtype=wp.vec3, device=dev)
        self.keys = wp.empty(size, dtype=wp.int32, device=dev)
        self.scan = allocate_runs(*size, dev)
        self.transforms = wp.empty(chunk, dtype=wp.mat33, device=dev)
        self.extremes = wp.empty((chunk, 2), dtype=wp.vec2, device=dev)
        self.areas = wp.empty(chunk, dtype=wp.float32, device=dev)
        self.distances = wp.empty((chunk, num_points), dtype=wp.float32, device=dev)
        self.parts = wp.empty((chunk, num_points), dtype=wp.int32, device=dev)
        self.row_sums = wp.empty((chunk, view.height), dtype=PartVector, device=dev)
        self.row_pixels = wp.empty((chunk, view.height), dtype=wp.int32, device=dev)

    def arrays(self) -> list[wp.array]:
        return [v for v in (*vars(self).values(), *vars(self.scan).values())
                if isinstance(v, wp.array)]

    def scan_rows(self, num: int) -> BoundaryRuns:
        return BoundaryRuns(self.scan.runs[:num], self.scan.run_counts[:num],
                            self.scan.row_moments[:num])


class _Workspace:
    """Every buffer one thread needs to evaluate chunks of up to ``capacity`` candidates:
    the skinned bodies, the costs, and each view's buffers (``pose_groups``: the views'
    data grouped by their fixed pose angles, in the evaluator's order)."""

    def __init__(self, model: ModelArrays, pose_groups: dict[tuple, list[_ViewData]],
                 capacity: int):
        dev = model.device
        self.capacity = capacity
        self.joints = wp.empty((capacity, len(POSE_NAMES)), dtype=wp.vec3, device=dev)
        self.rotations = wp.empty((capacity, len(POSE_NAMES)), dtype=wp.mat33, device=dev)
        self.vertices = wp.empty((capacity, model.num_vertices), dtype=wp.vec3, device=dev)
        self.term_costs = wp.empty((capacity, len(TERM_NAMES)), dtype=wp.float32, device=dev)
        self.costs = wp.empty(capacity, dtype=wp.float32, device=dev)
        self.pose_groups = {fixed: [_ViewBuffers(d, model.num_vertices, capacity) for d in views]
                            for fixed, views in pose_groups.items()}

    def arrays(self) -> list[wp.array]:
        arrays = [v for v in vars(self).values() if isinstance(v, wp.array)]
        return arrays + [a for views in self.pose_groups.values() for b in views
                         for a in b.arrays()]


def cpu_threads() -> int:
    """The CPU cores this process may run on (the default number of CPU workers)."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


class PopulationEvaluator:
    """Evaluates populations of (betas, pose) against one person's views.

    Device buffers are allocated by the first :meth:`evaluate` (for min(P, chunk size)
    candidates), grown if a later population needs more, and otherwise reused.

    On a CPU the population is cut into ``workers`` contiguous slices, each evaluated
    chunk by chunk on its own Python thread with its own buffers (Warp runs a CPU kernel
    in the calling thread and releases the GIL while it runs, so the slices run on
    separate cores). Every candidate is evaluated on its own, so the costs do not depend
    on the number of workers or the chunk size. On a GPU the chunks run one after
    another on the device.

    Args:
        model: the body model on the device the views were prepared for.
        views: one :class:`ViewTarget` per view (``"front"`` and/or ``"side"``, each once).
        settings: weights and matching choices.
        chunk_size: candidates per launch (default ``DEFAULT_CHUNK`` for the device).
        workers: CPU threads (default: one per core this process may use,
            :func:`cpu_threads`); 1 on a GPU and with ``profile``.
        profile: synchronise after every stage and add its time to ``stage_seconds``
            (slower; for the benchmark; one worker): the process's CPU time on a CPU
            device (other jobs on a shared machine do not count; Warp runs CPU kernels in
            the calling thread), wall time on a GPU.

    Raises:
        ValueError: no view, a repeated view name, views on another device, a chunk
            size or a number of workers < 1.
    """

    def __init__(self, model: ModelArrays, views: Sequence[ViewTarget],
                 settings: CostSettings = CostSettings(), chunk_size: int | None = None,
                 workers: int | None = None, profile: bool = False):
        names = [v.name for v in views]
        if not views or len(set(names)) != len(names):
            raise ValueError(f"views must be one or more distinct views, got {names}")
        for view in views:
            if view.boundary_points.device != model.device:
                raise ValueError(f"view {view.name!r} was prepared on "
                                 f"{view.boundary_points.device}, the model is on {model.device}")
        chunk = chunk_size or DEFAULT_CHUNK["cuda" if model.device.is_cuda else "cpu"]
        if chunk < 1:
            raise ValueError(f"chunk_size must be >= 1, got {chunk}")
        if workers is not None and workers < 1:
            raise ValueError(f"workers must be >= 1, got {workers}")
        self.model = model
        self.settings = settings
        self.chunk_size = chunk
        self.profile = profile
        self.workers = 1 if model.device.is_cuda or profile else (workers or cpu_threads())
        self.stage_seconds = dict.fromkeys(STAGES, 0.0)
        #: the views by their ``fixed_pose_deg``: one skinning per chunk for each group
        self._pose_groups: dict[tuple, list[_ViewData]] = {}
        for view in views:
            self._pose_groups.setdefault(view.fixed_pose_deg, []).append(
                _ViewData(view, model, settings))
        self._workspaces: list[_Workspace] = []
        self._pool: ThreadPoolExecutor | None = None  # started by the first threaded call
        self._timer = time.perf_counter if model.device.is_cuda else time.process_time
        self._clock = 0.0
        if self.workers > 1:  # Warp's module loading is not for concurrent threads
            for module in _KERNEL_MODULES:
                wp.load_module(module, device=model.device)

    def replace_view(self, view: ViewTarget) -> None:
        """Score the next populations against ``view`` in place of the view of its name
        that differs from it only in its camera and ``millimetres_per_pixel`` (the person
        placed anew); the canvas and everything computed from the person stay."""
        for group in self._pose_groups.values():
            for data in group:
                if data.view.name == view.name:
                    data.view = view
                    data.params = cost_params(self.settings, view.name,
                                              view.millimetres_per_pixel)
                    return
        raise ValueError(f"this evaluator has no view {view.name!r}")

    def buffer_bytes(self) -> int:
        """Bytes of device memory held by this evaluator (model data excluded)."""
        return sum(a.capacity for space in self._workspaces for a in space.arrays())

    def _stage_done(self, stage: str) -> None:
        if self.profile:
            wp.synchronize_device(self.model.device)
            now = self._timer()
            self.stage_seconds[stage] += now - self._clock
            self._clock = now

    def evaluate(self, betas, pose_deg) -> PopulationCost:
        """Costs and per-term costs of P candidates.

        Args:
            betas: (P, K) float, shape coefficients in units of standard deviation.
            pose_deg: (P, 4) float, abduction angles in degrees, ``POSE_NAMES`` order.

        Raises:
            ValueError: wrong shapes or dtypes.
        """
        dev = self.model.device
        dims = {"K": self.model.num_components}
        betas = device_array("betas", betas, ("P", "K"), dims, "float", wp.float32, dev)
        pose_deg = device_array("pose_deg", pose_deg, ("P", len(POSE_NAMES)), dims, "float",
                                wp.float32, dev)
        total = dims["P"]
        workers = min(self.workers, total)
        per_worker = -(-total // workers)
        capacity = min(per_worker, self.chunk_size)
        if len(self._workspaces) < workers or self._workspaces[0].capacity < capacity:
            self._workspaces = [_Workspace(self.model, self._pose_groups, capacity)
                                for _ in range(workers)]
        costs = np.empty(total, np.float32)
        part_costs = np.empty((total, len(TERM_NAMES)), np.float32)

        def evaluate_slice(space: _Workspace, start: int, stop: int) -> None:
            for first in range(start, stop, capacity):
                last = min(first + capacity, stop)
                costs[first:last], part_costs[first:last] = self._evaluate_chunk(
                    space, betas[first:last], pose_deg[first:last])

        slices = [(space, i * per_worker, min((i + 1) * per_worker, total))
                  for i, space in enumerate(self._workspaces[:workers])]
        if workers == 1:
            evaluate_slice(*slices[0])
        else:
            if self._pool is None:  # its idle threads end with the evaluator
                self._pool = ThreadPoolExecutor(self.workers, "bodyfit-evaluator")
                weakref.finalize(self, self._pool.shutdown, wait=False)
            for done in [self._pool.submit(evaluate_slice, *s) for s in slices]:
                done.result()
        return PopulationCost(costs, part_costs)

    def evaluate_posed(self, posed: dict[str, np.ndarray]) -> PopulationCost:
        """Costs and per-term costs of P candidates given as posed bodies: view name ->
        (P, V, 3) float metres, each body as that view shows it (for poses the kernels'
        rig cannot make, such as bent elbows); scored in one chunk by one worker.

        Raises:
            ValueError: a view missing, or bodies of another shape than (P, V, 3).
        """
        names = {data.view.name for views in self._pose_groups.values() for data in views}
        if set(posed) != names:
            raise ValueError(f"posed bodies are needed for the views {sorted(names)}, "
                             f"got {sorted(posed)}")
        shapes = {np.shape(bodies) for bodies in posed.values()}
        count = len(next(iter(posed.values())))
        if shapes != {(count, self.model.num_vertices, 3)}:
            raise ValueError(f"posed bodies must be (P, {self.model.num_vertices}, 3), "
                             f"got {sorted(shapes)}")
        if not self._workspaces:
            self._workspaces.append(_Workspace(self.model, self._pose_groups, count))
        elif self._workspaces[0].capacity < count:  # the others keep theirs
            self._workspaces[0] = _Workspace(self.model, self._pose_groups, count)
        space = self._workspaces[0]
        self._clock = self._timer()
        term_costs, costs = space.term_costs[:count], space.costs[:count]
        term_costs.zero_()
        costs.zero_()
        vertices = space.vertices[:count]
        for views in space.pose_groups.values():
            for buffers in views:
                vertices.assign(wp.array(np.asarray(posed[buffers.data.view.name], np.float32),
                                         dtype=wp.vec3, device=self.model.device))
                self._evaluate_view(buffers, vertices, term_costs, costs)
        return PopulationCost(costs.numpy().copy(), term_costs.numpy().copy())

    def _evaluate_chunk(self, space: _Workspace, betas: wp.array, pose_deg: wp.array):
        num = betas.shape[0]
        self._clock = self._timer()
        term_costs, costs = space.term_costs[:num], space.costs[:num]
        term_costs.zero_()
        costs.zero_()
        vertices = space.vertices[:num]  # each pose group's views are done with it in turn
        for fixed, views in space.pose_groups.items():
            launch_skinning(self.model, betas, pose_deg, space.joints[:num],
                            space.rotations[:num], vertices, fixed)
            self._stage_done("skin")
            for buffers in views:
                self._evaluate_view(buffers, vertices, term_costs, costs)
        out = costs.numpy(), term_costs.numpy()
        self._stage_done("cost")
        return out

    def _evaluate_view(self, buffers: _ViewBuffers, vertices: wp.array, term_costs: wp.array,
                       costs: wp.array) -> None:
        num = vertices.shape[0]
        data = buffers.data
        view = data.view
        screen, keys = buffers.screen[:num], buffers.keys[:num]
        launch_projection(view.camera, vertices, screen)
        launch_raster(view.camera, screen, data.faces, data.face_parts, keys)
        self._stage_done("raster")
        scan = buffers.scan_rows(num)
        transforms, extremes = buffers.transforms[:num], buffers.extremes[:num]
        areas, distances, parts = buffers.areas[:num], buffers.distances[:num], buffers.parts[:num]
        row_sums, row_pixels = buffers.row_sums[:num], buffers.row_pixels[:num]
        launch_row_scan(keys, scan)
        launch_alignment(scan.row_moments, data.moments, self.settings.align_rotation,
                         transforms, extremes, areas, self.settings.vertical_anchor)
        if data.params.person_to_model > 0:
            launch_nearest(scan, view.boundary_points, transforms, distances, parts)
        if data.params.model_to_person > 0:
            launch_model_to_person(scan.runs, scan.run_counts, transforms, view.boundary_distance,
                                   row_sums, row_pixels)
        self._stage_done("distance")
        launch_view_cost(data.params, data.moments, distances, parts, row_sums, row_pixels,
                         transforms, extremes, areas, term_costs, costs)
        self._stage_done("cost")


def evaluate_population(model: ModelArrays, views: Sequence[ViewTarget], betas, pose_deg,
                        settings: CostSettings = CostSettings()) -> PopulationCost:
    """One-off :meth:`PopulationEvaluator.evaluate` (an optimiser loop should keep one
    :class:`PopulationEvaluator` and call it every generation).

    Args:
        model: the body model on the views' device.
        views: the person's prepared views.
        betas: (P, K) float, units of sigma.
        pose_deg: (P, 4) float, degrees, ``POSE_NAMES`` order.
        settings: weights and matching choices.

    Returns:
        ``PopulationCost(costs (P,), part_costs (P, 12))``.
    """
    return PopulationEvaluator(model, views, settings).evaluate(betas, pose_deg)
