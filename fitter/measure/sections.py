"""Plane sections of a body mesh and their tape-measure length.

A tape measure drawn around a body part follows the convex hull of the part's cross
section: it bridges the concave dips (the gap between the buttocks, the navel). So a
circumference here is the perimeter of the 2D convex hull of the points where the plane
cuts the mesh's edges. The edges considered can be restricted to a region (one limb, the
torso without the arms), which is how a tape is kept off the neighbouring parts.

All lengths are metres, model frame.
"""

from __future__ import annotations

import cv2
import numpy as np

__all__ = ["mesh_edges", "region_edges", "plane_basis", "hull_perimeter", "tape_lengths",
           "section_axes", "section_points", "section_centre"]


def mesh_edges(faces: np.ndarray) -> np.ndarray:
    """Unique undirected edges of a triangle mesh.

    Args:
        faces: (F, 3) int triangle vertex indices.

    Returns:
        (E, 2) int32, each row sorted (smaller index first).
    """
    e = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    return np.unique(np.sort(e, axis=1), axis=0).astype(np.int32)


def region_edges(edges: np.ndarray, vertex_mask: np.ndarray) -> np.ndarray:
    """(E', 2) int32: the edges whose two vertices both lie in the region ``vertex_mask`` (V,) bool."""
    return edges[vertex_mask[edges[:, 0]] & vertex_mask[edges[:, 1]]]


def plane_basis(normal: np.ndarray) -> np.ndarray:
    """(2, 3) float64 orthonormal in-plane axes for a plane of unit ``normal`` (3,)."""
    n = np.asarray(normal, np.float64)
    n = n / np.linalg.norm(n)
    helper = np.array([0.0, 0.0, 1.0]) if abs(n[2]) < 0.9 else np.array([1.0, 0.0, 0.0])
    u = np.cross(n, helper)
    u /= np.linalg.norm(u)
    return np.stack([u, np.cross(n, u)])


def _sections(vertices: np.ndarray, edges: np.ndarray, origins: np.ndarray,
              normal: np.ndarray) -> list[np.ndarray]:
    """Where parallel planes (through ``origins`` (N, 3), shared ``normal`` (3,)) cut the
    ``edges`` (E, 2) of a mesh with ``vertices`` (V, 3): one (n_i, 2) float64 array per
    plane, in the planes' 2D frame (:func:`plane_basis`), metres."""
    n = np.asarray(normal, np.float64)
    n = n / np.linalg.norm(n)
    offsets = origins @ n
    a = vertices[edges[:, 0]].astype(np.float64)
    b = vertices[edges[:, 1]].astype(np.float64)
    da, db = a @ n, b @ n
    near = (np.maximum(da, db) > offsets.min()) & (np.minimum(da, db) <= offsets.max())
    a, b, da, db = a[near], b[near], da[near], db[near]
    basis = plane_basis(n)
    a2, b2 = a @ basis.T, b @ basis.T
    out = []
    for offset in offsets:
        sa, sb = da - offset, db - offset
        cut = (sa > 0) != (sb > 0)
        t = (sa[cut] / (sa[cut] - sb[cut]))[:, None]
        out.append(a2[cut] + t * (b2[cut] - a2[cut]))
    return out


def hull_perimeter(points: np.ndarray) -> float:
    """The perimeter of the 2D convex hull of ``points`` (n >= 3, 2), in their unit."""
    return cv2.arcLength(cv2.convexHull(np.asarray(points, np.float32)), closed=True)


def tape_lengths(vertices: np.ndarray, edges: np.ndarray, origins: np.ndarray,
                 normal: np.ndarray) -> np.ndarray:
    """Convex-hull perimeter of the sections of parallel planes.

    Args:
        vertices: (V, 3) float, metres.
        edges: (E, 2) int, the region's edges (:func:`region_edges`).
        origins: (N, 3) float, a point of each plane, metres.
        normal: (3,) float, the planes' common normal (any length > 0).

    Returns:
        (N,) float64 perimeters in metres; NaN where a plane misses the region.
    """
    origins = np.atleast_2d(np.asarray(origins, np.float64))
    out = np.full(len(origins), np.nan)
    for i, pts in enumerate(_sections(vertices, edges, origins, normal)):
        if len(pts) >= 3:
            out[i] = hull_perimeter(pts)
    return out


def section_points(vertices: np.ndarray, edges: np.ndarray, origin: np.ndarray,
                   normal: np.ndarray, across: np.ndarray) -> np.ndarray:
    """Where one plane cuts the ``edges`` (E, 2) of a mesh with ``vertices`` (V, 3), in a
    frame of the plane turned to a direction of the body.

    Args:
        origin: (3,) a point of the plane; normal: (3,) its normal (any length > 0).
        across: (3,) a direction not along ``normal``: the frame's first axis is it
            projected onto the plane, the second ``normal`` x the first (for a neck, the
            model's x gives its width as a front photo shows it, then its depth as a side
            photo does).

    Returns:
        (n, 2) float64, metres, relative to the plane's point nearest the model's origin.
    """
    n = np.asarray(normal, np.float64)
    n = n / np.linalg.norm(n)
    points = _sections(vertices, edges, np.atleast_2d(np.asarray(origin, np.float64)), n)[0]
    return points @ plane_basis(n) @ section_axes(n, across).T


def section_axes(normal: np.ndarray, across: np.ndarray) -> np.ndarray:
    """(2, 3) float64 unit axes of :func:`section_points`' frame, in the mesh's frame:
    ``across`` (3,) projected onto the plane of ``normal`` (3,), then ``normal`` x it."""
    n = np.asarray(normal, np.float64)
    n = n / np.linalg.norm(n)
    first = np.asarray(across, np.float64) - np.dot(across, n) * n
    first /= np.linalg.norm(first)
    return np.stack([first, np.cross(n, first)])


def section_centre(vertices: np.ndarray, edges: np.ndarray, origin: np.ndarray,
                   normal: np.ndarray) -> np.ndarray:
    """(3,) float64, metres: the mean of the points where one plane (through ``origin``
    (3,), of ``normal`` (3,)) cuts the ``edges`` (E, 2) of a mesh with ``vertices`` (V, 3),
    in the mesh's frame."""
    n = np.asarray(normal, np.float64)
    n = n / np.linalg.norm(n)
    origin = np.asarray(origin, np.float64)
    points = _sections(vertices, edges, origin[None], n)[0]
    return (origin @ n) * n + points.mean(axis=0) @ plane_basis(n)
