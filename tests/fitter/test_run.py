"""`fitter run` end to end on synthetic photos, its outputs, and its bad input."""

import dataclasses
import json

import cv2
import numpy as np
import pytest

from bodyfit.fitter.cli.main import main
from bodyfit.fitter.demo.studio_photos import BACKDROP_BGR, write_subject
from bodyfit.fitter.fit.contour import contour_points
from bodyfit.fitter.fit.person import PersonInputs
from bodyfit.fitter.fit.person_fit import FitSettings, fit_inputs
from bodyfit.fitter.fit.search import SearchSettings
from bodyfit.fitter.fit.spreads import POOR_MATCH_COST
from bodyfit.fitter.output.overlays import match_contours, outline_in_photo
from bodyfit.fitter.run.results import RUN_FILES

TRUE_BETAS = np.array([0.8, -0.6, 0.5, 0.3, -0.4] + [0.0] * 15)
TRUE_POSE = np.array([6.0, 6.0, 3.0, 3.0])
BUDGET = ["--method", "thorough", "--optimizer", "cmaes", "--population", "24", "--generations", "30", "--seed", "1",
          "--refine-components", "0"]


@pytest.fixture(scope="module")
def subject(body_model, tmp_path_factory):
    folder = tmp_path_factory.mktemp("subject")
    truth = write_subject(folder, body_model, TRUE_BETAS, TRUE_POSE)
    return folder, truth


def run(capsys, *argv):
    code = main(["-q", *argv])
    out, err = capsys.readouterr()
    return code, out, err


def person_args(folder, truth):
    """The subject's options; its studio photos are orthographic."""
    return ["--front", str(folder / "front.png"), "--side", str(folder / "side.png"),
            "--height-cm", f"{truth['O'] / 10:.2f}", "--projection", "orthographic"]


def test_run_writes_every_output_and_fits_the_silhouettes(subject, tmp_path, capsys):
    folder, truth = subject
    out = tmp_path / "out"
    code, stdout, err = run(capsys, "run", *person_args(folder, truth), "-o", str(out), *BUDGET,
                            "--segmenter", "backdrop")
    assert code == 0, err
    assert sorted(p.name for p in out.iterdir()) == sorted(RUN_FILES)
    assert {"overlay_front.png", "overlay_side.png", "report.html"} <= set(RUN_FILES)
    assert "chest circumference" in stdout and str(out / "mesh.obj") in stdout
    table = json.loads((out / "measurements.json").read_text())["measurements"]
    assert len(table) == 16 and table["stature"]["letter"] == "O"
    assert all(row["spread_mm"] >= 0 for row in table.values())
    # the stature is an input: the fit stands it to within the height's rounding (0.05 mm)
    assert table["stature"]["value_mm"] == pytest.approx(truth["O"], abs=0.2)
    record = json.loads((out / "run.json").read_text())
    assert record["inputs"]["segmenter"] == "backdrop"
    assert record["settings"]["search"]["optimizer"] == "cmaes"
    assert record["settings"]["side_arms"] == "down"
    assert record["settings"]["search"]["searches"] == 2
    assert record["result"]["evaluations"] == 2 * 24 * 30  # two searches, averaged
    costs = record["result"]["best_cost_per_generation"]
    assert costs[-1] < costs[0] and all(np.diff(costs) <= 0)
    assert cv2.imread(str(out / "convergence.png")).shape == (480, 800, 3)


def test_default_fit_measures_the_subject(subject, tmp_path, capsys):
    """The default method end to end (the local solver from the mean body): the stature, an
    input, to within its rounding; chest, waist and hip within 8 mm of the truth."""
    folder, truth = subject
    out = tmp_path / "out"
    code, _, err = run(capsys, "run", *person_args(folder, truth), "-o", str(out))
    assert code == 0, err
    table = json.loads((out / "measurements.json").read_text())["measurements"]
    fitted = {row["letter"]: row["value_mm"] for row in table.values()}
    assert fitted["O"] == pytest.approx(truth["O"], abs=0.2)
    for key in ("D", "E", "F"):
        assert abs(fitted[key] - truth[key]) < 8.0, (key, fitted[key], truth[key])


@pytest.mark.parametrize("from_right", [False, True])
def test_the_fitted_outline_lies_on_the_photos_silhouette(subject, body_model, tmp_path,
                                                          from_right):
    """The default fit's outline, moved from the canvas into the photo, runs along the
    person's silhouette there (the side photo from the right mirrored back)."""
    folder, truth = subject
    side = folder / "side.png"
    if from_right:
        side = tmp_path / "side_from_right.png"
        cv2.imwrite(str(side), cv2.imread(str(folder / "side.png"))[:, ::-1])
    inputs = PersonInputs(str(folder / "front.png"), str(side), truth["O"] / 10)
    fit = fit_inputs(body_model, inputs, dataclasses.replace(FitSettings(),
                                                             projection="orthographic"))
    assert fit.photos["side_from"] == ("right" if from_right else "left")
    for view in ("front", "side"):
        mirrored = view == "side" and from_right
        matched = match_contours(body_model, fit.view_bodies[view], fit.views[view])
        outline = outline_in_photo(matched, fit.masks[view], mirrored)
        photo_mask = fit.masks[view][:, ::-1] if mirrored else fit.masks[view]
        edge = np.ones(photo_mask.shape, np.uint8)
        edge[tuple(np.round(contour_points(photo_mask)).astype(int)[:, ::-1].T)] = 0
        distance = cv2.distanceTransform(edge, cv2.DIST_L2, 5)
        columns, rows = np.round(outline).astype(int).T
        assert np.median(distance[rows, columns]) < 1.5, view


def test_a_silhouette_that_took_in_a_lamp_is_warned_of(subject, tmp_path, capsys):
    """A dark lamp merged with the head in the side photo (60 px, 8 % of the height) leaves
    the fit's answer cost over POOR_MATCH_COST: the run warns on stderr, in run.json and
    in the report, and still writes its outputs; the clean photos are not warned of."""
    folder, truth = subject
    side = cv2.copyMakeBorder(cv2.imread(str(folder / "side.png")), 60, 0, 0, 0,
                              cv2.BORDER_CONSTANT, value=BACKDROP_BGR)
    rows, cols = np.nonzero(np.abs(side.astype(int) - BACKDROP_BGR).sum(axis=2) > 30)
    top, centre = rows.min(), int(cols[rows == rows.min()].mean())
    side[top - 60:top + 4, centre - 20:centre + 20] = (60, 60, 60)
    cv2.imwrite(str(tmp_path / "side.png"), side)
    args = person_args(folder, truth)
    for name, side_photo in (("clean", folder / "side.png"), ("lamp", tmp_path / "side.png")):
        args[args.index("--side") + 1] = str(side_photo)
        code, _, err = run(capsys, "run", *args, "-o", str(tmp_path / name))
        assert code == 0, err
        record = json.loads((tmp_path / name / "run.json").read_text())
        warned = "matches the silhouettes poorly" in err
        assert warned == (name == "lamp") == ("fit_warning" in record["photos"])
        assert warned == (record["result"]["best_cost"] > POOR_MATCH_COST)
        assert warned == ("matches the silhouettes poorly"
                          in (tmp_path / name / "report.html").read_text())


def test_same_seed_same_result(subject, tmp_path, capsys):
    folder, truth = subject
    budget = ["--method", "thorough", "--optimizer", "ga", "--population", "12", "--generations", "3", "--seed", "4",
              "--refine-components", "0"]
    runs = []
    for name in ("a", "b"):
        code, _, err = run(capsys, "run", *person_args(folder, truth), "-o",
                           str(tmp_path / name), *budget)
        assert code == 0, err
        runs.append(json.loads((tmp_path / name / "run.json").read_text())["result"])
    assert runs[0]["betas"] == runs[1]["betas"] and runs[0]["best_cost"] == runs[1]["best_cost"]


def test_two_searches_answer_with_the_mean_of_their_answers(subject, tmp_path, capsys):
    """--searches 2 (the default) with seed 4 answers with the mean pose and the mean of
    betas 2..K of the single searches with seeds 4 and 5 (the first beta is solved anew
    from the stature), scored by the kernels at its own cost."""
    folder, truth = subject
    budget = ["--method", "thorough", "--population", "8", "--generations", "4",
              "--refine-components", "0"]
    results = {}
    for name, options in (("4", ["--searches", "1", "--seed", "4"]),
                          ("5", ["--searches", "1", "--seed", "5"]),
                          ("both", ["--seed", "4"])):
        code, _, err = run(capsys, "run", *person_args(folder, truth), "-o",
                           str(tmp_path / name), *budget, *options)
        assert code == 0, err
        results[name] = json.loads((tmp_path / name / "run.json").read_text())["result"]
    single = [np.array(results[name]["betas"]) for name in ("4", "5")]
    both = np.array(results["both"]["betas"])
    np.testing.assert_allclose(both[1:], (single[0][1:] + single[1][1:]) / 2, atol=1e-6)
    assert not np.allclose(single[0][1:], single[1][1:])
    for joint, angle in results["both"]["pose_deg"].items():
        assert angle == pytest.approx((results["4"]["pose_deg"][joint]
                                       + results["5"]["pose_deg"][joint]) / 2)
    assert results["both"]["evaluations"] == 2 * 8 * 4
    assert sum(results["both"]["part_costs"].values()) == pytest.approx(
        results["both"]["best_cost"], rel=1e-5)


def test_refinement_continues_from_the_searches_over_more_components(subject, tmp_path,
                                                                     capsys):
    """--refine-components 24: the searches run as without it (their curves and
    per-generation answers the same, the answers padded with zero components), then the
    refinements' generations follow, ``SearchSettings.refinements`` of them by default (one
    with --refinements 1); the answer has 24 components, scored at its cost."""
    folder, truth = subject
    n = SearchSettings().refinements
    budget = ["--method", "thorough", "--population", "8", "--generations", "4", "--seed", "4"]
    refine = ["--refine-components", "24", "--refine-generations", "3"]
    results = {}
    for name, options in (("searches", ["--refine-components", "0"]), ("refined", refine),
                          ("one", [*refine, "--refinements", "1"])):
        code, _, err = run(capsys, "run", *person_args(folder, truth), "-o",
                           str(tmp_path / name), *budget, *options)
        assert code == 0, err
        results[name] = json.loads((tmp_path / name / "run.json").read_text())["result"]
    searches, refined = results["searches"], results["refined"]
    assert len(refined["betas"]) == 24 and len(searches["betas"]) == 20
    assert refined["evaluations"] == 2 * 8 * 4 + n * 8 * 3 and refined["generations"] == 7
    assert results["one"]["evaluations"] == 2 * 8 * 4 + 8 * 3
    assert refined["best_cost_per_generation"][:4] == searches["best_cost_per_generation"]
    answers = np.array(refined["best_betas_per_generation"])
    np.testing.assert_allclose(answers[:4, :20], searches["best_betas_per_generation"])
    assert not answers[:4, 20:].any() and answers[4:, 20:].any()
    assert not np.allclose(refined["betas"], results["one"]["betas"])
    # run.json holds the answers averaged: the n refinements' (run side by side; the
    # first equals the refinement of the same seed run alone), the two searches' without
    # refinements, none for one refinement
    averaged = refined["averaged"]
    assert len(averaged) == n and len(searches["averaged"]) == 2
    assert results["one"]["averaged"] == []
    assert averaged[0]["betas"] == results["one"]["betas"]
    np.testing.assert_allclose(np.mean([a["betas"] for a in averaged], axis=0)[1:],
                               refined["betas"][1:], atol=1e-9)
    for joint, angle in refined["pose_deg"].items():
        assert angle == pytest.approx(np.mean([a["pose_deg"][joint] for a in averaged]))
    assert all(a["cost"] > 0 for a in averaged)
    assert sum(refined["part_costs"].values()) == pytest.approx(refined["best_cost"],
                                                                rel=1e-5)
    assert f"24 components, 3 generations, {n} averaged" in (tmp_path / "refined"
                                                             / "report.html").read_text()


def test_weight_override_reaches_the_cost(subject, tmp_path, capsys):
    folder, truth = subject
    budget = ["--method", "thorough", "--optimizer", "ga", "--population", "8",
              "--generations", "1", "--refine-components", "0"]
    costs = {}
    for name, extra in (("paper", []), ("waist", ["--weight", "waist=50"])):
        code, _, err = run(capsys, "run", *person_args(folder, truth), "-o",
                           str(tmp_path / name), *budget, *extra)
        assert code == 0, err
        record = json.loads((tmp_path / name / "run.json").read_text())
        costs[name] = record["result"]["part_costs"]["waist"]
        assert record["settings"]["cost"]["part_weights"][2] == (50.0 if extra else 5.0)
    assert costs["waist"] == pytest.approx(10 * costs["paper"], rel=1e-4)


@pytest.mark.parametrize("change,message", [
    ({"--height-cm": "1.80"}, "centimetres"),
    ({"--height-cm": "400"}, "centimetres"),
    ({"--front": "missing.png"}, "no such file"),
    ({"--side": "."}, "is a folder, not a file"),
    ({"--weight": "knee=3"}, "unknown"),
    ({"--weight": "waist"}, "NAME=VALUE|="),
    ({"--weights": "heavy"}, "heavy"),
    ({"--optimizer": "sgd"}, "invalid choice"),
    ({"--components": "99"}, "components"),
    ({"--refine-components": "20"}, "refine-components must be 0 or 21-"),
    ({"--refinements": "0"}, "--refinements must be at least 1"),
    ({"--matching": "both"}, "matching"),
    ({"--side-arms": "up"}, "invalid choice"),
    ({"--threads": "0"}, "--threads"),
    ({"--mass-kg": "350"}, "--mass-kg must be a body mass in kilograms, 25-300; got 350"),
    ({"--mass-kg": "160"}, r"--mass-kg 160 is 2\.0 times what the body in the photos "
                           r"weighs \(about 8\d kg\): give this person's mass in kilograms"),
    ({"--mass-kg": "30"}, r"--mass-kg 30 is 0\.4 times what the body"),
    ({"--measurement-prior": "soldiers"}, "invalid choice"),
    ({"--iterations": "-1"}, "--iterations must be >= 0"),
    ({"--iterations": "0", "--start": "mean"}, "--searches 0 needs the local solver"),
    ({"--searches": "1", "--start": "learned"}, "--start learned needs --searches 0"),
    ({"swap": True}, "swapped"),
    ({"blank": True}, "no person"),
    ({"front twice": True}, r"is (\d\.\d\d) of its height wide and the side one \1: .*the "
                            "person's left or right"),
    ({"arms down": True}, "the side one 0.30: .*the arms held out from the body"),
    ({"lying down": True}, "the front photo: the person is not upright"),
    ({"mirror selfie": True}, "the front photo: a hand is raised above the shoulders"),
])
def test_bad_input_is_one_line_exit_2_and_writes_nothing(subject, body_model, tmp_path, capsys,
                                                         change, message):
    folder, truth = subject
    args = dict(zip(person_args(folder, truth)[::2], person_args(folder, truth)[1::2]))
    if change.pop("swap", False):
        args["--front"], args["--side"] = args["--side"], args["--front"]
    if change.pop("front twice", False):
        args["--side"] = args["--front"]
    if change.pop("arms down", False):  # the arms hanging: 45 degrees below the rest A-pose
        write_subject(tmp_path, body_model, TRUE_BETAS, np.array([-45.0, -45.0, 3.0, 3.0]))
        args["--front"] = str(tmp_path / "front.png")
    if change.pop("lying down", False):  # the photo turned on its side
        front = tmp_path / "lying.png"
        cv2.imwrite(str(front), np.ascontiguousarray(np.rot90(cv2.imread(args["--front"]))))
        args["--front"] = str(front)
    if change.pop("mirror selfie", False):  # the left hand raised to hold a phone up
        write_subject(tmp_path, body_model, TRUE_BETAS, np.array([110.0, 6.0, 3.0, 3.0]))
        args["--front"] = str(tmp_path / "front.png")
    if change.pop("blank", False):
        blank = tmp_path / "blank.png"
        cv2.imwrite(str(blank), np.full((800, 600, 3), 180, np.uint8))
        args["--front"] = str(blank)
    args.update(change)
    argv = [item for pair in args.items() for item in pair]
    out = tmp_path / "out"
    code, _, err = run(capsys, "run", *argv, "-o", str(out), "--generations", "1",
                       "--refine-generations", "1")
    assert code == 2
    assert err.startswith("fitter: error:") and len(err.strip().splitlines()) == 1
    import re
    assert re.search(message, err), err
    assert not out.exists()


def test_non_empty_output_folder_needs_overwrite(subject, tmp_path, capsys):
    folder, truth = subject
    (tmp_path / "out").mkdir()
    (tmp_path / "out" / "notes.txt").write_text("mine")
    code, _, err = run(capsys, "run", *person_args(folder, truth), "-o", str(tmp_path / "out"))
    assert code == 2 and "not empty" in err and "--overwrite" in err
    assert [p.name for p in (tmp_path / "out").iterdir()] == ["notes.txt"]
