"""Reading and writing body meshes (.obj, .ply) with trimesh, in the model's topology.

Files hold vertices in metres, model frame (z up, -y forward) unless a unit is given
when reading. Vertex order is kept exactly (trimesh's merging and reordering are off),
so a written body reads back as the same (V, 3) array.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import trimesh

from bodyfit.common.errors import UserError
from bodyfit.common.files import write_atomic

__all__ = ["MESH_SUFFIXES", "UNITS_TO_METRES", "write_mesh", "read_mesh"]

MESH_SUFFIXES = (".obj", ".ply")
UNITS_TO_METRES = {"m": 1.0, "cm": 0.01, "mm": 0.001}
_PLAUSIBLE_HEIGHT_M = (0.8, 2.6)


def write_mesh(path: Path, vertices: np.ndarray, faces: np.ndarray) -> None:
    """Write a triangle mesh atomically; the format follows the suffix (.obj or .ply).

    Args:
        vertices: (V, 3) float, metres.
        faces: (F, 3) int.
    """
    path = Path(path)
    if path.suffix.lower() not in MESH_SUFFIXES:
        raise UserError(f"cannot write {path}: mesh files end in .obj or .ply")
    mesh = trimesh.Trimesh(np.asarray(vertices, np.float64), np.asarray(faces), process=False)
    data = mesh.export(file_type=path.suffix.lower()[1:])
    write_atomic(path, data if isinstance(data, bytes) else data.encode())


def read_mesh(path: Path, faces: np.ndarray, units: str = "m") -> np.ndarray:
    """Vertices of a mesh file that must be in the model's topology.

    Args:
        faces: (F, 3) int, the model's triangles; the file's must be identical.
        units: the file's length unit, "m", "cm" or "mm".

    Returns:
        (V, 3) float64 vertices in metres.

    Raises:
        UserError: unreadable file, not a triangle mesh, another topology, or a size
            that does not fit the stated unit.
    """
    path = Path(path)
    if not path.is_file():
        raise UserError(f"no such file: {path}")
    if path.suffix.lower() not in MESH_SUFFIXES:
        raise UserError(f"{path} is not a mesh file (.obj or .ply expected)")
    try:
        mesh = trimesh.load(path, process=False, force="mesh")
    except Exception as exc:  # trimesh raises many types for malformed files
        raise UserError(f"{path} is not a readable mesh ({type(exc).__name__}: {exc})") from None
    if not isinstance(mesh, trimesh.Trimesh) or len(mesh.faces) == 0:
        raise UserError(f"{path} holds no triangle mesh")
    if mesh.vertices.shape[0] != faces.max() + 1 or not np.array_equal(mesh.faces, faces):
        raise UserError(
            f"{path} is a mesh of another topology ({len(mesh.vertices)} vertices, "
            f"{len(mesh.faces)} faces); bodyfit measures meshes in its body model's "
            f"topology ({faces.max() + 1} vertices, {len(faces)} faces), such as the "
            "mesh.obj files that `fitter run` writes")
    if not np.isfinite(mesh.vertices).all():
        raise UserError(f"{path} holds vertex coordinates that are not finite numbers (NaN or infinity)")
    vertices = mesh.vertices * UNITS_TO_METRES[units]
    height = np.ptp(vertices[:, 2])
    lo, hi = _PLAUSIBLE_HEIGHT_M
    if not lo <= height <= hi:
        guess = min(UNITS_TO_METRES, key=lambda u: abs(np.log(
            np.ptp(mesh.vertices[:, 2]) * UNITS_TO_METRES[u] / 1.7)))
        raise UserError(f"{path} is {height:.3g} m tall in unit '{units}'; a person is "
                        f"{lo}-{hi} m. Its unit looks like '{guess}': pass --units {guess}")
    return vertices
