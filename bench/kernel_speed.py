"""Benchmark of the Warp kernels: candidate-views per second, per stage and in total.

    python -m bench.kernel_speed                      # CPU, P = 30, 256, 1024, 512 px
    python -m bench.kernel_speed --device cuda:0 --populations 30 256 1024 4096 16384
    python -m bench.kernel_speed --populations 30 --render-cell-mm 8   # the fitter's mesh

A synthetic person (a body of the model) is photographed front and side by the
orthographic paper cameras at the given image height; populations are drawn like the
GA's first generation (betas uniform in +-3 sigma, angles in 0-30 degrees) and, for the
total only, like a late generation (within 0.3 sigma and 3 degrees of the person). The
candidates are the full model's, or with ``--render-cell-mm`` the lighter mesh the fitter
renders (bodyfit.fitter.fit.render_mesh; the person's photos stay the full model's). The
same run times the NumPy/OpenCV reference pipeline (bodyfit.kernels.reference) on a few
candidates of the first population and checks the nearest-boundary distances against
scipy.ndimage.distance_transform_edt. Prints Markdown (docs/kernels.md holds the output).
"""

from __future__ import annotations

import argparse
import os
import platform
import resource
import sys
import time

import numpy as np
import scipy.ndimage as ndi
import warp as wp

from bodyfit.fitter.fit.render_mesh import render_model
from bodyfit.fitter.model.body_model import PART_NAMES, forward
from bodyfit.fitter.model.cache import load_model
from bodyfit.kernels.boundary import nearest_boundary
from bodyfit.kernels.cost import CostSettings
from bodyfit.kernels.device import resolve_device
from bodyfit.kernels.evaluator import STAGES, PopulationEvaluator, cpu_threads
from bodyfit.kernels.raster import rasterize
from bodyfit.kernels.reference import population_cost
from bodyfit.kernels.skinning import ModelArrays
from bodyfit.kernels.target import (SIDE_VIEW_PARTS, boundary_mask, prepare_view_target,
                                    visible_faces)
from bodyfit.kernels.view_camera import FRONT_VIEW_DEG, SIDE_VIEW_DEG, orthographic_camera

CPU_TARGET_MS = 2.0
REFERENCE_TARGET_RATIO = 10.0
CUDA_TARGET_PER_S = 50_000


def _views(model, height: int, device: str, seed: int):
    """Front and side views of a synthetic person; canvases fitted to the mean body."""
    mean = model.mean_vertices
    stature = np.ptp(mean[:, 2])
    ppm = 0.85 * height / stature
    rng = np.random.default_rng(seed)
    betas = rng.uniform(-1, 1, (1, 20)).astype(np.float32)
    pose = rng.uniform(5, 20, (1, 4)).astype(np.float32)
    views = []
    for name, view_deg, axis, parts in (("front", FRONT_VIEW_DEG, 0, PART_NAMES),
                                        ("side", SIDE_VIEW_DEG, 1, SIDE_VIEW_PARTS)):
        width = int(np.ceil(1.3 * np.ptp(mean[:, axis]) * ppm / 16) * 16)
        centre_u = width / 2 - ppm * (mean[:, axis].max() + mean[:, axis].min()) / 2
        centre_v = height / 2 + ppm * (mean[:, 2].max() + mean[:, 2].min()) / 2
        camera = orthographic_camera(view_deg, ppm, (centre_u, centre_v))
        faces, face_parts = visible_faces(model.faces, model.face_parts, parts)
        mask = rasterize(forward(model, betas, pose), faces, face_parts, camera, height,
                         width).numpy()[0] >= 0
        views.append(prepare_view_target(name, mask, camera, 1000.0 / ppm, parts, device))
    return views, (betas, pose)


def _populations(size: int, person, seed: int):
    rng = np.random.default_rng(seed)
    first = (rng.uniform(-3, 3, (size, 20)).astype(np.float32),
             rng.uniform(0, 30, (size, 4)).astype(np.float32))
    late = ((person[0] + rng.normal(0, 0.3, (size, 20))).astype(np.float32),
            (person[1] + rng.normal(0, 3, (size, 4))).astype(np.float32))
    return first, late


def _best_seconds(evaluator, population, repeats: int, clock) -> float:
    best = np.inf
    for _ in range(repeats):
        start = clock()
        evaluator.evaluate(*population)
        best = min(best, clock() - start)
    return best


def _distance_errors(model, views, population) -> tuple[float, float]:
    """Mean and max |kernel - scipy EDT| over every pixel of a few candidates' maps."""
    view = views[0]
    maps = rasterize(forward(model, *population), model.faces, model.face_parts, view.camera,
                     view.height, view.width).numpy()
    rows, cols = np.mgrid[0:view.height, 0:view.width]
    points = np.stack([cols.ravel(), rows.ravel()], axis=1)
    distances, _ = nearest_boundary(maps, points)
    exact = np.stack([ndi.distance_transform_edt(~boundary_mask(m >= 0)).ravel() for m in maps])
    errors = np.abs(distances - exact)
    return float(errors.mean()), float(errors.max())


def main() -> None:
    parser = argparse.ArgumentParser(prog="python -m bench.kernel_speed",
                                     description=__doc__.split("\n\n")[0])
    parser.add_argument("--device", default="cpu", help="cpu, cuda or cuda:N")
    parser.add_argument("--populations", type=int, nargs="+", default=[30, 256, 1024])
    parser.add_argument("--height", type=int, default=512, help="image height, pixels")
    parser.add_argument("--repeats", type=int, default=3, help="timed runs, best kept")
    parser.add_argument("--reference-candidates", type=int, default=6,
                        help="candidates timed through the NumPy/OpenCV reference")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--render-cell-mm", type=float, default=0.0,
                        help="candidates on the fitter's render mesh at this cell size "
                             "(FitSettings.render_cell_mm; 0: the full model)")
    args = parser.parse_args()

    wp.config.log_level = wp.LOG_WARNING  # keep Warp's start-up and module lines out
    model = load_model()
    try:  # ValueError, with a message for the user: a bad device or cell size
        device = resolve_device(args.device)
        rendered = render_model(model, args.render_cell_mm)
        arrays = ModelArrays.from_body_model(rendered, 20, device)
    except ValueError as exc:
        sys.exit(f"bench_kernels: error: {exc}")
    views, person = _views(model, args.height, device, args.seed)
    settings = CostSettings()
    num_views = len(views)
    # CPU: the process's CPU time, so that other jobs on a shared machine do not count
    # (Warp runs CPU kernels in the calling thread); GPU: wall time.
    clock = time.perf_counter if device.is_cuda else time.process_time
    print(f"Kernel benchmark: {device.name} ({device.alias}), {platform.processor() or platform.machine()}, "
          f"{os.cpu_count()} logical CPUs, load average at start "
          f"{', '.join(f'{x:.1f}' for x in os.getloadavg())}; Warp {wp.__version__}\n")
    print(f"Canvas {args.height} px high: front {views[0].width} px wide "
          f"({views[0].boundary_points.shape[0]} person boundary points), side "
          f"{views[1].width} px ({views[1].boundary_points.shape[0]}); "
          f"candidates: {rendered.faces.shape[0]} triangles front, "
          f"{len(visible_faces(rendered.faces, rendered.face_parts, SIDE_VIEW_PARTS)[0])} "
          f"side, {rendered.num_vertices} vertices (render cell {args.render_cell_mm:g} mm); "
          f"matching {settings.matching}.\n")
    header = "| P | " + " | ".join(f"{s} (cv/s)" for s in STAGES)
    print(header + " | total (cv/s) | ms per cv | late generation (cv/s) | buffers (MB) | peak RSS (MB) |")
    print("|" + "---|" * (len(STAGES) + 6))
    totals, shares = {}, {}
    for size in args.populations:
        first, late = _populations(size, person, args.seed + size)
        evaluator = PopulationEvaluator(arrays, views, settings, workers=1)
        evaluator.evaluate(*first)  # compile and allocate
        seconds = _best_seconds(evaluator, first, args.repeats, clock)
        late_seconds = _best_seconds(evaluator, late, args.repeats, clock)
        profiler = PopulationEvaluator(arrays, views, settings, profile=True)
        profiler.evaluate(*first)
        profiler.stage_seconds = dict.fromkeys(STAGES, 0.0)
        profiler.evaluate(*first)
        work = size * num_views
        totals[size] = work / seconds
        profiled = sum(profiler.stage_seconds.values())
        shares[size] = {s: profiler.stage_seconds[s] / profiled for s in STAGES}
        rate = " | ".join(f"{work / profiler.stage_seconds[s]:,.0f}" for s in STAGES)
        peak_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
        if device.is_cuda:
            peak_mb = wp.get_mempool_used_mem_high(device) / 2 ** 20
        print(f"| {size} | {rate} | {totals[size]:,.0f} | {1e3 * seconds / work:.3f} | "
              f"{work / late_seconds:,.0f} | {evaluator.buffer_bytes() / 2 ** 20:.0f} | "
              f"{peak_mb:.0f} |")
    print("\ncv = candidate-view (one candidate scored in one view); times are "
          f"{'wall time' if device.is_cuda else 'the process CPU time (Warp runs CPU kernels in one thread)'}, "
          "best of the repeats; stage rates come from a profiled run that synchronises after "
          "every stage; 'skin' runs once per candidate for both views. Peak memory is the "
          "process's peak resident set (CPU) or the CUDA memory pool's high-water mark.\n")

    sample = _populations(args.reference_candidates, person, args.seed)[0]
    start = clock()
    reference_costs, _ = population_cost(rendered, *sample, views, settings)
    reference_s = (clock() - start) / (args.reference_candidates * num_views)
    kernel_costs = PopulationEvaluator(arrays, views, settings).evaluate(*sample).costs
    agreement = np.median(np.abs(kernel_costs - reference_costs) / reference_costs)
    largest = max(args.populations)
    ratio = totals[largest] * reference_s
    print(f"NumPy/OpenCV reference (NumPy forward, cv2.fillPoly far to near, cKDTree): "
          f"{1e3 * reference_s:.1f} ms per cv on {args.reference_candidates} candidates; "
          f"kernels at P = {largest}: {ratio:.0f}x faster (target >= {REFERENCE_TARGET_RATIO:.0f}x: "
          f"{'met' if ratio >= REFERENCE_TARGET_RATIO else 'missed'}). Median cost difference "
          f"{100 * agreement:.1f} % (the reference's cv2.fillPoly dilates silhouettes by about "
          "half a pixel).\n")
    mean_error, max_error = _distance_errors(rendered, views, (sample[0][:2], sample[1][:2]))
    print(f"Nearest boundary pixel vs scipy.ndimage.distance_transform_edt, every pixel of "
          f"2 front maps: mean error {mean_error:.2e} px, max {max_error:.2e} px.\n")
    if device.is_cuda:
        big = [p for p in args.populations if p >= 4096]
        best = max((totals[p] for p in big), default=0.0)
        print(f"CUDA target >= {CUDA_TARGET_PER_S:,} cv/s at P >= 4096: "
              f"{'met' if best >= CUDA_TARGET_PER_S else 'missed'} ({best:,.0f} cv/s)."
              if big else "CUDA target needs P >= 4096: not measured in this run.")
    else:
        _print_threads(arrays, views, settings, _populations(largest, person, args.seed)[0],
                       args.repeats)
        ms = 1e3 / totals[largest]
        verdict = "met" if ms <= CPU_TARGET_MS else f"missed by {100 * (ms / CPU_TARGET_MS - 1):.1f} %"
        split = ", ".join(f"{s} {100 * shares[largest][s]:.0f} %" for s in STAGES)
        print(f"CPU target <= {CPU_TARGET_MS} ms per cv at P = {largest}: {ms:.2f} ms, {verdict}. "
              f"Time shares: {split}.")


def _print_threads(arrays, views, settings, population, repeats: int) -> None:
    """Wall time of one population on 1 thread and on one per core (the fitter's default)."""
    cores = cpu_threads()
    work = len(population[0]) * len(views)
    walls = {}
    for workers in sorted({1, cores}):
        evaluator = PopulationEvaluator(arrays, views, settings, workers=workers)
        evaluator.evaluate(*population)
        walls[workers] = _best_seconds(evaluator, population, repeats, time.perf_counter)
    line = ", ".join(f"{w} thread{'s' * (w > 1)} {1e3 * s / work:.3f} ms per cv"
                     for w, s in walls.items())
    print(f"Wall time at P = {len(population[0])} (the fitter's CPU evaluator runs slices of "
          f"the population on one thread per core, {cores} here): {line}"
          + (f"; {walls[1] / walls[cores]:.2f}x." if cores > 1 else ".") + "\n")


if __name__ == "__main__":
    main()
