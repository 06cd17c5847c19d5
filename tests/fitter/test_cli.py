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


def test_demo_writes_meshes_measurements_and_picture(body_model, tmp_path, capsys):
    out_dir = tmp_path / "demo"
    code, out, err = run(capsys, "-q", "demo", "-o", str(out_dir), "--bodies", "2")
    assert code == 0, err
    names = sorted(p.name for p in out_dir.iterdir())
    assert names == ["bodies.png", "body_0.obj", "body_0.ply", "body_1.obj", "body_1.ply",
                     "measurements.csv", "measurements.json"]
    table = json.loads((out_dir / "measurements.json").read_text())
    assert table["units"] == "mm" and set(table["bodies"]) == {"body_0", "body_1"}
    assert len((out_dir / "measurements.csv").read_text().splitlines()) == 1 + 2 * 16
    assert not list(tmp_path.glob(".*partial*"))


def test_measure_writes_json_and_csv(body_model, measurer, tmp_path, capsys):
    mesh = tmp_path / "body.ply"
    write_mesh(mesh, body_model.mean_vertices, body_model.faces)
    code, out, err = run(capsys, "-q", "measure", str(mesh), "-o", str(tmp_path / "m.json"))
    assert code == 0, err
    got = json.loads((tmp_path / "m.json").read_text())["bodies"]["body"]
    expected = measurer.measure(body_model.mean_vertices)
    for key, value in expected.items():
        assert got[key] == pytest.approx(value, abs=0.01)
    assert (tmp_path / "m.csv").exists()


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
])
def test_bad_options_are_one_line_exit_2(capsys, argv, message):
    code, _, err = run(capsys, *argv)
    assert code == 2 and message in err and len(err.strip().splitlines()) == 1
