"""`fitter demo`: the built-in example.

Loads (or builds, the first time) the body model, draws a few bodies from its shape
space, and writes their meshes, their 16 measurements and a picture of them coloured by
body part.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

from bodyfit.fitter.body_model import BodyModel, rest_shape
from bodyfit.fitter.measurements import Measurer
from bodyfit.fitter.mesh_io import write_mesh
from bodyfit.calib.images import write_image
from bodyfit.fitter.outputs import staged_directory, write_measurements
from bodyfit.fitter.render import labelled_grid, parts_legend, render_parts

__all__ = ["DemoSettings", "run_demo"]


@dataclasses.dataclass(frozen=True)
class DemoSettings:
    bodies: int = 3
    num_betas: int = 20  # shape components used, as the paper
    beta_limit_sigma: float = 2.0  # |beta| clipped here
    seed: int = 0
    picture_height_px: int = 500


def run_demo(model: BodyModel, out_dir: Path, settings: DemoSettings = DemoSettings()) -> list[Path]:
    """Write ``body_<i>.obj``/``.ply`` (rest A-pose, metres), ``measurements.json``/``.csv``
    (mm) and ``bodies.png`` (a grid of front and side views, each labelled with its mesh
    file's name) into ``out_dir``; return the paths written."""
    rng = np.random.default_rng(settings.seed)
    n = settings.bodies
    betas = np.clip(rng.standard_normal((n, settings.num_betas)),
                    -settings.beta_limit_sigma, settings.beta_limit_sigma)
    rest, _ = rest_shape(model, betas)
    measurer = Measurer.from_model(model)
    names = [f"body_{i}" for i in range(n)]
    face_parts = model.face_parts
    tiles = [np.concatenate([render_parts(v, model.faces, face_parts, view,
                                          settings.picture_height_px)
                             for view in ("front", "side")], axis=1) for v in rest]
    picture = labelled_grid(tiles, [f"{name}.obj (front, side)" for name in names],
                            parts_legend(settings.picture_height_px))
    written = []
    with staged_directory(out_dir) as stage:
        for name, vertices in zip(names, rest):
            for suffix in (".obj", ".ply"):
                write_mesh(stage / f"{name}{suffix}", vertices, model.faces)
                written.append(out_dir / f"{name}{suffix}")
        provenance = {"command": "fitter demo", "settings": dataclasses.asdict(settings),
                      "betas_sigma": betas.round(4).tolist(),
                      "model": model.metadata.get("settings")}
        csv_path = write_measurements(stage / "measurements.json",
                                      {name: measurer.measure(v) for name, v in zip(names, rest)},
                                      provenance)
        write_image(stage / "bodies.png", picture)
        written += [out_dir / "measurements.json", out_dir / csv_path.name,
                    out_dir / "bodies.png"]
    return written
