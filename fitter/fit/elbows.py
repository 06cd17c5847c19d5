"""The elbows: each forearm bent about its elbow, a motion outside the model's rig.

The model's rest pose (Anny's A-pose) bends each forearm forward at the elbow by about
40 degrees (:attr:`ElbowRig.rest_deg`), and its rig turns only the shoulders and hips
(:mod:`bodyfit.fitter.model.body_model`). So its arms, hung down for a side photo, swing
their hands in front of the belly, where a person's straight arm lays them against the
thigh; and in a front photo its forearm is foreshortened towards the camera. The local
solver fits one elbow flexion for both arms and both photos
(``SolverSettings.elbows``; the flexion the learned start and the search leave is the
rest pose's).

The bend: each forearm-and-hand vertex ``v`` turned about its side's elbow, through the
centroid ``c`` of the elbow ring (linear in the body) about the rest elbow's hinge axis
(perpendicular to the upper arm and forearm of the mean body), by the flexion minus the
rest's, blended by the vertex's forearm weight ``e`` (1 on the forearm and hand, 0 on
the rest of the body, smoothed across the elbow ring over the mesh)::

    v' = v + e (R(flexion - rest) - I) (v - c)

For a given flexion that map is linear in the body (no constant term), so it maps shape
directions as it maps bodies. Units: metres, degrees; model frame (z up, -y forward).
"""

from __future__ import annotations

import dataclasses
import functools

import numpy as np
from scipy.spatial.transform import Rotation

from bodyfit.fitter.measure.sections import mesh_edges
from bodyfit.fitter.model.body_model import (PART_NAMES, BodyModel, abduction_rotations,
                                             forward, rest_shape)
from bodyfit.kernels.body_forward import blend_skinning

__all__ = ["ElbowRig", "elbow_rig", "bent", "bend_derivative", "elbow_forward"]

SIDES = ("L", "R")
_SMOOTHING_ROUNDS = 6  # neighbour averages of the forearm weight across the elbow ring


@dataclasses.dataclass(frozen=True, eq=False)
class ElbowRig:
    """The model's elbows (module docstring).

    Attributes:
        weights: (2, V) float64 each side's forearm weight ``e``.
        rings: the two sides' elbow-ring vertex indices.
        axes: (2, 3) unit hinge axes: turning by + about them bends the forearm forward.
        rest_deg: the rest pose's flexion (the mean body's, both sides' mean), degrees.
    """

    weights: np.ndarray
    rings: tuple[np.ndarray, np.ndarray]
    axes: np.ndarray
    rest_deg: float


@functools.lru_cache(maxsize=4)
def elbow_rig(model: BodyModel) -> ElbowRig:
    """The model's :class:`ElbowRig`, from its parts, rings and mean body (cached)."""
    mean = model.mean_vertices.astype(np.float64)
    neighbours = _neighbour_mean_matrix(model.faces, len(mean))
    forearm = np.isin(model.vertex_parts, [PART_NAMES.index("elbow"), PART_NAMES.index("hand")])
    weights, rings, axes, flexions = [], [], [], []
    for side in SIDES:
        sign = 1.0 if side == "L" else -1.0
        e = (forearm & (sign * mean[:, 0] > 0)).astype(np.float64)
        arm = model.chain_weights[:, SIDES.index(side)] > 0  # the shoulder chain's vertices
        for _ in range(_SMOOTHING_ROUNDS):
            e = np.where(arm, neighbours @ e, e)
        ring = model.landmarks[f"ring:elbow.{side}"]
        elbow = mean[ring].mean(axis=0)
        upper = elbow - mean[model.landmarks[f"ring:shoulder.{side}"]].mean(axis=0)
        fore = mean[model.landmarks[f"ring:wrist.{side}"]].mean(axis=0) - elbow
        hinge = np.cross(upper, fore)
        weights.append(e)
        rings.append(ring)
        axes.append(hinge / np.linalg.norm(hinge))
        flexions.append(np.degrees(np.arccos(upper @ fore / np.linalg.norm(upper)
                                             / np.linalg.norm(fore))))
    return ElbowRig(np.array(weights), tuple(rings), np.array(axes), float(np.mean(flexions)))


def _neighbour_mean_matrix(faces: np.ndarray, count: int):
    """(V, V) sparse: each vertex's mean over itself and its mesh neighbours."""
    import scipy.sparse

    edges = mesh_edges(faces)
    rows = np.r_[edges[:, 0], edges[:, 1], np.arange(count)]
    cols = np.r_[edges[:, 1], edges[:, 0], np.arange(count)]
    adjacency = scipy.sparse.csr_matrix((np.ones(len(rows)), (rows, cols)), shape=(count, count))
    return scipy.sparse.diags(1.0 / np.asarray(adjacency.sum(axis=1)).ravel()) @ adjacency


def _turns(rig: ElbowRig, flexion_deg: float):
    """Per side: (the elbow's rotation from the rest flexion to ``flexion_deg`` (3, 3),
    its derivative per degree (3, 3))."""
    for axis in rig.axes:
        turn = Rotation.from_rotvec(axis * np.deg2rad(flexion_deg - rig.rest_deg)).as_matrix()
        cross = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]],
                          [-axis[1], axis[0], 0]])
        yield turn, cross @ turn * (np.pi / 180.0)


def _about_elbows(rig: ElbowRig, vertices: np.ndarray, matrices, rows) -> np.ndarray:
    """(..., N, 3) float64: the sum over the sides of e (M (v - c)) for the vertices
    ``rows`` of bodies (..., V, 3) and each side's (3, 3) ``matrices`` (the ring centroids
    c from the whole bodies)."""
    vertices = np.asarray(vertices)
    picked = np.asarray(vertices[..., rows, :], np.float64)
    out = np.zeros_like(picked)
    for weights, ring, matrix in zip(rig.weights, rig.rings, matrices):
        centre = np.asarray(vertices[..., ring, :], np.float64).mean(axis=-2, keepdims=True)
        out += weights[rows, None] * ((picked - centre) @ matrix.T)
    return out


def bent(rig: ElbowRig, vertices: np.ndarray, flexion_deg: float,
         rows=slice(None)) -> np.ndarray:
    """Bodies (..., V, 3) (or shape directions) with both elbows at ``flexion_deg``
    instead of the rest pose's (module docstring), float64: (..., N, 3), the vertices
    ``rows`` only (default all)."""
    return np.asarray(np.asarray(vertices)[..., rows, :], np.float64) + _about_elbows(
        rig, vertices, [turn - np.eye(3) for turn, _ in _turns(rig, flexion_deg)], rows)


def bend_derivative(rig: ElbowRig, vertices: np.ndarray, flexion_deg: float,
                    rows=slice(None)) -> np.ndarray:
    """(..., N, 3) float64: d :func:`bent` / d flexion, metres per degree, of the vertices
    ``rows`` (default all) of bodies (..., V, 3)."""
    return _about_elbows(rig, vertices, [d_turn for _, d_turn in _turns(rig, flexion_deg)],
                         rows)


def elbow_forward(model: BodyModel, betas: np.ndarray, pose_deg: np.ndarray,
                  flexion_deg: float | None) -> np.ndarray:
    """(P, V, 3) float32 metres: ``forward(model, betas, pose_deg)`` with both elbows
    bent to ``flexion_deg`` before the skinning (None: the rest pose's, ``forward``'s
    own result)."""
    if flexion_deg is None:
        return forward(model, betas, pose_deg)
    rest, joints = rest_shape(model, np.asarray(betas))
    rest = bent(elbow_rig(model), rest, flexion_deg)
    return blend_skinning(model.chain_weights, rest, joints,
                          abduction_rotations(np.asarray(pose_deg, np.float64)))
