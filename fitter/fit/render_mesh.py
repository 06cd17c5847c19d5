"""A lighter mesh for scoring candidates: head and feet clustered, the rest as it is.

Head and feet hold 47 % of the model's triangles (12,414 of 26,692), mostly smaller than a
canvas pixel (4-5 mm), and every triangle costs the rasteriser a setup whether it covers a
pixel centre or not. :func:`render_model` merges those parts' vertices that fall
in one cube of ``cell_mm`` (per part, in the mean body's rest shape; each cluster keeps
its member nearest the cluster's centroid, so the kept vertices are the model's own and
skin exactly as before) and drops the triangles that collapse. Kept as they are: every
other part, the vertices on a seam with another part (the mesh stays closed) and those
within ``_EXTREME_BAND_M`` of the body's top and bottom (a candidate's rendered height is
the height the stature conditioning solved for).

The model it returns is a :class:`~bodyfit.fitter.model.body_model.BodyModel` over the kept
vertices (with the landmarks whose vertices are all kept, such as the limbs' rings): the
kernels render and score it, the local solver bends its elbows by its rings; the fitted body, its
measurements and the pictures use the full model. At 8 mm: 19,900 triangles, 9,874
vertices; the kernels' speed: docs/fitter.md, "Speed".

The hands (6,380 triangles) were clustered too until docs/history.md [34]: a hand
of 8 mm cubes reaches about 1 mm less far than the model's, which the fits paid for with
longer arms (the arm length's error in-space 3.10 -> 2.59 mm with the hands left whole).
"""

from __future__ import annotations

import dataclasses
import functools

import numpy as np

from bodyfit.fitter.model.body_model import PART_NAMES, BodyModel

__all__ = ["CLUSTERED_PARTS", "render_model"]

#: The parts whose vertices are clustered.
CLUSTERED_PARTS = ("head", "foot")
#: Vertices this close (metres) to the mean body's highest or lowest point are kept.
_EXTREME_BAND_M = 0.01


@functools.lru_cache(maxsize=4)
def render_model(model: BodyModel, cell_mm: float) -> BodyModel:
    """The model with ``CLUSTERED_PARTS`` clustered to ``cell_mm`` cubes (module docstring);
    ``cell_mm`` 0 returns ``model`` itself. Made once per model and cell (a fit asks for
    it for its evaluators and its local solver, a batch for every subject; the same
    object each time, so what is cached per model, its scaled shape directions, is too).

    Raises:
        ValueError: a negative cell size.
    """
    if cell_mm < 0:
        raise ValueError(f"the render mesh's cell must be >= 0 mm, got {cell_mm}")
    if cell_mm == 0:
        return model
    rest = model.mean_vertices.astype(np.float64)
    clustered = [PART_NAMES.index(name) for name in CLUSTERED_PARTS]
    on_other_faces = np.zeros(len(rest), bool)
    on_other_faces[model.faces[~np.isin(model.face_parts, clustered)].ravel()] = True
    height = rest[:, 2]
    extreme = (height >= height.max() - _EXTREME_BAND_M) | \
        (height <= height.min() + _EXTREME_BAND_M)
    merged = np.isin(model.vertex_parts, clustered) & ~on_other_faces & ~extreme
    # cluster key: (part, cell); a vertex that is not merged gets a key of its own
    keys = np.column_stack([model.vertex_parts.astype(np.int64),
                            np.floor(rest * 1000.0 / cell_mm).astype(np.int64)])
    keys[~merged] = -1 - np.arange(np.count_nonzero(~merged))[:, None]
    cluster = np.unique(keys, axis=0, return_inverse=True)[1].ravel()
    count = np.bincount(cluster)
    centroid = np.zeros((len(count), 3))
    np.add.at(centroid, cluster, rest)
    centroid /= count[:, None]
    # each cluster's member nearest its centroid: the first of its members by distance
    order = np.lexsort((np.linalg.norm(rest - centroid[cluster], axis=1), cluster))
    first = np.r_[True, cluster[order][1:] != cluster[order][:-1]]
    keeper = np.empty(len(count), np.int64)
    keeper[cluster[order][first]] = order[first]
    faces = keeper[cluster[model.faces]]
    whole = (faces[:, 0] != faces[:, 1]) & (faces[:, 1] != faces[:, 2]) & \
        (faces[:, 0] != faces[:, 2])
    faces = faces[whole]
    once = np.sort(np.unique(np.sort(faces, axis=1), axis=0, return_index=True)[1])
    kept, faces = np.unique(faces[once], return_inverse=True)
    index = np.full(len(rest), -1)
    index[kept] = np.arange(len(kept))
    return dataclasses.replace(
        model, mean_vertices=model.mean_vertices[kept],
        vertex_components=model.vertex_components[:, kept],
        faces=faces.reshape(-1, 3).astype(model.faces.dtype),
        vertex_parts=model.vertex_parts[kept], chain_weights=model.chain_weights[kept],
        landmarks={name: index[vertices] for name, vertices in model.landmarks.items()
                   if np.all(index[vertices] >= 0)})
