"""`fitter run`: a person's two photos to a measured 3D body, written to a folder.

Outputs, written atomically into OUT (a failed run leaves OUT as it was):

- ``mesh.obj``, ``mesh.ply``: the fitted body in its fitted pose, metres, model frame;
- ``mesh_rest.ply``: the same body in the rest A-pose (where it is measured);
- ``measurements.json`` / ``.csv``: the 16 measurements with their ± (``spread_mm``, mm;
  :mod:`bodyfit.fitter.fit.spreads`; the JSON names its kind, ``spread_basis``);
- ``convergence.png``: the best and mean cost per generation;
- ``run.json``: inputs, settings, weights, seed, versions, timings, best cost, parameters,
  the answers averaged into the fit's (``result.averaged``: each one's betas, angles and
  cost), the output folder and the working folder (``fitter run --config`` repeats the run);
- ``overlay_front.png``, ``overlay_side.png``: the person's and the fitted body's
  silhouettes with their matched contour points, coloured by part (the paper's Fig. 6/8);
- ``photo_front.png``, ``photo_side.png``: the person's own photos with their silhouette's
  outline and the fitted body's, coloured by part;
- ``body_views.png``: the fitted body from the front, three-quarter and side, shaded;
- ``report.html``: one self-contained page of all of it, for a person to read.
"""

from __future__ import annotations

import dataclasses
import importlib.metadata
import os
import platform
from pathlib import Path


from bodyfit import kernels
from bodyfit.calib.images import write_image
from bodyfit.common.errors import UserError
from bodyfit.fitter.fit.person import PersonInputs
from bodyfit.fitter.fit.person_fit import Fit, FitSettings, fit_inputs, fit_work
from bodyfit.fitter.fit.weights import weights_record
from bodyfit.fitter.model.body_model import POSE_NAMES, BodyModel
from bodyfit.fitter.output.body_views import body_views_image
from bodyfit.fitter.output.mesh_io import write_mesh
from bodyfit.fitter.output.overlays import (fitted_outline_image, match_contours, overlay_image,
                                            photo_outline_image)
from bodyfit.fitter.output.plots import line_chart
from bodyfit.fitter.output.report import report_html
from bodyfit.fitter.output.result_files import (staged_directory, write_fitted_measurements,
                                                write_json, write_text)

__all__ = ["RUN_FILES", "check_output_dir", "run_person", "run_record"]

#: The files every successful run writes into OUT.
RUN_FILES = ("mesh.obj", "mesh.ply", "mesh_rest.ply", "measurements.json", "measurements.csv",
             "convergence.png", "run.json", "overlay_front.png", "overlay_side.png",
             "photo_front.png", "photo_side.png", "body_views.png", "report.html")


def check_output_dir(out_dir: Path, overwrite: bool) -> None:
    """Refuse an OUT that is a file, or a folder that is not empty (unless ``overwrite``)."""
    if out_dir.exists() and not out_dir.is_dir():
        raise UserError(f"output folder {out_dir} is a file")
    if out_dir.is_dir() and any(out_dir.iterdir()) and not overwrite:
        raise UserError(f"output folder {out_dir} is not empty; choose another or pass --overwrite")


def _versions() -> dict[str, str]:
    names = ("bodyfit", "warp-lang", "numpy", "opencv-contrib-python-headless", "cma")
    found = {}
    for name in names:
        try:
            found[name] = importlib.metadata.version(name)
        except importlib.metadata.PackageNotFoundError:
            found[name] = "not installed"
    return found | {"python": platform.python_version()}


def run_record(inputs: PersonInputs, settings: FitSettings, model: BodyModel, fit: Fit,
               out_dir: Path) -> dict:
    """The run.json payload: everything needed to repeat and judge the run (relative
    input paths are relative to ``working_dir``)."""
    result = fit.search
    return {
        "inputs": dataclasses.asdict(inputs),
        "photos": fit.photos,
        "output": str(out_dir),
        "working_dir": os.getcwd(),
        "settings": dataclasses.asdict(settings),
        "weights": weights_record(settings.cost),
        "cost_terms": list(kernels.TERM_NAMES),
        "model": {"settings": model.metadata.get("settings"),
                  "anny_version": model.metadata.get("anny_version")},
        "versions": _versions(),
        "result": {
            "best_cost": result.cost,
            "part_costs": dict(zip(kernels.TERM_NAMES, map(float, result.part_costs))),
            "betas": result.betas.tolist(),
            "pose_deg": dict(zip(POSE_NAMES, result.pose_deg.tolist())),
            "elbow_deg": result.elbow_deg,
            "hand_twist_deg": (None if result.hand_twist_deg is None
                               else dict(zip(("left", "right"), result.hand_twist_deg.tolist()))),
            "mass_scale": fit.mass_scale,
            "evaluations": result.evaluations,
            "generations": result.generations,
            "stop_reasons": {k: str(v) for k, v in result.stop_reasons.items()},
            "best_cost_per_generation": result.best_costs.tolist(),
            "best_betas_per_generation": result.best_betas.round(4).tolist(),
            "averaged": [{"betas": r.betas.tolist(),
                          "pose_deg": dict(zip(POSE_NAMES, r.pose_deg.tolist())),
                          "cost": r.cost} for r in result.averaged_from],
        },
        "timings_s": {k: round(v, 3) for k, v in fit.seconds.items()},
    }


def run_person(model: BodyModel, inputs: PersonInputs, settings: FitSettings, out_dir: Path,
               overwrite: bool = False, progress: bool | None = None) -> tuple[Fit, list[Path]]:
    """Fit one person and write the outputs of the module docstring into ``out_dir``.

    Returns:
        The fit and the paths written.
    """
    out_dir = Path(out_dir)
    check_output_dir(out_dir, overwrite)
    fit = fit_inputs(model, inputs, settings, progress)
    result = fit.search
    title = fit_work(settings, result)
    if settings.search.searches:
        chart = line_chart({"best so far": result.best_costs,
                            "generation mean": result.mean_costs},
                           title, "generation", "cost (weighted mm)", log_y=True)
    else:
        chart = line_chart({"cost": result.best_costs}, title, "iteration",
                           "smooth cost (weighted square mm)", log_y=True)
    with staged_directory(out_dir) as stage:
        for name, vertices in (("mesh.obj", fit.posed), ("mesh.ply", fit.posed),
                               ("mesh_rest.ply", fit.rest)):
            write_mesh(stage / name, vertices, model.faces)
        write_fitted_measurements(stage / "measurements.json", fit.measurements, fit.spreads,
                                  fit.spread_basis,
                                  {"command": "fitter run", "front": inputs.front,
                                   "side": inputs.side, "height_cm": inputs.height_cm})
        write_image(stage / "convergence.png", chart)
        record = run_record(inputs, settings, model, fit, out_dir)
        write_json(stage / "run.json", record)
        pictures = {"convergence": chart, "body_views": body_views_image(fit.posed, model.faces)}
        for name, view in fit.views.items():
            matched = match_contours(model, fit.view_bodies[name], view, settings.device)
            pictures[f"overlay_{name}"] = overlay_image(matched)
            pictures[f"outline_{name}"] = fitted_outline_image(matched)
            pictures[f"photo_{name}"] = photo_outline_image(
                matched, fit.images[name], fit.masks[name],
                mirrored=name == "side" and fit.photos["side_from"] == "right")
            for kind in ("overlay", "photo"):
                write_image(stage / f"{kind}_{name}.png", pictures[f"{kind}_{name}"])
        write_image(stage / "body_views.png", pictures["body_views"])
        write_text(stage / "report.html",
                   report_html(record, fit.measurements, fit.spreads, fit.spread_basis,
                               pictures))
    return fit, [out_dir / name for name in RUN_FILES]
