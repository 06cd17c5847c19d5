"""What the front photo's limb bends do to the photo readings (docs/history.md, [46]).

The out-of-space bodies swing each limb forward or back in the front photo
(:func:`~bench.accuracy.bodies.flexion_rotations`, about the model's x axis),
which the fit's rig cannot. Two probes:

- :func:`twist_width_change`: the rest A-pose's upper arm hangs some 42-45 degrees out
  from the body, so a swing about the model's x axis also turns the arm about its own
  axis (by the swing times the sine of that angle, the arm's direction's x component);
  the bicep's section is not round, so its width across the front view changes with
  the turn. Measured on the truth's own section
  (orthographic, no photo): the swing against a pure tilt of the arm towards the camera
  (about the axis across it in the front view), which turns nothing.
- :func:`bend_readings`: a fit's photo readings (:data:`~bodyfit.fitter.fit.photo_extents.
  SCALED`) with its front body as `fitter run` has it (unbent), bent by the truth's own
  angles (an oracle: what knowing the bends would give the readings, the fit left as it
  is), and its arms swung by the front photo's estimate (:func:`estimate_arm_swing`).

Units: degrees, metres (model frame, z up, -y forward), pixels; errors in mm.
"""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import cv2
import numpy as np

from bench.accuracy.bodies import (Bodies, bent_bodies, flexion_rotations, turned_bodies)
from bench.accuracy.fit_photos import FitPhotos, answer_pose
from bodyfit import kernels
from bodyfit.fitter.fit.person_fit import fitted_bodies, view_photos
from bodyfit.fitter.fit.photo_extents import (SCALED, ViewPhoto, photo_scaled_measurements,
                                              placed_camera, silhouette_axis)
from bodyfit.fitter.measure.measurements import Measurer
from bodyfit.fitter.model.body_model import BodyModel, rest_shape

__all__ = ["VARIANTS", "SWING_GRID_DEG", "ABDUCTION_GRID_DEG", "HEAD_ROWS_SHARE",
           "twist_width_change", "estimate_arm_swing", "bend_readings"]

#: The readings :func:`bend_readings` compares, in its order.
VARIANTS = ("fit", "truth's arms", "truth's legs", "truth's bends", "estimated arms")
#: :func:`estimate_arm_swing`'s grid: each arm's swing and change of abduction, degrees.
SWING_GRID_DEG = np.arange(-8.0, 8.5, 1.0)
ABDUCTION_GRID_DEG = np.arange(-2.0, 2.01, 0.5)
#: The head: the silhouette's top rows, this share of its height (:func:`_head_centred`).
HEAD_ROWS_SHARE = 0.08
_ARMS, _LEGS = [0, 1], [2, 3]  # POSE_NAMES columns


def _axis_rotation(axis: np.ndarray, degrees: float) -> np.ndarray:
    """(3, 3) the rotation by ``degrees`` about the unit ``axis`` (3,) (OpenCV's Rodrigues)."""
    return cv2.Rodrigues(np.deg2rad(degrees) * np.asarray(axis, np.float64))[0]


def twist_width_change(model: BodyModel, measurer: Measurer, bodies: Bodies, row: int,
                       degrees: float = 4.0) -> tuple[float, float]:
    """(swing, tilt): the change, % per degree, of the left bicep's section width along
    its front :func:`silhouette_axis` (the orthographic front view's), body ``row`` in its
    front photo's abduction, the left arm swung forward and back by ``degrees`` about the
    model's x axis (the benchmark's bend), then tilted as far towards and away from the
    camera about the axis across the arm in the front view (no turn about its own axis)."""
    rest, joints = bodies.vertices[row], bodies.joints[row]
    arm = measurer.girth_plane(rest, "H.L")[1]  # the shoulder ring's centre to the elbow's
    across = np.cross(arm, [0.0, 1.0, 0.0])
    across /= np.linalg.norm(across)
    if (_axis_rotation(across, 1.0) @ arm)[1] > 0:  # forward is -y
        across = -across
    poses = np.repeat(bodies.abduction_deg[row][None].astype(float), 2, axis=0)
    changes = []
    for turn_of in (flexion_rotations, lambda d: _axis_rotation(across, d)):
        turns = np.array([[turn_of(np.float64(d))] + [np.eye(3)] * 3
                          for d in (-degrees, degrees)])
        widths = []
        for body in turned_bodies(model, rest, joints, poses, turns):
            section = measurer.girth_section(body, "H.L") @ measurer.girth_axes(body, "H.L")
            widths.append(np.ptp(section @ silhouette_axis(measurer, body, "H.L", "front")))
        changes.append(100.0 * (widths[1] - widths[0]) / (2 * degrees) / np.mean(widths))
    return changes[0], changes[1]


def _head_centred(model: BodyModel, photo: ViewPhoto) -> tuple[np.ndarray, np.ndarray]:
    """(R (3, 3), t (3,)): the photo's camera placed from its fitted body
    (:func:`placed_camera`), moved sideways so that the body's head (the silhouette's top
    :data:`HEAD_ROWS_SHARE`) is centred on the person's: the placement centres the
    silhouette's horizontal extent, which the hands set, and a swung arm's hand comes
    nearer the camera or goes further from it, so it moves the camera sideways
    (5 degrees forward on one arm, 3 back on the other: 7 mm at 3 m)."""
    rotation, translation = placed_camera(model, photo)
    k = np.asarray(photo.intrinsics, float)
    rendered = kernels.rasterize(photo.body[None].astype(np.float32), model.faces,
                                 model.face_parts,
                                 kernels.pinhole_camera(k, rotation, translation),
                                 *photo.mask.shape).numpy()[0] >= 0
    centres = []
    for mask in (photo.mask, rendered):
        rows, cols = np.nonzero(mask)
        centres.append(cols[rows < rows.min() + HEAD_ROWS_SHARE * np.ptp(rows)].mean())
    translation = translation + [(centres[0] - centres[1]) * translation[2] / k[0, 0], 0, 0]
    return rotation, translation


def estimate_arm_swing(model: BodyModel, photo: ViewPhoto, rest: np.ndarray,
                       joints: np.ndarray, pose_deg: np.ndarray) -> np.ndarray:
    """(4,) degrees: each arm's swing and change of abduction in ``photo`` (the front
    one), the legs' none: the grid point (:data:`SWING_GRID_DEG` x
    :data:`ABDUCTION_GRID_DEG`) whose render of the fitted body (``rest`` (V, 3), its
    ``joints`` (4, 3), the view's ``pose_deg`` (4,): ``photo.body`` so posed) through the
    placed camera
    (:func:`_head_centred`) differs from the person's mask in the fewest pixels of that
    arm's half of the photo (split at the silhouette's median column); returned as
    (left swing, right swing, left abduction change, right abduction change)."""
    grid = [(a, s) for a in ABDUCTION_GRID_DEG for s in SWING_GRID_DEG]
    poses = np.array([pose_deg + np.r_[a, a, 0.0, 0.0] for a, _ in grid])
    swings = np.array([[s, s, 0.0, 0.0] for _, s in grid])
    rotation, translation = _head_centred(model, photo)
    k = np.asarray(photo.intrinsics, float)
    height, width = photo.mask.shape
    labels = kernels.rasterize(bent_bodies(model, rest, joints, poses, swings), model.faces,
                               model.face_parts, kernels.pinhole_camera(k, rotation, translation),
                               height, width).numpy()
    wrong = (labels >= 0) != photo.mask[None]
    centre = int(np.median(np.flatnonzero(photo.mask.any(axis=0))))
    left_joint = rotation @ joints[0] + translation
    left_on_right = k[0, 0] * left_joint[0] / left_joint[2] + k[0, 2] > centre
    halves = [wrong[:, :, centre:].sum(axis=(1, 2)), wrong[:, :, :centre].sum(axis=(1, 2))]
    left, right = halves if left_on_right else halves[::-1]
    (left_a, left_s), (right_a, right_s) = grid[int(np.argmin(left))], grid[int(np.argmin(right))]
    return np.array([left_s, right_s, left_a, right_a])


def bend_readings(model: BodyModel, measurer: Measurer, bodies: Bodies, row: int,
                  set_folder: Path, run: Path, subject: str) -> tuple[np.ndarray, np.ndarray]:
    """((len(VARIANTS), len(SCALED)) signed errors (mm) of the fit of ``subject`` (body
    ``row`` of the set in ``set_folder``) in ``run``, one row per :data:`VARIANTS`; (4,)
    the arms' estimated swing and abduction change, :func:`estimate_arm_swing`)."""
    record = json.loads((run / subject / "run.json").read_text())
    photos = FitPhotos.of(model, set_folder, subject, record)
    betas, pose = np.array(record["result"]["betas"]), answer_pose(record)
    _, fitted_rest, view_bodies = fitted_bodies(model, betas, pose, photos.views,
                                                photos.stature_m,
                                                photos.settings.search.condition_stature)
    shown = view_photos(photos.settings, photos.views, view_bodies, photos.masks,
                        photos.intrinsics)
    rest, joints = (a[0] for a in rest_shape(model, betas[None]))
    front_pose = photos.views["front"].view_pose(pose[None])[0]
    estimate = estimate_arm_swing(model, shown["front"], rest, joints, front_pose)
    # the truth's bends of the arms, the legs, both; then the estimate's swing and abduction
    swings = np.zeros((4, 4))
    for bend, chains in enumerate((_ARMS, _LEGS, _ARMS + _LEGS)):
        swings[bend, chains] = bodies.flexion_deg[row][chains]
    swings[3, :2] = estimate[:2]
    poses = np.repeat(np.asarray(front_pose, np.float64)[None], 4, axis=0)
    poses[3, :2] += estimate[2:]
    truth = json.loads((set_folder / subject / "truth.json").read_text())["measurements"]

    def errors(front_body=None) -> list[float]:
        front = shown["front"] if front_body is None else dataclasses.replace(
            shown["front"], body=front_body)
        values = photo_scaled_measurements(model, measurer, fitted_rest,
                                           shown | {"front": front})
        return [values[key] - truth[key] for key in SCALED]

    rows = [errors()] + [errors(body) for body in bent_bodies(model, rest, joints, poses, swings)]
    return np.array(rows), estimate
