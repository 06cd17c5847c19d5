"""The side photo's arms: how the side view treats arms hanging down against the body.

People are photographed from the side with their arms hanging down (README, how to
photograph), so their side silhouette holds the arms: in front of and beside the torso's
profile, the model's forearms bending forward. The model's A-pose arms stand out to the
sides; a shoulder abduction of about -41 degrees hangs them straight down
(:func:`arms_down_deg`). The side view of a fit can treat them two ways
(``SIDE_ARMS``):

- ``"down"`` (default): candidates are rendered in the side view with every part, their
  shoulders at the mean body's arms-down angle instead of their own abduction (the
  kernels' per-view fixed pose, ``kernels.prepare_view_target(fixed_pose_deg=...)``); the
  hips keep the candidate's angles. The abduction turns the arms in the frontal plane,
  so in the side view it only sets how low the hands hang: a person whose arms hang a few
  degrees off vertical looks the same there.
- ``"hidden"``: arm, elbow and hand are left out of the candidates' side render
  (``kernels.SIDE_VIEW_PARTS``), the person's arms stay in their silhouette: right for a
  photo whose arms hide within the torso's profile, biased when they do not
  (docs/fitter.md, "Side photo: the arms").

Units: degrees; model frame metres, z up, +x the body's left.
"""

from __future__ import annotations

import numpy as np

from bodyfit import kernels
from bodyfit.common.errors import UserError
from bodyfit.fitter.model.body_model import PART_NAMES, POSE_NAMES, BodyModel, rest_shape

__all__ = ["SIDE_ARMS", "arms_down_deg", "arms_down_angle", "side_view_options", "side_photo_pose"]

#: How a fit's side view treats the arms; the first is the default.
SIDE_ARMS = ("down", "hidden")
_SHOULDERS = (POSE_NAMES[0], POSE_NAMES[1])


def arms_down_deg(model: BodyModel, betas: np.ndarray | None = None) -> float:
    """Shoulder abduction (degrees, negative) that hangs a body's arms straight down:
    :func:`arms_down_angle` of the body of ``betas`` ((K,) in sigma; None: the mean body)."""
    betas = np.zeros((1, 1)) if betas is None else np.atleast_2d(betas)
    rest, joints = rest_shape(model, betas)
    return arms_down_angle(model, rest[0], joints[0])


def arms_down_angle(model: BodyModel, rest: np.ndarray, joints: np.ndarray) -> float:
    """Shoulder abduction (degrees, negative) that hangs the arms of a body in the model's
    topology straight down: the angle that puts the centroid of the left hand's vertices
    directly below the left shoulder joint, in the frontal plane (the hand moves rigidly
    with the shoulder chain; the body is left-right symmetric, so the right side needs
    the same angle).

    Args:
        rest: (V, 3) rest vertices, metres; joints: (4, 3) its rig joints, metres.
    """
    hand = (model.vertex_parts == PART_NAMES.index("hand")) & (model.chain_weights[:, 0] > 0.5)
    dx, _, dz = rest[hand].mean(axis=0) - joints[0]
    return -float(np.degrees(np.arctan2(dx, -dz)))


def side_photo_pose(model: BodyModel, betas: np.ndarray, pose_deg: np.ndarray) -> np.ndarray:
    """(4,) float64 degrees: a body's pose in a side photo with the arms hanging down:
    ``pose_deg`` (4,) with both shoulders at the body's own :func:`arms_down_deg`."""
    pose = np.array(pose_deg, dtype=np.float64).reshape(len(POSE_NAMES))
    pose[:2] = arms_down_deg(model, betas)
    return pose


def side_view_options(model: BodyModel, side_arms: str) -> dict:
    """Keyword arguments of ``kernels.prepare_view_target`` for the side view:
    ``visible_parts`` and ``fixed_pose_deg`` of the ``side_arms`` choice.

    Raises:
        UserError: ``side_arms`` is not one of ``SIDE_ARMS``.
    """
    if side_arms == "down":
        angle = arms_down_deg(model)
        return {"visible_parts": PART_NAMES,
                "fixed_pose_deg": {name: angle for name in _SHOULDERS}}
    if side_arms == "hidden":
        return {"visible_parts": kernels.SIDE_VIEW_PARTS, "fixed_pose_deg": None}
    raise UserError(f"--side-arms must be one of {', '.join(SIDE_ARMS)}, got {side_arms!r}")
