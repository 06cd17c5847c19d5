"""The `fitter` command line: outputs and one-line errors."""

import json

import numpy as np
import pytest

from bodyfit.fitter.cli.main import main
from bodyfit.fitter.fit.photo_extents import MAX_CHANGE, SCALED
from bodyfit.fitter.output.mesh_io import read_mesh, write_mesh


def run(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


@pytest.fixture(autouse=True)
def no_user_model(tmp_path_factory, monkeypatch):
    """Every CLI test sees a fresh cache: no user-built model, so the shipped one is used."""
    from bodyfit.fitter.model import cache as model_cache

    monkeypatch.setenv(model_cache.CACHE_ENV_VAR, str(tmp_path_factory.mktemp("cache")))


def test_demo_calibrates_fits_and_measures_against_the_truth(body_model, measurer, tmp_path,
                                                             capsys, monkeypatch):
    import re
    import shlex

    from bodyfit.fitter.demo.example import DemoSettings, demo_camera
    from bodyfit.fitter.fit.measurement_prior import MeasurementPrior, combined
    from bodyfit.fitter.fit.spreads import SPREAD_NOTES, bodyfit_calibration, recorded_answer_cost
    from bodyfit.fitter.measure.measurements import IMPORTANT, MEASUREMENTS
    from bodyfit.fitter.model.body_model import rest_shape
    from bodyfit.fitter.run.results import RUN_FILES

    monkeypatch.chdir(tmp_path)
    code, out, err = run(capsys, "-q", "demo", "-o", "demo")
    assert code == 0, err
    out_dir = tmp_path / "demo"
    assert sorted(p.name for p in out_dir.iterdir()) == [
        "board", "camera.json", "camera_coverage.png", "fit", "front.png", "side.png",
        "truth.json"]
    assert len(list((out_dir / "board").glob("*.png"))) == 12 + 2
    assert sorted(p.name for p in (out_dir / "fit").iterdir()) == sorted(RUN_FILES)
    # the calibration recovered the synthetic phone camera
    true_camera = demo_camera(DemoSettings().size_px)
    camera = json.loads((out_dir / "camera.json").read_text())
    assert camera["K"][0][0] == pytest.approx(true_camera.K[0, 0], rel=0.01)
    assert camera["provenance"]["argv"][:2] == ["calib", "capture"]
    # truth.json holds the true camera and the measurements of the body it records
    truth_record = json.loads((out_dir / "truth.json").read_text())
    np.testing.assert_allclose(truth_record["camera"]["K"], true_camera.K)
    betas = np.array(truth_record["body"]["betas_sigma"])
    expected = measurer.measure(rest_shape(body_model, betas[None])[0][0])
    truth = {row["letter"]: row["value_mm"] for row in truth_record["measurements"].values()}
    for key in MEASUREMENTS:
        assert truth[key] == pytest.approx(expected[key], abs=0.01)
    # the fit went through `fitter run --camera` with its default settings: the local
    # solver from the learned start over 40 components, no population search
    record = json.loads((out_dir / "fit" / "run.json").read_text())
    assert record["settings"]["projection"] == "pinhole"
    assert record["settings"]["search"]["searches"] == 0
    assert record["settings"]["solver"]["iterations"] == 40
    assert record["settings"]["solver"]["start"] == "learned"
    assert record["settings"]["solver"]["pitch"] == "searched"
    assert record["settings"]["solver"]["hands"] == "fitted"  # the demo's are the rest
    twists = record["result"]["hand_twist_deg"]  # pose's, palms in (measured: -0.1, -0.0)
    assert set(twists) == {"left", "right"} and max(map(abs, twists.values())) < 5.0
    assert set(record["photos"]["pitch_deg"].values()) <= {-4.0, 0.0, 4.0}
    assert len(record["result"]["betas"]) == 40
    assert record["inputs"]["camera"] == "demo/camera.json"
    written = json.loads((out_dir / "fit" / "measurements.json").read_text())
    fitted = {row["letter"]: row["value_mm"] for row in written["measurements"].values()}
    spreads = {row["letter"]: row["spread_mm"] for row in written["measurements"].values()}
    assert fitted["O"] == pytest.approx(truth["O"], abs=0.6)  # given in cm to 1 decimal
    # the mesh's measurements but for the girths scaled to the photos, which move by less
    # than their bound (photo_extents: the fit's pinhole views take them), each weighed
    # against the prior for the person's stature by the calibrated ± of the fit's cost
    mesh = measurer.measure(read_mesh(out_dir / "fit" / "mesh_rest.ply", body_model.faces))
    own = bodyfit_calibration().spreads(recorded_answer_cost(record))
    person = record["inputs"]
    expected, expected_spreads = combined(mesh, own, *MeasurementPrior.load().predict(
        person["sex"], 10.0 * person["height_cm"], person["mass_kg"]))
    for key in MEASUREMENTS:
        assert spreads[key] == pytest.approx(expected_spreads[key], abs=0.01), key
        if key in SCALED:
            assert abs(fitted[key] / mesh[key] - 1) < MAX_CHANGE, key
        else:
            assert fitted[key] == pytest.approx(expected[key], abs=0.01), key
    # the printed table: 16 rows of fitted, ±, true and error, then the important ones'
    # mean; the ±'s kind named (the default method's: calibrated)
    rows = re.findall(r"^  ([A-P]) .+? +(-?\d+\.\d) +(\d+\.\d) +(-?\d+\.\d) +([+-]\d+\.\d)$",
                      out, re.MULTILINE)
    assert [key for key, *_ in rows] == list(MEASUREMENTS)
    assert written["spread_basis"] == "calibrated" and SPREAD_NOTES["calibrated"] in out
    for key, value, spread, true, error in rows:
        assert float(value) == pytest.approx(fitted[key], abs=0.06)
        assert float(spread) == pytest.approx(spreads[key], abs=0.06)
        assert float(true) == pytest.approx(truth[key], abs=0.06)
        assert float(error) == pytest.approx(fitted[key] - truth[key], abs=0.11)
    mae = float(re.search(r"7 important .*: (\d+\.\d) mm", out).group(1))
    assert mae == pytest.approx(np.mean([abs(fitted[k] - truth[k]) for k in IMPORTANT]),
                                abs=0.06)
    # the printed command fits the photos again by hand: the same body
    command = re.search(r"by hand: fitter (.+)$", out, re.MULTILINE).group(1)
    code, _, err = run(capsys, "-q", *shlex.split(command))
    assert code == 0, err
    again = json.loads((out_dir / "fit" / "measurements.json").read_text())["measurements"]
    assert {row["letter"]: row["value_mm"] for row in again.values()} == fitted
    assert not list(tmp_path.glob(".*partial*"))


def test_version_and_usage_errors(capsys):
    code, out, _ = run(capsys, "--version")
    assert code == 0 and out.startswith("bodyfit ")
    code, _, err = run(capsys, "frobnicate")
    assert code == 2 and err.startswith("fitter: error:") and len(err.strip().splitlines()) == 1
    code, out, _ = run(capsys, "--help")
    assert code == 0 and all(c in out for c in ("run", "demo", "measure", "model"))


@pytest.mark.parametrize("command", ["run", "batch"])
def test_help_states_the_search_defaults(capsys, command):
    """The help's "(default N)" of each search option is the default method's own."""
    import re

    from bodyfit.fitter.fit.person_fit import FitSettings

    code, out, _ = run(capsys, command, "--help")
    assert code == 0
    text = " ".join(out.split())
    defaults = FitSettings().search
    for option, value in (("--population", defaults.population),
                          ("--generations", defaults.generations),
                          ("--searches", defaults.searches),
                          ("--iterations", FitSettings().solver.iterations),
                          ("--refine-generations", defaults.refine_generations),
                          ("--refinements", defaults.refinements)):
        stated = re.search(rf"{option} [A-Z_]+ (?:(?! --[a-z]).)*?\(default (\d+)", text)
        assert stated and int(stated.group(1)) == value, option


def test_demo_with_a_corrupt_user_model_exits_2(tmp_path, capsys):
    from bodyfit.fitter.model import cache as model_cache

    model_cache.model_path().write_bytes(b"garbage")
    code, _, err = run(capsys, "demo", "-o", str(tmp_path / "demo"))
    assert code == 2 and "corrupt" in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "demo").exists()
    assert model_cache.model_path().read_bytes() == b"garbage"  # not silently rebuilt


def test_model_info_names_the_shipped_model(capsys):
    code, out, err = run(capsys, "model", "info")
    assert code == 0, err
    assert "shipped with bodyfit" in out and "anny" in out


def test_measure_writes_json_and_csv(body_model, measurer, tmp_path, capsys):
    mesh = tmp_path / "body.ply"
    write_mesh(mesh, body_model.mean_vertices, body_model.faces)
    target = tmp_path / "m" / "b1.json"  # README's example: the folder does not exist yet
    code, out, err = run(capsys, "-q", "measure", str(mesh), "-o", str(target))
    assert code == 0, err
    got = json.loads(target.read_text())["bodies"]["body"]
    expected = measurer.measure(body_model.mean_vertices)
    for key, value in expected.items():
        assert got[key] == pytest.approx(value, abs=0.01)
    assert (tmp_path / "m" / "b1.csv").exists()


@pytest.mark.parametrize("content,name,message", [
    (b"hello", "notes.txt", "not a mesh file"),
    (b"\x00garbage", "broken.obj", "not a readable mesh|holds no triangle mesh|another topology"),
    (None, "missing.obj", "no such file"),
])
def test_measure_bad_input_is_one_line_exit_2(body_model, tmp_path, capsys, content, name,
                                             message):
    path = tmp_path / name
    if content is not None:
        path.write_bytes(content)
    code, out, err = run(capsys, "measure", str(path), "-o", str(tmp_path / "m.json"))
    assert code == 2
    assert len(err.strip().splitlines()) == 1 and err.startswith("fitter: error:")
    import re
    assert re.search(message, err)
    assert not (tmp_path / "m.json").exists()


def test_measure_other_topology_exit_2(body_model, tmp_path, capsys):
    import trimesh
    path = tmp_path / "box.obj"
    trimesh.creation.box([1, 1, 1]).export(path)
    code, _, err = run(capsys, "measure", str(path))
    assert code == 2 and "another topology" in err and len(err.strip().splitlines()) == 1


@pytest.mark.parametrize("argv,message", [
    (["model", "build", "--samples", "7"], "--samples"),
    (["model", "build", "--components", "0"], "--components"),
    (["model", "build", "--girth-spread", "0"], "--girth-spread"),
    (["demo", "--method", "fast"], "--method"),
    (["demo", "-o", __file__], "is a file"),
    (["demo", "-o", f"{__file__}/inside"], "is a file"),  # a parent that is a file
    (["model", "build", "-o", "model.txt"], "-o takes a .npz"),
])
def test_bad_options_are_one_line_exit_2(capsys, argv, message):
    code, _, err = run(capsys, *argv)
    assert code == 2 and message in err and len(err.strip().splitlines()) == 1


@pytest.mark.parametrize("content", [b"garbage", None])
def test_demo_with_a_corrupt_or_foreign_learned_start_exits_2(body_model, tmp_path, capsys,
                                                               content):
    import dataclasses

    from bodyfit.fitter.fit.learned_start import (LearnedStart, shipped_start_path,
                                                  trained_start_path)

    path = trained_start_path()
    if content is None:  # weights trained for another body model
        start = LearnedStart.load(shipped_start_path())
        dataclasses.replace(start, fingerprint="0" * 16).save(path)
    else:
        path.write_bytes(content)
    code, _, err = run(capsys, "demo", "-o", str(tmp_path / "demo"))
    assert code == 2 and len(err.strip().splitlines()) == 1
    assert ("corrupt" if content else "another body model") in err and "train-start" in err
    assert not (tmp_path / "demo").exists()
