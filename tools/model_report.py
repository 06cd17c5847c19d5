"""Write docs/model.md: the body model's build figures, realism and reconstruction error.

Reports, for the cached body model (built first if missing):
- build settings and time, file size, load time;
- the sample's measurement statistics next to ANSUR II's, per sex, and the main
  correlations;
- the PCA space's reconstruction error on held-out bodies drawn as the sample was (drawn
  with another seed) for K = 10, 20, 40, 60 components: vertex error (mean and 95th
  percentile) and the error of all 16 measurements;
- a picture of the part labels, front and side (docs/model_parts.png).

Usage:
    python tools/model_report.py [--held-out 200] [--seed 1001] [--docs docs]
"""

from __future__ import annotations

import argparse
import platform
import sys
import time
from pathlib import Path

import numpy as np

from bodyfit.calib.images import write_image
from bodyfit.fitter.measure.measurements import IMPORTANT, MEASUREMENTS, Measurer
from bodyfit.fitter.model.body_model import BodyModel, project_shape, rest_shape
from bodyfit.fitter.model.cache import active_model_path, load_model
from bodyfit.fitter.model_build.anny_source import AnnySource
from bodyfit.fitter.model_build.body_sample import SEXES, BodySampler, ReferenceStats
from bodyfit.fitter.model_build.builder import ModelBuildSettings
from bodyfit.fitter.output.render import parts_legend, render_parts
from bodyfit.fitter.output.result_files import write_text

KEYS = list(MEASUREMENTS)
REALISM_KEYS = ("O", "D", "E", "F", "L", "P", "K")  # the list
CORRELATION_PAIRS = (("E", "D"), ("O", "K"), ("F", "L"), ("O", "P"), ("D", "B"), ("E", "F"),
                     ("O", "J"), ("L", "M"))
COMPONENT_COUNTS = (10, 20, 40, 60)


def realism_section(model: BodyModel) -> list[str]:
    ref = ReferenceStats.load()
    lines = ["## The sample next to ANSUR II", "",
             f"The {len(model.sample_sex)} bodies the shape space was learned from "
             "(half men, half women), measured with bodyfit's definitions "
             f"(`bodyfit.fitter.measure.measurements`), against ANSUR II ({ref.n['male']:,} men, "
             f"{ref.n['female']:,} women). "
             "Mean (SD) in mm; ratio = sample / ANSUR. The issue's bar: ratios within "
             "0.90-1.10 for the measurements marked *.", ""]
    for sex in SEXES:
        pop = model.sample_measurements[model.sample_sex == SEXES.index(sex)]
        lines += [f"### {sex} ({len(pop)} bodies)", "",
                  "| key | measurement | sample | ANSUR II | ratio mean | ratio SD |",
                  "|---|---|---|---|---|---|"]
        for key in KEYS:
            col = pop[:, KEYS.index(key)]
            name = MEASUREMENTS[key][1] + (" *" if key in REALISM_KEYS else "")
            if key in ref.keys:
                r = ref.keys.index(key)
                m, s = ref.mean[sex][r], ref.std[sex][r]
                lines.append(f"| {key} | {name} | {col.mean():.0f} ({col.std():.0f}) | "
                             f"{m:.0f} ({s:.0f}) | {col.mean() / m:.3f} | {col.std() / s:.3f} |")
            else:
                lines.append(f"| {key} | {name} | {col.mean():.0f} ({col.std():.0f}) | — | — | — |")
        corr = np.corrcoef(pop, rowvar=False)
        lines += ["", "| correlation | sample | ANSUR II |", "|---|---|---|"]
        for a, b in CORRELATION_PAIRS:
            want = ref.correlation[sex][ref.keys.index(a), ref.keys.index(b)]
            lines.append(f"| {MEASUREMENTS[a][1]} ~ {MEASUREMENTS[b][1]} | "
                         f"{corr[KEYS.index(a), KEYS.index(b)]:.2f} | {want:.2f} |")
        lines.append("")
    lines += ["ANSUR II takes the bicep (H) and forearm (I) circumferences flexed; bodyfit "
              "measures the relaxed arm, so those two are not fitted and sit below ANSUR's. "
              "C (shoulder to crotch) has no ANSUR II column.", ""]
    return lines


def reconstruction_section(model: BodyModel, held_out, measurer: Measurer) -> list[str]:
    truth = held_out.measurements
    lines = ["## Reconstruction of held-out bodies", "",
             f"{len(held_out.sex)} bodies drawn like the sample but with another seed "
             "(never seen by the PCA), projected orthogonally onto the first K components "
             "(the best any fit in a K-dimensional space can do). Vertex error: distance "
             "between corresponding vertices, mm, over all vertices of all bodies. "
             "Measurement errors: mean |reconstructed - true|, mm.", "",
             "| K | mean vertex error (mm) | p95 vertex error (mm) | waist circ. error (mm) | "
             "chest circ. error (mm) | mean of the 7 important (mm) | mean of all 16 (mm) |",
             "|---|---|---|---|---|---|---|"]
    per_key = {}
    for k in COMPONENT_COUNTS:
        if k > model.num_components:
            continue
        rebuilt, _ = rest_shape(model, project_shape(model, held_out.vertices, held_out.joints, k))
        err = np.linalg.norm(rebuilt - held_out.vertices, axis=2) * 1000
        meas_err = np.abs(measurer.measure_many(rebuilt) - truth)
        per_key[k] = np.nanmean(meas_err, axis=0)
        important = np.nanmean(meas_err[:, [KEYS.index(c) for c in IMPORTANT]])
        lines.append(f"| {k} | {err.mean():.2f} | {np.percentile(err, 95):.2f} | "
                     f"{per_key[k][KEYS.index('E')]:.2f} | {per_key[k][KEYS.index('D')]:.2f} | "
                     f"{important:.2f} | {np.nanmean(meas_err):.2f} |")
    lines += ["", "Per measurement, mean |error| in mm:", "",
              "| key | measurement | " + " | ".join(f"K={k}" for k in per_key) + " |",
              "|---|---|" + "---|" * len(per_key)]
    for i, key in enumerate(KEYS):
        lines.append(f"| {key} | {MEASUREMENTS[key][1]} | "
                     + " | ".join(f"{per_key[k][i]:.2f}" for k in per_key) + " |")
    return lines + [""]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--held-out", type=int, default=200, help="held-out bodies (even)")
    parser.add_argument("--seed", type=int, default=1001, help="seed of the held-out bodies")
    parser.add_argument("--docs", type=Path, default=Path(__file__).resolve().parent.parent / "docs")
    args = parser.parse_args()

    model = load_model()
    path = active_model_path()
    loads = []
    for _ in range(5):
        t0 = time.perf_counter()
        BodyModel.load(path)
        loads.append(time.perf_counter() - t0)
    measurer = Measurer.from_model(model)
    t0 = time.perf_counter()
    half = args.held_out // 2
    held_out = BodySampler(AnnySource(), measurer,
                                 ModelBuildSettings.of(model).sampling).sample(
        {"male": half, "female": half}, seed=args.seed)
    held_out_s = time.perf_counter() - t0

    meta = model.metadata
    command = "python tools/model_report.py " + " ".join(sys.argv[1:])
    lines = ["# The body model", "",
             f"Produced by `{command.strip()}` on {time.strftime('%Y-%m-%d')} "
             f"({platform.machine()}, {platform.python_version()}, "
             f"anny {meta['anny_version']}). The model described is the one `fitter` uses "
             "(`fitter model info` names it); the shipped default is built by `fitter model build -o "
             "fitter/data/body_model.npz` (see `fitter/model_build/builder.py`); this file by "
             "`tools/model_report.py`.", "",
             "## Build", "",
             f"- settings: {meta['settings']}",
             f"- {model.num_vertices} vertices, {len(model.faces)} triangles, "
             f"{model.num_components} components stored (20 used by default), "
             f"explaining {meta['explained_variance']:.6f} of the sample's variance",
             f"- build time: {meta['timings_s']['total']:.0f} s on the build machine "
             f"(setup {meta['timings_s']['setup']:.0f} s, sample "
             f"{meta['timings_s']['sample']:.0f} s, PCA {meta['timings_s']['pca']:.0f} s), "
             "plus about a minute the first time Anny builds its own data cache (1.1 GB)",
             f"- file: `{path.name}`, {path.stat().st_size / 1e6:.1f} MB (compressed .npz)",
             f"- load time: {np.median(loads) * 1000:.0f} ms (median of 5)",
             f"- held-out bodies for the table below: {args.held_out}, drawn in "
             f"{held_out_s:.0f} s", "",
             "Eigenvalue share of the first components: "
             + ", ".join(f"{x:.4f}" for x in model.eigenvalues[:10] / model.eigenvalues.sum())
             + ". The first component is mostly stature (Anny's origin is at the pelvis, "
             "so a taller body reaches further down).", ""]
    lines += realism_section(model)
    lines += reconstruction_section(model, held_out, measurer)

    views = [render_parts(model.mean_vertices, model.faces, model.face_parts, view, 700)
             for view in ("front", "side")]
    write_image(args.docs / "model_parts.png", np.concatenate(views + [parts_legend(700)], axis=1))
    lines += ["## Part labels", "",
              "The mean body, front and side, coloured by its ten parts (Table 2's nine and the neck); "
              "see `fitter/model_build/parts.py` for how they are derived.", "",
              "![part labels, front and side](model_parts.png)", ""]
    write_text(args.docs / "model.md", "\n".join(lines))
    print(f"wrote {args.docs / 'model.md'} and {args.docs / 'model_parts.png'}")


if __name__ == "__main__":
    main()
