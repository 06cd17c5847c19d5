"""The `fitter` command line: outputs and one-line errors."""

import json

import numpy as np
import pytest

from bodyfit.fitter.cli import main
from bodyfit.fitter.mesh_io import write_mesh


def run(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


@pytest.fixture(autouse=True)
def no_user_model(tmp_path_factory, monkeypatch):
    """Every CLI test sees a fresh cache: no user-built model, so the shipped one is used."""
    from bodyfit.fitter import model_cache

    monkeypatch.setenv(model_cache.CACHE_ENV_VAR, str(tmp_path_factory.mktemp("cache")))


def test_demo_writes_meshes_measurements_and_picture(body_model, tmp_path, capsys):
    out_dir = tmp_path / "demo"
    code, out, err = run(capsys, "-q", "demo", "-o", str(out_dir), "--bodies", "4")
    assert code == 0, err
    names = sorted(p.name for p in out_dir.iterdir())
    assert names == ["bodies.png"] + [f"body_{i}.{s}" for i in range(4) for s in ("obj", "ply")] \
        + ["measurements.csv", "measurements.json"]
    table = json.loads((out_dir / "measurements.json").read_text())
    assert table["units"] == "mm" and set(table["bodies"]) == {f"body_{i}" for i in range(4)}
    assert len((out_dir / "measurements.csv").read_text().splitlines()) == 1 + 4 * 16
    assert not list(tmp_path.glob(".*partial*"))
    import cv2
    picture = cv2.imread(str(out_dir / "bodies.png"))
    assert picture.shape[0] > 2 * 500  # 4 bodies of 500 px in a 2 x 2 grid, not a strip
    assert picture.shape[1] < 1.5 * picture.shape[0]  # a strip would be 4.7 times wider


def test_version_and_usage_errors(capsys):
    code, out, _ = run(capsys, "--version")
    assert code == 0 and out.startswith("bodyfit ")
    code, _, err = run(capsys, "frobnicate")
    assert code == 2 and err.startswith("fitter: error:") and len(err.strip().splitlines()) == 1
    code, out, _ = run(capsys, "--help")
    assert code == 0 and all(c in out for c in ("run", "demo", "measure", "model"))


def test_demo_with_a_corrupt_user_model_exits_2(tmp_path, capsys):
    from bodyfit.fitter import model_cache

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
    (["demo", "--bodies", "0"], "--bodies"),
    (["model", "build", "-o", "model.txt"], "-o takes a .npz"),
])
def test_bad_options_are_one_line_exit_2(capsys, argv, message):
    code, _, err = run(capsys, *argv)
    assert code == 2 and message in err and len(err.strip().splitlines()) == 1
