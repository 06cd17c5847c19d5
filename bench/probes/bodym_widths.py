"""Probe: does a BodyM fit reach the widths its masks show, and do they carry the girths?

For each fitted photo pair of a ``python -m bench.bodym`` run (its subjects' first pair,
the choice part), at each of the chest's, the waist's and the hip's tape planes
(:meth:`~bodyfit.fitter.measure.measurements.Measurer.girth_plane` on the fitted body in
its pose, a height above its soles):

- the fitted section's breadth and depth (its extents across the body and front to back:
  what the body's front and side silhouettes show at that height);
- the person's at the same height: the padded mask cropped to the person, scaled so that
  the person is the stated height tall (as the orthographic canvas is), the width of the
  foreground run nearest the person's middle column, averaged over 5 mm either side;
- an ellipse through the mask's breadth and depth (Ramanujan's perimeter).

It prints per girth the median mask-over-fit ratio of the breadth and the depth by body
mass index, and the correlation with the scan's girth of the fitted girth and of the
mask's ellipse, and the share of shape components at their bounds. Run from the
repository root::

    python -m bench.probes.bodym_widths default --first 100

Aggregate figures only (BodyM is CC BY-NC: evaluation only).
"""

from __future__ import annotations

import argparse
import json

import numpy as np

from bench.bodym.cli import RUNS
from bench.bodym.dataset import DEFAULT_SPLIT, part, read_split
from bench.bodym.scores import BMI_BANDS
from bodyfit.calib.silhouette import load_mask
from bodyfit.fitter.fit.search import SearchSettings
from bodyfit.fitter.measure.measurements import MEASUREMENTS, Measurer
from bodyfit.fitter.model.cache import load_model
from bodyfit.fitter.output.mesh_io import read_mesh

_GIRTHS = ("D", "E", "F")
_BAND_MM = 5.0
_LIMIT = SearchSettings().beta_limit - 0.01  # |beta| at its bound


def mask_width_mm(mask: np.ndarray, stature_mm: float, height_mm: float) -> float:
    """The person's width (mm) at ``height_mm`` above the lowest row of the (H, W) bool
    ``mask``, scaled so that the person is ``stature_mm`` tall: the foreground run of
    each row within ``_BAND_MM`` nearest the person's middle column, averaged."""
    rows, cols = np.nonzero(mask)
    top, bottom = rows.min(), rows.max()
    mm = stature_mm / (bottom - top + 1)
    middle = 0.5 * (cols.min() + cols.max())
    centre = bottom - height_mm / mm
    widths = []
    for row in range(round(centre - _BAND_MM / mm), round(centre + _BAND_MM / mm) + 1):
        edges = np.flatnonzero(np.diff(np.r_[0, mask[row].astype(np.int8), 0]))
        runs = edges.reshape(-1, 2)
        if len(runs):
            gap = np.maximum(runs[:, 0] - middle, middle - runs[:, 1]).clip(min=0)
            start, end = runs[np.argmin(gap)]
            widths.append((end - start) * mm)
    return float(np.mean(widths)) if widths else float("nan")


def ellipse_perimeter(breadth: np.ndarray, depth: np.ndarray) -> np.ndarray:
    """Ramanujan's perimeter of ellipses of these breadths and depths (their axes)."""
    a, b = breadth / 2, depth / 2
    return np.pi * (3 * (a + b) - np.sqrt((3 * a + b) * (a + 3 * b)))


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m bench.probes.bodym_widths")
    parser.add_argument("name", help="the bench.bodym run (out/bodym/NAME)")
    parser.add_argument("--first", type=int, default=100)
    args = parser.parse_args(argv)
    model = load_model()
    measurer = Measurer.from_model(model)
    rows = []
    for subject in part(read_split(DEFAULT_SPLIT), "choice")[:args.first]:
        photo = subject.photo_ids[0]
        fit = RUNS / args.name / photo
        if not (fit / "mesh.obj").exists():
            continue
        posed = read_mesh(fit / "mesh.obj", model.faces)
        floor = posed[:, 2].min()
        masks = [load_mask(str(RUNS / "masks" / f"{photo}_{view}.png"))
                 for view in ("front", "side")]
        stature = subject.stated_height_cm * 10.0
        values = json.loads((fit / "measurements.json").read_text())["measurements"]
        betas = np.array(json.loads((fit / "run.json").read_text())["result"]["betas"])
        row = [subject.bmi, np.mean(np.abs(betas[1:]) > _LIMIT)]
        for key in _GIRTHS:
            height = (measurer.girth_plane(posed, key)[0][2] - floor) * 1000.0
            section = measurer.girth_section(posed, key) * 1000.0
            fitted = np.ptp(section, axis=0)
            seen = [mask_width_mm(m, stature, height) for m in masks]
            row += [*fitted, *seen, values[MEASUREMENTS[key][0]]["value_mm"],
                    subject.truth_mm[key]]
        rows.append(row)
    a = np.array(rows)
    print(f"{args.name}: {len(a)} fits; shape components 2..K at their bounds: "
          f"{100 * a[:, 1].mean():.0f} %")
    print("girth | band | people | mask/fit breadth | mask/fit depth")
    for i, key in enumerate(_GIRTHS):
        fb, fd, mb, md, value, truth = a[:, 2 + 6 * i:8 + 6 * i].T
        for label, low, high in BMI_BANDS:
            inside = (a[:, 0] >= low) & (a[:, 0] < high)
            if inside.any():
                print(f"{key} | {label} | {inside.sum()} | "
                      f"{np.median(mb[inside] / fb[inside]):.3f} | "
                      f"{np.median(md[inside] / fd[inside]):.3f}")
        ellipse = ellipse_perimeter(mb, md)
        print(f"{key}: correlation with the scan's girth: the fit's "
              f"{np.corrcoef(value, truth)[0, 1]:.2f}, the mask's ellipse "
              f"{np.corrcoef(ellipse, truth)[0, 1]:.2f}")


if __name__ == "__main__":
    main()
