"""Fuzzed mesh files: read_mesh answers any .obj or .ply with a one-line UserError.

Needs no body model: the topology is a small icosphere's. Settings (derandomized, no
deadline) come from the "bodyfit" hypothesis profile in tests/conftest.py.
"""

import tempfile
from pathlib import Path

import numpy as np
import pytest
import trimesh
from hypothesis import given
from hypothesis import strategies as st

from bodyfit.common.errors import UserError
from bodyfit.fitter.output.mesh_io import read_mesh

SPHERE = trimesh.creation.icosphere(subdivisions=1, radius=0.85)  # 1.7 m tall: a plausible size
FACES = np.asarray(SPHERE.faces)
OTHER = trimesh.creation.icosphere(subdivisions=0)
ENCODINGS = {
    ".obj": [SPHERE.export(file_type="obj").encode()],
    ".ply": [SPHERE.export(file_type="ply", encoding=e) for e in ("ascii", "binary")],
}


def _read(suffix: str, payload: bytes, units: str = "m"):
    """read_mesh of ``payload`` saved with ``suffix``; None after a one-line UserError."""
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / f"mesh{suffix}"
        path.write_bytes(payload)
        try:
            vertices = read_mesh(path, FACES, units)
        except UserError as error:
            assert str(error) and "\n" not in str(error), repr(str(error))
            return None
    assert vertices.shape == (len(SPHERE.vertices), 3) and np.isfinite(vertices).all()
    return vertices


@given(st.sampled_from(sorted(ENCODINGS)), st.binary(max_size=500))
def test_mesh_of_random_bytes(suffix, payload):
    _read(suffix, payload)


@given(
    st.sampled_from([(suffix, payload) for suffix, payloads in ENCODINGS.items() for payload in payloads]),
    st.integers(0, 10**5),
    st.lists(st.tuples(st.integers(0, 10**5), st.integers(0, 255)), max_size=4),
    st.sampled_from(["m", "cm", "mm"]),
)
def test_mesh_truncated_or_mutated(encoded, cut, flips, units):
    suffix, payload = encoded
    data = bytearray(payload[:cut])
    for position, value in flips:
        if data:
            data[position % len(data)] = value
    _read(suffix, bytes(data), units)


obj_lines = st.one_of(
    st.tuples(st.just("v"), st.lists(st.floats() | st.integers(-(10**6), 10**6), max_size=4)),
    st.tuples(st.just("f"), st.lists(st.integers(-50, 50), max_size=5)),
    st.tuples(
        st.sampled_from(["vn", "vt", "o", "g", "usemtl", "#", "mtllib"]), st.lists(st.text(max_size=5), max_size=3)
    ),
)


@given(st.lists(obj_lines, max_size=30))
def test_obj_text_of_random_lines(lines):
    text = "\n".join(" ".join([kind, *map(str, values)]) for kind, values in lines)
    _read(".obj", text.encode())


@given(st.integers(-5, 10**9), st.integers(-5, 10**9))
def test_ply_header_claiming_any_counts(vertices, faces):
    header = (
        f"ply\nformat {{}} 1.0\nelement vertex {vertices}\nproperty float x\nproperty float y\n"
        f"property float z\nelement face {faces}\nproperty list uchar int vertex_indices\nend_header\n"
    )
    for encoding in ("ascii", "binary_little_endian"):
        _read(".ply", header.format(encoding).encode() + b"0 0 0\n3 0 0 0\n")


def test_other_topology_and_the_valid_sphere():
    assert _read(".obj", OTHER.export(file_type="obj").encode()) is None
    assert _read(".obj", ENCODINGS[".obj"][0]) is not None
    nan_sphere = SPHERE.copy()
    nan_sphere.vertices[3] = np.nan
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "nan.ply"
        path.write_bytes(nan_sphere.export(file_type="ply"))
        with pytest.raises(UserError, match="not finite"):
            read_mesh(path, FACES)
