"""report.html: one self-contained page of a `fitter run`, for a person to read.

Everything is inside the file: pictures as base64 PNG data URIs, the CSS inline, no
script and no external resource, so it opens anywhere and can be mailed. Every string
that comes from the user (paths, sex, device) is HTML-escaped.
"""

from __future__ import annotations

import base64
import html

import numpy as np

from bodyfit.calib.images import encode_image
from bodyfit.fitter.fit.facing import side_text
from bodyfit.fitter.fit.pitch import pitch_text
from bodyfit.fitter.fit.spreads import SPREAD_NOTES
from bodyfit.fitter.measure.measurements import IMPORTANT, MEASUREMENTS

__all__ = ["REPORT_PICTURES", "png_data_uri", "report_html"]

#: The pictures a report shows, by key, with their captions.
REPORT_PICTURES = {
    "photo_front": "Front: your photo, the silhouette taken of it (white) and the fitted "
                   "body's outline (photo_front.png)",
    "photo_side": "Side: your photo, the silhouette taken of it (white) and the fitted "
                  "body's outline (photo_side.png)",
    "body_views": "The fitted body from the front, three-quarter and side (body_views.png)",
    "outline_front": "Front: the person's silhouette (grey) with the fitted body's outline",
    "outline_side": "Side: the person's silhouette (grey) with the fitted body's outline",
    "overlay_front": "Front: matched contours (overlay_front.png)",
    "overlay_side": "Side: matched contours (overlay_side.png)",
    "convergence": "The fit's cost per iteration or generation (convergence.png; the local "
                   "solver's rises where it places the cameras anew from the body so far)",
}

_CSS = """
body { font-family: system-ui, sans-serif; margin: 24px auto; max-width: 1200px;
       color: #222; padding: 0 16px; }
h1 { font-size: 1.5em; margin-bottom: 0.2em; }
h2 { font-size: 1.15em; border-bottom: 1px solid #ccc; padding-bottom: 4px; margin-top: 1.6em; }
.note { color: #666; font-size: 0.9em; }
.row { display: flex; flex-wrap: wrap; gap: 16px; align-items: flex-start; }
figure { margin: 0; flex: 1 1 0; min-width: 260px; }
figure img { max-width: 100%; max-height: 640px; border: 1px solid #ddd; }
figcaption { font-size: 0.85em; color: #555; margin-top: 4px; }
table { border-collapse: collapse; font-size: 0.92em; margin: 8px 0; }
th, td { padding: 3px 10px; border-bottom: 1px solid #e4e4e4; text-align: left; }
td.num { text-align: right; font-variant-numeric: tabular-nums; }
tr.important td { font-weight: 600; }
.tables { display: flex; flex-wrap: wrap; gap: 32px; align-items: flex-start; }
code { font-size: 0.95em; word-break: break-all; }
"""


def png_data_uri(image: np.ndarray) -> str:
    """``data:image/png;base64,...`` of a (H, W, 3) uint8 BGR picture."""
    return "data:image/png;base64," + base64.b64encode(encode_image(image, ".png")).decode("ascii")


def _e(value) -> str:
    return html.escape(str(value), quote=True)


def _rows(pairs, numeric: bool = False) -> str:
    cell = '<td class="num">' if numeric else "<td>"
    return "".join(f"<tr><th>{_e(k)}</th>{cell}{v}</td></tr>" for k, v in pairs)


def _figure(key: str, images: dict[str, np.ndarray]) -> str:
    caption = _e(REPORT_PICTURES[key])
    return (f'<figure><img src="{png_data_uri(images[key])}" alt="{caption}">'
            f"<figcaption>{caption}</figcaption></figure>")


def _measurement_table(values: dict[str, float], spreads: dict[str, float]) -> str:
    rows = []
    for key, (_, label) in MEASUREMENTS.items():
        marked = ' class="important"' if key in IMPORTANT else ""
        rows.append(f"<tr{marked}><td>{key}</td><td>{_e(label)}</td>"
                    f'<td class="num">{values[key]:.1f}</td>'
                    f'<td class="num">± {spreads[key]:.1f}</td></tr>')
    return ("<table><thead><tr><th>letter</th><th>measurement</th><th>value (mm)</th>"
            "<th>± (mm)</th></tr></thead><tbody>" + "".join(rows) + "</tbody></table>")


def _settings_rows(record: dict) -> list[tuple[str, str]]:
    search, cost = record["settings"]["search"], record["settings"]["cost"]
    solver = record["settings"]["solver"]
    result = record["result"]
    default = "the optimiser's default"
    learned = solver.get("start") == "learned"
    elbows, hands = result.get("elbow_deg"), result.get("hand_twist_deg")
    solver_row = ("local solver", f"{_e(solver['iterations'])} iterations at most, "
                                  f"{_e(solver['components'])} components"
                                  + (", from the learned start" if learned else "")
                                  + ("" if elbows is None else
                                     f"; the elbows fitted, {elbows:.1f} degrees")
                                  + ("" if hands is None else
                                     "; the front photo's hands turned {} and {} degrees "
                                     "from palm in".format(*map(round, hands.values())))
                  if solver["iterations"] else
                  "none: the learned start's body" if learned else "none")
    if not search["searches"]:
        return [("population search", "none"), solver_row,
                ("ran", f"{result['generations']} iterations, {result['evaluations']} bodies "
                        "rendered"),
                ("matching", "model to person and person to model, sub-pixel"),
                ("device", _e(record["settings"]["device"]))]
    return [
        ("optimizer", _e(search["optimizer"])),
        ("population", _e(search["population"] or default)),
        ("generations", f"{_e(search['generations'] or default)} "
                        f"(ran {result['generations']}, {result['evaluations']} candidates)"),
        ("components", _e(search["components"])),
        ("refinement", f"{_e(search['refine_components'])} components, "
                       f"{_e(search['refine_generations'])} generations"
                       + (f", {_e(search['refinements'])} averaged"
                          if search["refinements"] > 1 else "")
         if search.get("refine_components") else "none"),
        solver_row,
        ("matching", _e(cost["matching"])),
        ("seed", _e(search["seed"])),
        ("device", _e(record["settings"]["device"])),
    ]


def _weight_rows(weights: dict[str, float]) -> list[tuple[str, str]]:
    return [(name, f"{value:g}") for name, value in weights.items()]


def report_html(record: dict, values: dict[str, float], spreads: dict[str, float],
                spread_basis: str, images: dict[str, np.ndarray]) -> str:
    """The report page.

    Args:
        record: the run.json payload (:func:`bodyfit.fitter.run.results.run_record`), its weights
            included.
        values, spreads: measurement key ("A".."P") -> mm.
        spread_basis: the kind of spread, a key of :data:`bodyfit.fitter.fit.spreads.SPREAD_NOTES`.
        images: one (H, W, 3) uint8 BGR picture per key of ``REPORT_PICTURES``.
    """
    inputs, result = record["inputs"], record["result"]
    given = [(name, f"<code>{_e(value)}</code>") for name, value in inputs.items()
             if value is not None and name not in ("height_cm", "sex", "check")]
    given += [("stature", f"{inputs['height_cm']:g} cm"), ("sex", _e(inputs["sex"]))]
    photos = record.get("photos", {})
    if "camera" in photos:
        given.append(("camera used", _e(photos["camera"])))
    if "side_from" in photos:
        given.append(("side photo", _e(side_text(photos))))
    if "pitch_deg" in photos:
        given.append(("cameras' pitch", pitch_text(photos["pitch_deg"])))
    if "check_warnings" in photos:
        given.append(("photography check", "<br>".join(
            ["passed" + (", with warnings:" if photos["check_warnings"] else "")]
            + [_e(line) for line in photos["check_warnings"]])))
    elif inputs.get("check") is False:
        given.append(("photography check", "skipped (--no-check)"))
    if "fit_warning" in photos:
        given.append(("fit", f"<strong>{_e(photos['fit_warning'])}</strong>"))
    terms = [("total", f"{result['best_cost']:.2f}")]
    terms += [(name, f"{value:.2f}") for name, value in result["part_costs"].items()]
    timings = [(stage, f"{seconds:.2f} s") for stage, seconds in record["timings_s"].items()]
    return f"""<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<title>bodyfit report</title>
<style>{_CSS}</style>
</head>
<body>
<h1>bodyfit: fitted body and measurements</h1>
<p class="note">bodyfit {_e(record["versions"].get("bodyfit", "?"))}, <code>fitter run</code>.
The measurements are those of the fitted body model; {_e(SPREAD_NOTES[spread_basis])}.</p>
<table>{_rows(given)}</table>

<h2>Your photos</h2>
<p class="note">Where the white outline leaves the person, the silhouette is wrong (photograph
again before a plainer background); where the coloured one leaves the white, the fit is.</p>
<div class="row">{_figure("photo_front", images)}{_figure("photo_side", images)}</div>

<h2>The fitted body</h2>
<div class="row">{_figure("body_views", images)}</div>

<h2>Silhouettes</h2>
<p class="note">The person's silhouette on the fitting canvas (scaled from the stature),
and the fitted body's outline coloured by body part, registered onto it by the paper's
rigid ICP.</p>
<div class="row">{_figure("outline_front", images)}{_figure("outline_side", images)}</div>

<h2>Matched contours</h2>
<p class="note">As the paper's Fig. 6 and 8: the person's contour registered onto the
fitted body's, and each person point joined to its nearest body point, coloured by that
point's body part.</p>
<div class="row">{_figure("overlay_front", images)}{_figure("overlay_side", images)}</div>

<h2>Measurements</h2>
<p class="note">Bold: the paper's seven visually important measurements.</p>
{_measurement_table(values, spreads)}

<h2>Convergence</h2>
<div class="row">{_figure("convergence", images)}</div>
<div class="tables">
<div><h3>Settings</h3><table>{_rows(_settings_rows(record))}</table></div>
<div><h3>Weights</h3><table>{_rows(_weight_rows(record["weights"]), numeric=True)}</table></div>
<div><h3>Best cost (weighted mm)</h3><table>{_rows(terms, numeric=True)}</table></div>
<div><h3>Timings</h3><table>{_rows(timings, numeric=True)}</table></div>
</div>
</body>
</html>
"""
