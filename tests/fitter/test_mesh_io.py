"""Mesh files: round trips, other topologies, units."""

import numpy as np
import pytest
import trimesh

from bodyfit.common.errors import UserError
from bodyfit.fitter.output.mesh_io import read_mesh, write_mesh


@pytest.mark.parametrize("suffix", [".obj", ".ply"])
def test_round_trip_keeps_vertex_order(body_model, tmp_path, suffix):
    path = tmp_path / f"body{suffix}"
    write_mesh(path, body_model.mean_vertices, body_model.faces)
    got = read_mesh(path, body_model.faces)
    np.testing.assert_allclose(got, body_model.mean_vertices, atol=1e-6)
    assert [p.name for p in tmp_path.iterdir()] == [path.name]  # no temporary left


def test_other_topology_is_refused(body_model, tmp_path):
    path = tmp_path / "sphere.obj"
    trimesh.creation.icosphere().export(path)
    with pytest.raises(UserError, match="another topology"):
        read_mesh(path, body_model.faces)


def test_not_a_mesh_is_refused(body_model, tmp_path):
    path = tmp_path / "junk.ply"
    path.write_bytes(b"\x00\x01garbage")
    with pytest.raises(UserError):
        read_mesh(path, body_model.faces)


def test_millimetre_mesh_read_as_metres_names_the_unit(body_model, tmp_path):
    path = tmp_path / "body_mm.obj"
    write_mesh(path, body_model.mean_vertices * 1000.0, body_model.faces)
    with pytest.raises(UserError, match="--units mm"):
        read_mesh(path, body_model.faces)
    got = read_mesh(path, body_model.faces, units="mm")
    np.testing.assert_allclose(got, body_model.mean_vertices, atol=1e-6)
