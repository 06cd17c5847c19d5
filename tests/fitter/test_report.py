"""`fitter run`'s overlays and report.html, and repeating a run with --config run.json."""

import dataclasses
import html
import html.parser
import json
import re
import shutil

import cv2
import numpy as np
import pytest

from bodyfit.common.errors import UserError
from bodyfit.fitter.cli.main import main
from bodyfit.fitter.demo.studio_photos import write_subject
from bodyfit.fitter.fit import person_fit as fit_module
from bodyfit.fitter.fit.facing import side_text
from bodyfit.fitter.fit.local_solver import SolverSettings
from bodyfit.fitter.fit.person import PersonInputs
from bodyfit.fitter.fit.person_fit import FitSettings
from bodyfit.fitter.fit.search import SearchSettings
from bodyfit.fitter.fit.spreads import SPREAD_NOTES, bodyfit_calibration, recorded_answer_cost
from bodyfit.fitter.measure.measurements import MEASUREMENTS
from bodyfit.fitter.model.body_model import PART_NAMES
from bodyfit.fitter.output.body_views import BODY_BGR
from bodyfit.fitter.output.overlays import _canvas_to_photo
from bodyfit.fitter.output.render import PART_COLOURS_BGR
from bodyfit.fitter.run.config import read_run_config, run_config
from bodyfit.fitter.run.options import fit_settings
from bodyfit.kernels import CostSettings

BETAS = np.r_[0.5, np.zeros(19)]
POSE = np.array([5.0, 5.0, 3.0, 3.0])
BUDGET = ["--method", "thorough", "--optimizer", "ga", "--population", "10", "--generations", "2", "--seed", "5",
          "--weight", "waist=7", "--projection", "orthographic",  # orthographic studio photos
          "--refine-components", "0"]


class _Page(html.parser.HTMLParser):
    """Collects the tags, the <img> sources and every URL-valued attribute of a page."""

    def __init__(self):
        super().__init__()
        self.images, self.urls, self.tags = [], [], []

    def handle_starttag(self, tag, attrs):
        self.tags.append(tag)
        for name, value in attrs:
            if name in ("src", "href", "srcset", "action"):
                self.urls.append(value)
            if tag == "img" and name == "src":
                self.images.append(value)


@pytest.fixture(scope="module")
def first_run(body_model, tmp_path_factory):
    """One small run on photos in a folder named with markup; its output folder."""
    folder = tmp_path_factory.mktemp("photos") / "<script>alert(1)"
    folder.mkdir()
    truth = write_subject(folder, body_model, BETAS, POSE)
    out = tmp_path_factory.mktemp("runs") / "first"
    code = main(["-q", "run", "--front", str(folder / "front.png"), "--side",
                 str(folder / "side.png"), "--height-cm", f"{truth['O'] / 10:.2f}",
                 "-o", str(out), *BUDGET])
    assert code == 0
    return out


@pytest.mark.parametrize("view", ["front", "side"])
def test_overlays_show_both_silhouettes_and_part_coloured_pairs(first_run, view):
    image = cv2.imread(str(first_run / f"overlay_{view}.png"))
    # twice the canvas, cropped to the bodies (about as tall as the canvas's person there)
    # with 16 px around, under a 30 px title band
    body_px = FitSettings().canvas.body_height_px
    assert abs(image.shape[0] - (2 * body_px + 2 * 16 + 30)) <= 2 * 15
    drawing = image[30:, :-120]  # the legend is the last 120 columns
    counts = {name: int((drawing == colour).all(axis=2).sum())
              for name, colour in zip(PART_NAMES, PART_COLOURS_BGR)}
    assert all(counts[name] > 20 for name in ("head", "chest", "waist", "hip", "leg", "foot"))
    assert (counts["arm"] > 20) == (view == "front")  # the side view is fitted without arms
    assert (drawing == (212, 212, 212)).all(axis=2).sum() > 100  # the person's silhouette


def test_canvas_points_map_into_the_photo_by_the_silhouettes_area_and_centroid():
    photo, canvas = np.zeros((400, 300), bool), np.zeros((150, 120), bool)
    photo[100:300, 50:150] = True  # the canvas's person, twice as large, moved
    canvas[10:110, 20:70] = True
    mapped = _canvas_to_photo(canvas, photo, np.array([[20.0, 10.0], [69.0, 109.0]]))
    # each canvas pixel covers two photo pixels a side: the corners' centres land between
    np.testing.assert_allclose(mapped, [[50.5, 100.5], [148.5, 298.5]])


def test_the_body_is_shown_from_three_angles(first_run):
    image = cv2.imread(str(first_run / "body_views.png"))
    clay = (np.abs(image.astype(int) - BODY_BGR) < 90).all(axis=2) & (image < 250).any(axis=2)
    widths = [int(clay[:, cols].any(axis=0).sum()) for cols in
              np.array_split(np.arange(image.shape[1]), 3)]
    assert image.shape[0] == 480 + 30
    assert widths[0] > widths[2] and min(widths) > 40  # the A-pose is wider than its side


def test_report_is_one_self_contained_escaped_page(first_run):
    text = (first_run / "report.html").read_text()
    page = _Page()
    page.feed(text)
    page.close()
    # two photos, the body's views, two outlines, two overlays, convergence
    assert len(page.images) == 8
    assert all(src.startswith("data:image/png;base64,") for src in page.images)
    assert all(url.startswith("data:") for url in page.urls)
    assert "http://" not in text and "https://" not in text and "script" not in page.tags
    assert "&lt;script&gt;alert(1)" in text and "<script>" not in text
    values = json.loads((first_run / "measurements.json").read_text())["measurements"]
    for key, (name, label) in MEASUREMENTS.items():
        row = re.search(rf"<td>{key}</td><td>{re.escape(html.escape(label))}</td>"
                        r'<td class="num">([\d.]+)</td><td class="num">± ([\d.]+)</td>', text)
        assert row, label
        assert float(row[1]) == pytest.approx(values[name]["value_mm"], abs=0.051)
        assert float(row[2]) == pytest.approx(values[name]["spread_mm"], abs=0.051)
    assert '<th>waist</th><td class="num">7</td>' in text
    assert "<th>optimizer</th><td>ga</td>" in text and "<th>seed</th><td>5</td>" in text
    photos = json.loads((first_run / "run.json").read_text())["photos"]
    assert f"<th>camera used</th><td>{html.escape(photos['camera'])}</td>" in text
    assert f"<th>side photo</th><td>{html.escape(side_text(photos))}</td>" in text


def test_run_json_round_trips_into_the_same_settings(first_run):
    config = read_run_config(first_run / "run.json")
    weights = list(FitSettings().cost.part_weights)
    weights[PART_NAMES.index("waist")] = 7.0  # the run's --weight waist=7
    assert config.settings == FitSettings(
        search=SearchSettings(optimizer="ga", population=10, generations=2, seed=5,
                              refine_components=0),
        solver=SolverSettings(),  # the run's --method thorough: no local solver
        projection="orthographic", measurement_prior="none",  # thorough's: the fit's own
        mass_scaling="none",
        cost=dataclasses.replace(FitSettings().cost, part_weights=tuple(weights)))
    assert config.inputs.front.endswith("front.png") and config.output == first_run
    custom = FitSettings(search=SearchSettings(pose_lower_deg=(-5.0,) * 4, components=12),
                         cost=CostSettings(matching="symmetric", align_rotation=False),
                         device="cuda:0")
    inputs = PersonInputs("/a/f.png", "/a/s.png", 171.5, mask_side="/a/m.png", sex="female")
    record = json.loads(json.dumps({"inputs": dataclasses.asdict(inputs),
                                    "settings": dataclasses.asdict(custom)}))
    again = run_config(record)
    assert again.settings == custom and again.inputs == inputs and again.output is None


def test_run_json_from_before_the_solver_runs_without_it(first_run):
    """A run.json without ``settings.solver`` (written before the local solver) repeats
    its population search alone, not the search and then today's solver; one whose solver
    names no ``prior_per_cost`` (before the shape prior grew with the misfit) repeats
    the fixed prior alone, and ``--shape-prior`` sets it."""
    record = json.loads((first_run / "run.json").read_text())
    del record["settings"]["solver"]
    assert run_config(record).settings.solver.iterations == 0
    record["settings"]["solver"] = {"iterations": 12}  # and before the shape prior's share
    assert run_config(record).settings.solver == SolverSettings(iterations=12,
                                                                prior_per_cost=0.0)
    record["settings"]["solver"] = {"iterations": 12, "prior_per_cost": 0.002}
    assert run_config(record).settings.solver.prior_per_cost == 0.002
    given = fit_settings(run_config(record).settings, {"shape_prior": 0.0})
    assert given.solver == SolverSettings(iterations=12, prior_per_cost=0.0)


def test_run_json_of_nine_parts_weighs_the_neck_as_its_head(first_run):
    record = json.loads((first_run / "run.json").read_text())
    weights = record["settings"]["cost"]["part_weights"][:-1]  # as written before the neck
    weights[PART_NAMES.index("head")] = 3.0  # unlike any preset's neck
    record["settings"]["cost"]["part_weights"] = weights
    old = run_config(record).settings
    assert old.cost.part_weights == (*weights, 3.0)
    assert old == dataclasses.replace(read_run_config(first_run / "run.json").settings,
                                      cost=old.cost)
    record["settings"]["cost"]["part_weights"] = weights[:-1]
    with pytest.raises(UserError, match="part_weights needs 10 values"):
        run_config(record)


def test_config_repeats_the_run_and_options_override_it(first_run, tmp_path, capsys):
    first = json.loads((first_run / "run.json").read_text())
    same, other = tmp_path / "same", tmp_path / "other"
    assert main(["-q", "run", "--config", str(first_run / "run.json"), "-o", str(same)]) == 0
    assert main(["-q", "run", "--config", str(first_run / "run.json"), "-o", str(other),
                 "--seed", "6"]) == 0
    capsys.readouterr()
    repeated = json.loads((same / "run.json").read_text())
    assert repeated["result"]["best_cost"] == first["result"]["best_cost"]
    assert repeated["result"]["betas"] == first["result"]["betas"]
    assert repeated["settings"] == first["settings"]
    changed = json.loads((other / "run.json").read_text())
    assert changed["settings"]["search"]["seed"] == 6
    assert changed["result"]["betas"] != first["result"]["betas"]


def test_config_into_its_own_folder_needs_overwrite(first_run, tmp_path, capsys):
    copy = tmp_path / "copy"
    shutil.copytree(first_run, copy)
    record = json.loads((copy / "run.json").read_text()) | {"output": str(copy)}
    (copy / "run.json").write_text(json.dumps(record))
    assert main(["-q", "run", "--config", str(copy / "run.json")]) == 2
    assert "--overwrite" in capsys.readouterr().err


@pytest.mark.parametrize("content,message", [
    (None, "no such file"),
    ("{", "not valid JSON"),
    ("[1]", "object"),
    ('{"inputs": {}}', "missing 'settings'"),
    ('{"inputs": {"front": "f.png"}, "settings": {}}', "missing 'side'"),
    ('{"inputs": {"front": "f", "side": "s", "height_cm": 170}, '
     '"settings": {"search": {"components": "twenty"}}}', "components"),
    ('{"inputs": {"front": "f", "side": "s", "height_cm": 170}, '
     '"settings": {"cost": {"matching": "both"}}}', "matching"),
    ('{"inputs": {"front": "f", "side": "s", "height_cm": 170, "age": 3}, "settings": {}}',
     "unknown field 'age'"),
])
def test_bad_config_is_one_line(tmp_path, capsys, content, message):
    path = tmp_path / "run.json"
    if content is not None:
        path.write_text(content)
    assert main(["-q", "run", "--config", str(path), "-o", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("fitter: error:") and len(err.strip().splitlines()) == 1
    assert message in err, err
    assert not (tmp_path / "out").exists()


def test_without_config_the_person_is_required(capsys):
    assert main(["-q", "run", "--front", "f.png", "-o", "out"]) == 2
    err = capsys.readouterr().err
    assert "--side, --height-cm" in err and "--config" in err


@pytest.mark.parametrize("options, refine", [
    ({}, 40), ({"components": 30}, 40), ({"components": 40}, 0), ({"components": 50}, 0),
    ({"components": 40, "refine_components": 50}, 50), ({"refine_components": 0}, 0)])
def test_components_at_or_past_the_refinement_turn_it_off(options, refine):
    """thorough's refinement over 40 components adds none to a search of 40 or more: it is
    off unless --refine-components is given too (and then validated as given)."""
    from bodyfit.fitter.fit.person_fit import METHODS
    from bodyfit.fitter.run.options import fit_settings

    settings = fit_settings(METHODS["thorough"], {"components": None, **options})
    assert settings.search.refine_components == refine
    assert fit_settings(METHODS["paper"], options).search.refine_components == options.get(
        "refine_components", 0)


def test_the_default_method_reports_the_calibrated_spread(first_run, tmp_path, capsys,
                                                           monkeypatch):
    """A run of other settings than the default method's reports its population's spread;
    one of the default method (here: the first run's settings made the default), with
    another seed, the calibrated ± (fitter/fit/spreads.py): each measurement's factor times
    the answers' mean cost, as written in run.json."""
    first = json.loads((first_run / "measurements.json").read_text())
    assert first["spread_basis"] == "population"
    assert SPREAD_NOTES["population"] in html.unescape((first_run / "report.html").read_text())
    monkeypatch.setitem(fit_module.METHODS, "bodyfit",
                        read_run_config(first_run / "run.json").settings)
    out = tmp_path / "calibrated"
    assert main(["run", "--config", str(first_run / "run.json"), "-o", str(out),
                 "--seed", "6", "--threads", "1"]) == 0
    assert SPREAD_NOTES["calibrated"] in capsys.readouterr().out
    written = json.loads((out / "measurements.json").read_text())
    assert written["spread_basis"] == "calibrated"
    cost = recorded_answer_cost(json.loads((out / "run.json").read_text()))
    factors = bodyfit_calibration().per_cost
    for key, (name, _) in MEASUREMENTS.items():
        assert written["measurements"][name]["spread_mm"] == pytest.approx(
            factors[key] * cost, abs=0.006)
    assert SPREAD_NOTES["calibrated"] in html.unescape((out / "report.html").read_text())


def test_the_arms_lower_bound_is_the_defaults_and_replaced_by_name():
    """bodyfit's arms reach -25 degrees, the searches' -10; --arms-lower-deg sets both
    shoulders and leaves the hips."""
    from bodyfit.fitter.fit.person_fit import METHODS
    from bodyfit.fitter.run.options import fit_settings

    assert METHODS["bodyfit"].search.pose_lower_deg == (-25.0, -25.0, -10.0, -10.0)
    assert METHODS["thorough"].search.pose_lower_deg == (-10.0,) * 4
    assert METHODS["paper"].search.pose_lower_deg == (-10.0,) * 4
    before = fit_settings(METHODS["bodyfit"], {"arms_lower_deg": -10.0})
    assert before.search.pose_lower_deg == (-10.0,) * 4


def test_the_beta_limit_bounds_the_search(first_run):
    """--beta-limit sets the shape components' bounds (the canvases' room is read from
    them); 0 is refused; a run.json from when the canvas held its own copy of the bound
    still reads."""
    from bodyfit.fitter.fit.person_fit import METHODS
    from bodyfit.fitter.run.options import fit_settings

    assert METHODS["bodyfit"].search.beta_limit == 3.0
    wide = fit_settings(METHODS["bodyfit"], {"beta_limit": 5.0})
    assert wide.search.upper[0] == 5.0 and wide.search.lower[0] == -5.0
    with pytest.raises(UserError, match="--beta-limit must be above 0"):
        fit_settings(METHODS["bodyfit"], {"beta_limit": 0.0}).validate(40)
    record = json.loads((first_run / "run.json").read_text())
    record["settings"]["canvas"]["beta_limit"] = 3.0  # as written before
    assert run_config(record).settings == read_run_config(first_run / "run.json").settings
