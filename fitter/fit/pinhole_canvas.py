"""The person's silhouettes on the kernels' canvases, seen through a pinhole camera.

The alternative to :mod:`bodyfit.fitter.fit.canvas` (the paper's orthographic views) when the
camera is known (camera.json from ``calib capture``) or assumed (:func:`phone_intrinsics`).

The model of the scene, and its assumptions:

- **The photo** is undistorted and upright (calib did both), so it is an ideal pinhole
  image with the camera matrix ``K`` turned as the photo was (:func:`upright_intrinsics`).
- **The camera is aimed horizontally, then pitched** about its own x axis by the view's
  ``pitch_deg`` (0 unless the fit searches it, :mod:`bodyfit.fitter.fit.pitch`); the
  **person stands upright** on the floor, in the middle of the view's direction: the
  front view looks at the body's front, the side view at its left side (the body facing
  the image's left), with the rotations of the kernels' ``FRONT_VIEW_DEG`` and
  ``SIDE_VIEW_DEG``. A phone's roll is not modelled.
- **Placement from the stature** (:func:`solve_placement`): the mean body, scaled to the
  person's stature, stands where its highest and lowest projected points fall on the
  silhouette's top and bottom edges and its horizontal centre on the silhouette's. Those
  two rows (turned to a level camera's: a pitch is a turn about the camera's centre) give
  two equations, linear in the person's distance and the camera's height, once it is
  known which vertices project highest and lowest and how far in front of or behind the
  body's axis they are (the toes are nearer the camera than the crown); a few
  fixed-point rounds settle that. The body is posed and shown as the view renders
  candidates (the side view's arms hanging down, hands in front of the body: the
  horizontal centre must include them, or the camera lands 10 cm to one side and the side
  view is seen 2 degrees askew). The person's own shape differs from the scaled mean
  body; the error is the difference of their depth offsets at the crown and the toes
  (a few centimetres at 3 m: about 1 per cent of the distance), so the search places the
  camera anew from its best body so far (:func:`placed_anew`, ``FitSettings.
  placement_rounds``).
- **The canvas** is a crop of the photo's mask around the person and every candidate the
  search may ask for (model extent, as the orthographic canvas), resampled so that the
  person is ``body_height_px`` tall (area resampling cut at one half); ``K`` follows the
  crop and the scale. Candidates are rendered through this fixed camera at the solved
  distance; the kernels' alignment then moves each onto the person (2D), which is right
  for the small offsets between a candidate's and the mean body's placement.

Frames: photo and canvas pixels are (column, row) with OpenCV's centre convention; the
model frame is metres, z up, the body facing -y; the camera frame x right, y down, z forward.
"""

from __future__ import annotations

import dataclasses

import cv2
import numpy as np
from scipy.spatial.transform import Rotation

from bodyfit import kernels
from bodyfit.common.errors import UserError
from bodyfit.fitter.fit.canvas import VIEW_PARTS, CanvasSettings
from bodyfit.kernels.target import visible_vertices
from bodyfit.kernels.view_camera import camera_matrices, paper_rotation

__all__ = ["PHONE_HFOV_DEG", "Placement", "phone_intrinsics", "upright_intrinsics",
           "view_rotation", "view_pitch_deg", "solve_placement", "pinhole_view", "placed_anew"]

#: Horizontal field of view across the photo's long side of the camera assumed without
#: camera.json: a phone's main camera (26 mm equivalent focal length: 69.4 degrees).
PHONE_HFOV_DEG = 70.0
_VIEW_DEG = {"front": kernels.FRONT_VIEW_DEG, "side": kernels.SIDE_VIEW_DEG}
_ROUNDS = 6
_MIRRORED = (2, 4, 5, 7)


@dataclasses.dataclass(frozen=True)
class Placement:
    """Where the camera stands relative to the person.

    Attributes:
        distance_m: from the camera's centre to the body's vertical axis (model origin),
            along the camera's (horizontal) axis.
        camera_height_m: the camera's centre above the floor.
        lateral_m: the body's axis to the right of the camera's axis (image right).
        origin_height_m: the model origin above the floor, for the body of the stature.
        pitch_deg, roll_deg: the camera turned about its own centre after it is aimed
            horizontally: pitch about its x axis (positive looks down), then roll about its
            axis (positive turns the picture clockwise); degrees. A hand-held phone's.
    """

    distance_m: float
    camera_height_m: float
    lateral_m: float
    origin_height_m: float
    pitch_deg: float = 0.0
    roll_deg: float = 0.0

    def extrinsics(self, name: str) -> tuple[np.ndarray, np.ndarray]:
        """(R (3, 3), t (3,) metres): the model frame -> camera frame of view ``name``."""
        r = view_rotation(name)
        centre = (-self.distance_m * r[2] - self.lateral_m * r[0]
                  + np.array([0.0, 0.0, self.camera_height_m - self.origin_height_m]))
        r = (_pitched(self.pitch_deg)
             @ Rotation.from_euler("z", self.roll_deg, degrees=True).as_matrix() @ r)
        return r, -r @ centre


def _pitched(pitch_deg: float) -> np.ndarray:
    """(3, 3) the turn of a camera frame by ``pitch_deg`` about its x axis (positive looks
    down): level camera frame -> pitched camera frame."""
    return Rotation.from_euler("x", pitch_deg, degrees=True).as_matrix()


def view_rotation(name: str) -> np.ndarray:
    """(3, 3) model -> camera rotation of the ``"front"`` or ``"side"`` view (axis horizontal)."""
    return paper_rotation(_VIEW_DEG[name])


def view_pitch_deg(view: kernels.ViewTarget) -> float:
    """The pitch (degrees, positive looks down) of a pinhole view's camera: its rotation
    against the level one of :func:`view_rotation` (no roll)."""
    tilt = camera_matrices(view.camera)[1] @ view_rotation(view.name).T
    return float(np.rad2deg(np.arctan2(tilt[2, 1], tilt[1, 1])))


def phone_intrinsics(shape: tuple[int, int]) -> np.ndarray:
    """(3, 3) K of a typical phone photo of ``shape`` (H, W): :data:`PHONE_HFOV_DEG` across
    the long side, square pixels, no skew, principal point at the centre."""
    height, width = shape
    focal = max(height, width) / 2 / np.tan(np.deg2rad(PHONE_HFOV_DEG) / 2)
    return np.array([[focal, 0.0, (width - 1) / 2], [0.0, focal, (height - 1) / 2],
                     [0.0, 0.0, 1.0]])


def upright_intrinsics(intrinsics: np.ndarray, image_size_px: tuple[int, int],
                       orientation: int) -> np.ndarray:
    """K of the photo turned upright by EXIF ``orientation`` (as calib's ``to_upright``).

    Args:
        intrinsics: (3, 3) K of the sensor-frame image, pixels.
        image_size_px: (width, height) of the sensor-frame image.
        orientation: EXIF orientation, 1..8.

    Returns:
        (3, 3) K such that the upright image is that camera's picture (turned 0, 90, 180 or
        270 degrees about the optical axis; the model's camera frame turns with it).

    Raises:
        UserError: a mirrored orientation (2, 4, 5, 7: no camera takes such a photo), or a
            skewed K in a photo turned by 90 degrees.
    """
    if orientation in _MIRRORED:
        raise UserError(f"the photo's EXIF orientation {orientation} mirrors it; a pinhole "
                        "camera cannot be fitted to a mirrored photo: save it unmirrored")
    width, height = image_size_px
    (fx, skew, cx), (_, fy, cy) = np.asarray(intrinsics, float)[:2]
    if orientation == 1:
        return np.array(intrinsics, float)
    if orientation == 3:  # 180 degrees: u' = W-1-u, v' = H-1-v
        return np.array([[fx, skew, width - 1 - cx], [0, fy, height - 1 - cy], [0, 0, 1.0]])
    if skew != 0:
        raise UserError("camera.json has a skewed K; photos turned by 90 degrees (EXIF) "
                        "need K[0][1] = 0")
    if orientation == 6:  # 90 clockwise: u' = H-1-v, v' = u
        return np.array([[fy, 0, height - 1 - cy], [0, fx, cx], [0, 0, 1.0]])
    if orientation == 8:  # 90 counter-clockwise: u' = v, v' = W-1-u
        return np.array([[fy, 0, cy], [0, fx, width - 1 - cx], [0, 0, 1.0]])
    raise ValueError(f"EXIF orientation must be 1..8, got {orientation}")


def _project(intrinsics, rotation, translation, points) -> np.ndarray:
    """(N, 2) pixels of model-frame points (N, 3) under a pinhole camera."""
    cam = points @ rotation.T + translation
    return (cam[:, :2] / cam[:, 2:]) @ intrinsics[:2, :2].T + intrinsics[:2, 2]


def solve_placement(name: str, mask: np.ndarray, intrinsics: np.ndarray,
                    body: np.ndarray, pitch_deg: float = 0.0) -> Placement:
    """The camera's placement that puts ``body`` on the silhouette (module docstring).

    Args:
        name: ``"front"`` or ``"side"``.
        mask: (H, W) bool silhouette of the undistorted upright photo.
        intrinsics: (3, 3) K of that photo, pixels.
        body: (V, 3) metres, model frame: the parts the view shows of a body of the
            person's stature (the mean body scaled to it), standing on the floor at its
            lowest vertex.
        pitch_deg: the camera's pitch (positive looks down), degrees.
    """
    k = np.asarray(intrinsics, float)
    r = view_rotation(name)
    rows, cols = np.nonzero(mask)
    u_centre = (cols.min() + cols.max()) / 2
    # the silhouette's top and bottom edges as a level camera at the same centre sees them
    edges = np.array([[u_centre, rows.min() - 0.5, 1.0], [u_centre, rows.max() + 0.5, 1.0]])
    level = edges @ (k @ _pitched(pitch_deg).T @ np.linalg.inv(k)).T
    v_top, v_bottom = level[:, 1] / level[:, 2]
    floor = body[:, 2].min()
    depth = body @ r[2]  # in front of (-) or behind (+) the body's axis, metres
    fx, fy, cy = k[0, 0], k[1, 1], k[1, 2]
    distance = fy * np.ptp(body[:, 2]) / (v_bottom - v_top)
    placement = Placement(distance, 0.0 - floor, 0.0, -floor, pitch_deg)
    for _ in range(_ROUNDS):
        px = _project(k, *placement.extrinsics(name), body)
        top, bottom = np.argmin(px[:, 1]), np.argmax(px[:, 1])
        # (v - cy) (d + depth) = fy (h - z), z and h above the floor; unknowns d, h
        a = np.array([[v_top - cy, -fy], [v_bottom - cy, -fy]])
        b = np.array([-fy * (body[top, 2] - floor) - (v_top - cy) * depth[top],
                      -fy * (body[bottom, 2] - floor) - (v_bottom - cy) * depth[bottom]])
        distance, height = np.linalg.solve(a, b)
        lateral = placement.lateral_m - ((px[:, 0].min() + px[:, 0].max()) / 2 - u_centre) \
            * distance / fx
        placement = Placement(float(distance), float(height), float(lateral), float(-floor),
                              pitch_deg)
    if not 0.3 < placement.distance_m < 50:
        raise UserError(f"the {name} photo puts the person {placement.distance_m:.1f} m from "
                        "the camera; is the camera file or the stature right?")
    return placement


def _crop(mask: np.ndarray, low: np.ndarray, high: np.ndarray,
          scale: float) -> tuple[np.ndarray, np.ndarray]:
    """The photo pixels low..high (inclusive, (column, row), may lie outside the photo: no
    person there) resampled by ``scale``: the (h, w) bool canvas and the (3, 3) map from
    photo to canvas pixels (area resampling: canvas u + 1/2 = s (photo u - low + 1/2))."""
    count = high - low + 1
    window = np.zeros(count[::-1], np.float32)
    src_low, src_high = np.maximum(low, 0), np.minimum(high, np.array(mask.shape[::-1]) - 1)
    window[src_low[1] - low[1]:src_high[1] - low[1] + 1,
           src_low[0] - low[0]:src_high[0] - low[0] + 1] = \
        mask[src_low[1]:src_high[1] + 1, src_low[0]:src_high[0] + 1]
    size = np.maximum(1, np.round(count * scale)).astype(int)
    canvas = cv2.resize(window, tuple(int(v) for v in size), interpolation=cv2.INTER_AREA) > 0.5
    s = size / count
    photo_to_canvas = np.array([[s[0], 0, s[0] * (0.5 - low[0]) - 0.5],
                                [0, s[1], s[1] * (0.5 - low[1]) - 0.5], [0, 0, 1.0]])
    return canvas, photo_to_canvas


def pinhole_view(name: str, mask: np.ndarray, intrinsics: np.ndarray, stature_m: float,
                 extent: np.ndarray, mean_body: np.ndarray, vertex_parts: np.ndarray,
                 settings: CanvasSettings = CanvasSettings(),
                 device: str = "cpu", **view_options) -> kernels.ViewTarget:
    """One view of the person on a canvas with a pinhole camera placed from the stature.

    Args:
        name: ``"front"`` or ``"side"``.
        mask: (H, W) bool, the person's silhouette in the undistorted, upright photo.
        intrinsics: (3, 3) K of that photo (:func:`upright_intrinsics` of camera.json's, or
            :func:`phone_intrinsics`), pixels.
        stature_m: the person's stature, metres.
        extent: (M, 3) float32 metres, the vertices of
            :func:`bodyfit.fitter.fit.canvas.extreme_bodies`.
        mean_body: (V, 3) float32 metres, the mean body in the pose the view renders
            candidates in (the side view's arms hanging down, say).
        vertex_parts: (V,) int, each vertex's index in ``PART_NAMES``: the placement is
            solved with the parts the view renders (``visible_parts``).
        settings: canvas geometry.
        device: where the kernels run.
        view_options: ``visible_parts`` (default ``VIEW_PARTS[name]``) and
            ``fixed_pose_deg`` of ``kernels.prepare_view_target``, as for
            :func:`bodyfit.fitter.fit.canvas.orthographic_view`.

    Returns:
        The kernels' target; its camera is the photo's, cropped and scaled to the canvas.
    """
    k = np.asarray(intrinsics, float)
    body = mean_body.astype(np.float64) * (stature_m / np.ptp(mean_body[:, 2]))
    visible = view_options.get("visible_parts", VIEW_PARTS[name])
    shown = visible_vertices(vertex_parts, visible)
    placement = solve_placement(name, mask, k, body[shown])
    r, t = placement.extrinsics(name)
    rows, cols = np.nonzero(mask)
    scale = settings.body_height_px / (rows.max() - rows.min() + 1)
    bound = _project(k, r, t, extent.astype(np.float64))
    margin = settings.margin_px / scale
    low = np.floor(np.minimum(bound.min(axis=0), [cols.min(), rows.min()]) - margin).astype(int)
    high = np.ceil(np.maximum(bound.max(axis=0), [cols.max(), rows.max()]) + margin).astype(int)
    canvas, photo_to_canvas = _crop(mask, low, high, scale)
    k_canvas = photo_to_canvas @ k
    camera = kernels.pinhole_camera(k_canvas, r, t)
    view_options = {"visible_parts": VIEW_PARTS[name]} | view_options
    return kernels.prepare_view_target(name, canvas, camera,
                                       1000.0 * placement.distance_m / k_canvas[1, 1],
                                       device=device, **view_options)


def placed_anew(view: kernels.ViewTarget, mask: np.ndarray, intrinsics: np.ndarray,
                body: np.ndarray, pitch_deg: float | None = None) -> kernels.ViewTarget:
    """``view`` (of :func:`pinhole_view`) with the camera placed from ``body`` instead of
    the mean body: the same canvas and camera matrix, the distance and height solved by
    :func:`solve_placement` with this body's crown and toes (the search's best body so
    far is much nearer the person's than the mean body is; the mean body's placement
    errs by about 1 per cent of the distance, which scales every candidate by as much).

    Args:
        view: the view to place anew; mask, intrinsics: as for :func:`pinhole_view`.
        body: (V, 3) metres, the parts the view shows of a body in the view's pose, at
            the size the kernels render it (:func:`bodyfit.fitter.fit.person_fit.placement_body`: a
            candidate solved to the stature stands that tall posed, legs apart, so it is
            the person scaled up by a few tenths of a per cent, and its camera must
            stand as much farther).
        pitch_deg: the camera's pitch, degrees (positive looks down); None: the view's own
            (:func:`view_pitch_deg`).
    """
    pitch = view_pitch_deg(view) if pitch_deg is None else pitch_deg
    placement = solve_placement(view.name, mask, np.asarray(intrinsics, float), body, pitch)
    k_canvas = camera_matrices(view.camera)[0]
    camera = kernels.pinhole_camera(k_canvas, *placement.extrinsics(view.name))
    return dataclasses.replace(view, camera=camera, millimetres_per_pixel=1000.0
                               * placement.distance_m / k_canvas[1, 1])
