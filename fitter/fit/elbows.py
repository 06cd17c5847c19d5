"""The elbows and the hands: each forearm bent about its elbow, each hand turned about
its forearm, motions outside the model's rig.

The model's rest pose (Anny's A-pose) bends each forearm forward at the elbow by about
40 degrees (:func:`elbow_rig`'s ``rest_deg``), and its rig turns only the shoulders and
hips (:mod:`bodyfit.fitter.model.body_model`). So its arms, hung down for a side photo, swing
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
directions as it maps bodies.

The hands: a person in a front photo lets the palms face anywhere from in (the rest
pose's) to forward, and a palm turned forward shows the camera the hand's breadth where
the rest pose shows its edge; matching that outline with an edge-on hand, the solver
moves the wrist and misreads the arm's length (by 12 mm, mean absolute, on the
benchmark's people as they stand). The local solver fits each hand's twist in the front
photo (``SolverSettings.hands``): each hand-and-wrist vertex turned about its side's
forearm axis (the mean body's, elbow ring to wrist ring) through the
wrist ring's centroid, blended by a hand weight smoothed across the wrist ring; + turns
the palms forward on both sides. The twist comes first, on the rest body, then the
elbows' bend carries the turned hand with the forearm. The side photo's hands keep the
rest pose's turn. Units: metres, degrees; model frame (z up, -y forward).
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

__all__ = ["TurnRig", "TWISTED_VIEWS", "elbow_rig", "wrist_rig", "bent", "bend_derivative",
           "view_twist", "elbow_forward"]

SIDES = ("L", "R")
_SMOOTHING_ROUNDS = 6  # neighbour averages of a turned part's weight across its ring
#: The views whose hands the fitted twist turns (the side photo's keep the rest pose's).
TWISTED_VIEWS = ("front",)


@dataclasses.dataclass(frozen=True, eq=False)
class TurnRig:
    """A turn of each side's forearm or hand about an axis through a ring's centroid
    (module docstring): the elbows' (:func:`elbow_rig`) or the hands' (:func:`wrist_rig`).

    Attributes:
        weights: (2, V) float64 each side's weight of the turned part (``e``).
        rings: the two sides' ring vertex indices (the turn's centre: their centroid).
        axes: (2, 3) unit axes: the elbows' hinges (turning by + bends the forearm
            forward), or the forearms (turning by + turns the palm forward).
        rest_deg: the rest pose's angle (the elbows: the mean body's flexion, both sides'
            mean; the hands: 0), degrees.
    """

    weights: np.ndarray
    rings: tuple[np.ndarray, np.ndarray]
    axes: np.ndarray
    rest_deg: float


@functools.lru_cache(maxsize=4)
def elbow_rig(model: BodyModel) -> TurnRig:
    """The model's elbows (a :class:`TurnRig`), from its parts, rings and mean body
    (cached)."""
    weights, rings, axes, flexions = [], [], [], []
    for side, e in zip(SIDES, _side_weights(model, ("elbow", "hand"))):
        upper, fore = _arm_segments(model, side)
        hinge = np.cross(upper, fore)
        weights.append(e)
        rings.append(model.landmarks[f"ring:elbow.{side}"])
        axes.append(hinge / np.linalg.norm(hinge))
        flexions.append(np.degrees(np.arccos(upper @ fore / np.linalg.norm(upper)
                                             / np.linalg.norm(fore))))
    return TurnRig(np.array(weights), tuple(rings), np.array(axes), float(np.mean(flexions)))


@functools.lru_cache(maxsize=4)
def wrist_rig(model: BodyModel) -> TurnRig:
    """The model's hands turned about their forearms (a :class:`TurnRig`, rest angle 0),
    from its parts, rings and mean body (cached)."""
    axes = []
    for side in SIDES:
        sign = 1.0 if side == "L" else -1.0
        fore = _arm_segments(model, side)[1]
        axes.append(-sign * fore / np.linalg.norm(fore))  # + turns the palm forward
    return TurnRig(np.array(_side_weights(model, ("hand",))),
                   tuple(model.landmarks[f"ring:wrist.{side}"] for side in SIDES),
                   np.array(axes), 0.0)


def _side_weights(model: BodyModel, parts: tuple[str, ...]) -> list[np.ndarray]:
    """Per side: (V,) float64 1 on that side's vertices of ``parts``, 0 elsewhere,
    smoothed over the side's shoulder chain (``_SMOOTHING_ROUNDS`` neighbour means)."""
    mean = model.mean_vertices.astype(np.float64)
    neighbours = _neighbour_mean_matrix(model.faces, len(mean))
    wanted = np.isin(model.vertex_parts, [PART_NAMES.index(part) for part in parts])
    out = []
    for i, side in enumerate(SIDES):
        sign = 1.0 if side == "L" else -1.0
        e = (wanted & (sign * mean[:, 0] > 0)).astype(np.float64)
        arm = model.chain_weights[:, i] > 0  # the shoulder chain's vertices
        for _ in range(_SMOOTHING_ROUNDS):
            e = np.where(arm, neighbours @ e, e)
        out.append(e)
    return out


def _arm_segments(model: BodyModel, side: str) -> tuple[np.ndarray, np.ndarray]:
    """(upper arm, forearm) (3,) of the mean body's ``side``: shoulder ring to elbow ring,
    elbow ring to wrist ring (centroids), metres."""
    mean = model.mean_vertices.astype(np.float64)
    ring = {name: mean[model.landmarks[f"ring:{name}.{side}"]].mean(axis=0)
            for name in ("shoulder", "elbow", "wrist")}
    return ring["elbow"] - ring["shoulder"], ring["wrist"] - ring["elbow"]


def _neighbour_mean_matrix(faces: np.ndarray, count: int):
    """(V, V) sparse: each vertex's mean over itself and its mesh neighbours."""
    import scipy.sparse

    edges = mesh_edges(faces)
    rows = np.r_[edges[:, 0], edges[:, 1], np.arange(count)]
    cols = np.r_[edges[:, 1], edges[:, 0], np.arange(count)]
    adjacency = scipy.sparse.csr_matrix((np.ones(len(rows)), (rows, cols)), shape=(count, count))
    return scipy.sparse.diags(1.0 / np.asarray(adjacency.sum(axis=1)).ravel()) @ adjacency


def _turns(rig: TurnRig, angle_deg):
    """Per side: (the rotation from the rig's rest angle to ``angle_deg`` (one for both
    sides, or (2,) left and right) (3, 3), its derivative per degree (3, 3))."""
    for axis, angle in zip(rig.axes, np.broadcast_to(np.asarray(angle_deg, np.float64), 2)):
        turn = Rotation.from_rotvec(axis * np.deg2rad(angle - rig.rest_deg)).as_matrix()
        cross = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]],
                          [-axis[1], axis[0], 0]])
        yield turn, cross @ turn * (np.pi / 180.0)


def _about_rings(rig: TurnRig, vertices: np.ndarray, matrices, rows) -> np.ndarray:
    """(..., N, 3) float64: the sum over the sides of e (M (v - c)) for the vertices
    ``rows`` of bodies (..., V, 3) and each side's (3, 3) ``matrices`` (the ring centroids
    c from the whole bodies)."""
    vertices = np.asarray(vertices)
    picked = np.asarray(vertices[..., rows, :], np.float64)
    out = np.zeros_like(picked)
    for weights, ring, matrix in zip(rig.weights, rig.rings, matrices):
        centre = np.asarray(vertices[..., ring, :], np.float64).mean(axis=-2, keepdims=True)
        weight = weights[rows]
        moved = np.flatnonzero(weight)  # the side's turned part: a small share of the body
        out[..., moved, :] += weight[moved, None] * ((picked[..., moved, :] - centre)
                                                     @ matrix.T)
    return out


def bent(rig: TurnRig, vertices: np.ndarray, angle_deg, rows=slice(None)) -> np.ndarray:
    """Bodies (..., V, 3) (or shape directions) turned by ``rig`` to ``angle_deg`` (one
    for both sides, or (2,) left and right) instead of the rest pose's (module docstring:
    the elbows' flexion, the hands' twist), float64: (..., N, 3), the vertices ``rows``
    only (default all)."""
    return np.asarray(np.asarray(vertices)[..., rows, :], np.float64) + _about_rings(
        rig, vertices, [turn - np.eye(3) for turn, _ in _turns(rig, angle_deg)], rows)


def bend_derivative(rig: TurnRig, vertices: np.ndarray, angle_deg, rows=slice(None),
                    side: int | None = None) -> np.ndarray:
    """(..., N, 3) float64: d :func:`bent` / d angle, metres per degree, of the vertices
    ``rows`` (default all) of bodies (..., V, 3): the angle of both sides, or of the side
    ``side`` (0 left, 1 right) alone."""
    return _about_rings(rig, vertices, [d_turn if side in (None, i) else np.zeros((3, 3))
                                        for i, (_, d_turn) in enumerate(_turns(rig, angle_deg))],
                        rows)


def view_twist(view_name: str, twist_deg: np.ndarray | None) -> np.ndarray | None:
    """The hands' twists (2,) a view's body is posed with: ``twist_deg`` in the
    ``TWISTED_VIEWS``, None (the rest pose's) in the others."""
    return twist_deg if view_name in TWISTED_VIEWS else None


def elbow_forward(model: BodyModel, betas: np.ndarray, pose_deg: np.ndarray,
                  flexion_deg: float | None, twist_deg=None) -> np.ndarray:
    """(P, V, 3) float32 metres: ``forward(model, betas, pose_deg)`` with the hands
    turned by ``twist_deg`` ((2,) left and right) and then both elbows bent to
    ``flexion_deg`` before the skinning (None: the rest pose's; both None: ``forward``'s
    own result)."""
    if flexion_deg is None and twist_deg is None:
        return forward(model, betas, pose_deg)
    rest, joints = rest_shape(model, np.asarray(betas))
    if twist_deg is not None:
        rest = bent(wrist_rig(model), rest, twist_deg)
    if flexion_deg is not None:
        rest = bent(elbow_rig(model), rest, flexion_deg)
    return blend_skinning(model.chain_weights, rest, joints,
                          abduction_rotations(np.asarray(pose_deg, np.float64)))
