"""Synthetic studio photos of bodies from the model's space, with their truth.

For the tests and the fitter benchmark (bench/fitter_speed.py): a body whose
measurements are known, photographed so that ``fitter run`` can be checked against them.

Painted by :func:`bodyfit.fitter.output.render.render_parts` (OpenCV polygons far to near), not
by the kernels, on a plain backdrop. The paper's orthographic projection: the body is
scaled to ``body_px`` pixels tall. The front photo shows the body in its pose (an
A-pose). The side photo shows the body's left side (facing the image's left, as a camera
at the person's left sees it), with ``side_arms``:

- ``"down"`` (default, as users photograph it): the arms hang straight down, the
  shoulders at the body's own arms-down angle
  (:func:`bodyfit.fitter.fit.side_arms.side_photo_pose`), rendered with the arms, which show
  in front of and beside the torso's profile;
- ``"hidden"``: the body in the front photo's pose without arm, elbow and hand: a side
  photo whose arms hide within the torso's profile.

Two cameras: the paper's orthographic projection (:func:`photo`, :func:`write_subject`):
the body is scaled to ``body_px`` pixels tall; or a pinhole camera with a given K at a
given distance and height, its axis horizontal (:func:`pinhole_photo`;
:func:`write_pinhole_photos`, through a lens's distortion too, as a phone records them;
:func:`write_pinhole_subject`, which also writes the camera as camera.json).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from bodyfit.calib.camera import Camera, camera_fields
from bodyfit.calib.images import write_image
from bodyfit.calib.synthetic import distort_image

from bodyfit.fitter.fit.pinhole_canvas import Placement
from bodyfit.fitter.fit.side_arms import SIDE_ARMS, side_photo_pose
from bodyfit.fitter.measure.measurements import Measurer
from bodyfit.fitter.model.body_model import PART_NAMES, forward, rest_shape
from bodyfit.fitter.output.render import (coverage_mask, orthographic_pixels, pinhole_pixels,
                                          render_parts, render_pinhole)
from bodyfit.fitter.output.result_files import write_json
from bodyfit.kernels.target import SIDE_VIEW_PARTS, visible_faces

BACKDROP_BGR = (170, 185, 200)


def photo(vertices, model, view: str, parts, body_px: int = 700,
          size_px: tuple[int, int] = (600, 800)) -> np.ndarray:
    """(H, W, 3) uint8 BGR photo of posed ``vertices`` (V, 3) metres, one view."""
    faces, face_parts = visible_faces(model.faces, model.face_parts, parts)
    # body_px tall from the top edge of the first row to the bottom edge of the last
    # (with its top and bottom on pixel centres, the person would span body_px - 1 rows,
    # and the fitter, which reads the stature's scale from the rows, would see them
    # 1/body_px too large)
    image = render_parts(vertices, faces, face_parts, view, body_px + 1, margin_px=0.5)
    h, w = image.shape[:2]
    # the person's pixels: those the body covers by more than half (OpenCV's polygon fill
    # of the painted picture takes every pixel it touches, a pixel too wide)
    body = coverage_mask(orthographic_pixels(vertices, view, body_px + 1, 0.5), faces, (w, h))
    if view == "side":  # render_parts draws the side view mirrored
        image, body = image[:, ::-1], body[:, ::-1]
    width, height = size_px
    canvas = np.full((height, width, 3), BACKDROP_BGR, np.uint8)
    top, left = (height - h) // 2, (width - w) // 2
    canvas[top:top + h, left:left + w][body] = image[body]
    return canvas


def pinhole_photo(vertices, model, view: str, parts, intrinsics: np.ndarray,
                  size_px: tuple[int, int], distance_m: float,
                  camera_height_m: float, tilt_deg: tuple[float, float] = (0.0, 0.0)
                  ) -> np.ndarray:
    """(H, W, 3) uint8 BGR photo of posed ``vertices`` (V, 3) metres through a pinhole.

    Args:
        view: "front" or "side", the kernels' view rotations (camera axis horizontal).
        intrinsics: (3, 3) K, pixels; size_px: (width, height).
        distance_m: from the camera to the body's vertical axis (model origin).
        camera_height_m: the camera above the floor (the body's lowest vertex).
        tilt_deg: (pitch, roll) of the camera held askew (``Placement``'s), degrees.

    The person's pixels are those the body covers by more than half
    (:func:`pinhole_silhouette`).
    """
    image, body = pinhole_layers(vertices, model, view, parts, intrinsics, size_px,
                                 distance_m, camera_height_m, tilt_deg)
    canvas = np.full_like(image, BACKDROP_BGR)
    canvas[body] = image[body]
    return canvas


def pinhole_layers(vertices, model, view: str, parts, intrinsics: np.ndarray,
                   size_px: tuple[int, int], distance_m: float, camera_height_m: float,
                   tilt_deg: tuple[float, float] = (0.0, 0.0),
                   face_colours: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The body of :func:`pinhole_photo` (same arguments) before it is put on a backdrop:
    ((H, W, 3) uint8 BGR painted on white, (H, W) bool the pixels it covers by more than
    half). ``face_colours``: (F', 3) BGR for the faces of ``parts`` (in the order
    :func:`bodyfit.kernels.target.visible_faces` gives them), or None for the parts'
    colours."""
    faces, face_parts = visible_faces(model.faces, model.face_parts, parts)
    rotation, translation = _extrinsics(vertices, view, distance_m, camera_height_m, tilt_deg)
    image = render_pinhole(vertices, faces, face_parts, intrinsics, rotation, translation,
                           size_px, face_colours)
    return image, _covered(vertices, faces, intrinsics, rotation, translation, size_px)


def pinhole_silhouette(vertices, model, view: str, parts, intrinsics: np.ndarray,
                       size_px: tuple[int, int], distance_m: float,
                       camera_height_m: float) -> np.ndarray:
    """(H, W) bool: the pixels of :func:`pinhole_photo` (same arguments) that the body
    covers by more than half (:func:`bodyfit.fitter.output.render.coverage_mask`): the exact
    silhouette an extraction from the photo should find."""
    faces, _ = visible_faces(model.faces, model.face_parts, parts)
    rotation, translation = _extrinsics(vertices, view, distance_m, camera_height_m)
    return _covered(vertices, faces, intrinsics, rotation, translation, size_px)


def _covered(vertices, faces, intrinsics, rotation, translation, size_px) -> np.ndarray:
    """(H, W) bool: the pixels ``faces`` of ``vertices`` cover by more than half through
    the pinhole (K ``intrinsics``, the extrinsics of :func:`_extrinsics`)."""
    return coverage_mask(pinhole_pixels(vertices, intrinsics, rotation, translation)[0], faces,
                         size_px)


def _extrinsics(vertices: np.ndarray, view: str, distance_m: float, camera_height_m: float,
                tilt_deg: tuple[float, float] = (0.0, 0.0)) -> tuple[np.ndarray, np.ndarray]:
    """(rotation (3, 3), translation (3,) metres) of :func:`pinhole_photo`'s camera."""
    floor = float(vertices[:, 2].min())
    return Placement(distance_m, camera_height_m, 0.0, -floor, *tilt_deg).extrinsics(view)


__all__ = ["SIDE_ARMS", "photo", "pinhole_photo", "pinhole_layers", "pinhole_silhouette",
           "lens_photo", "write_subject", "write_pinhole_photos", "write_pinhole_subject"]




def write_subject(folder, model, betas, pose_deg, side_arms: str = "down") -> dict[str, float]:
    """Write front.png and side.png of one body into ``folder``; return its true
    measurements (key -> mm) of the rest body.

    Args:
        folder: an existing folder (``pathlib.Path``).
        betas: (K,) shape coefficients, sigma.
        pose_deg: (4,) front photo's abduction angles, degrees, ``POSE_NAMES`` order.
        side_arms: ``"down"`` or ``"hidden"`` (module docstring).
    """
    betas, pose_deg = np.atleast_2d(betas), np.atleast_2d(pose_deg)
    side, parts = _side_body(model, betas, pose_deg, side_arms)
    posed = forward(model, betas, pose_deg)[0]
    write_image(folder / "front.png", photo(posed, model, "front", PART_NAMES))
    write_image(folder / "side.png", photo(side, model, "side", parts))
    return Measurer.from_model(model).measure(rest_shape(model, betas)[0][0])


def _side_body(model, betas: np.ndarray, pose_deg: np.ndarray, side_arms: str):
    """(posed vertices (V, 3), parts shown) of the side photo (``side_arms``, module
    docstring); betas (1, K), pose_deg (1, 4) of the front photo."""
    if side_arms not in SIDE_ARMS:  # checked before any work
        raise ValueError(f"side_arms must be one of {SIDE_ARMS}, got {side_arms!r}")
    if side_arms == "down":
        side_pose = side_photo_pose(model, betas[0], pose_deg[0])[None]
        return forward(model, betas, side_pose)[0], PART_NAMES
    return forward(model, betas, pose_deg)[0], SIDE_VIEW_PARTS


def write_pinhole_photos(folder, model, betas, pose_deg, camera: Camera, distance_m: float,
                         camera_height_m: float, side_arms: str = "down") -> dict[str, float]:
    """Write front.png and side.png through ``camera`` into ``folder``; return the true
    measurements (key -> mm) of the rest body.

    Each view is :func:`lens_photo` (both from the same distance and height; the side
    photo's arms as ``side_arms``), as the camera's sensor records it.
    """
    folder = Path(folder)
    betas, pose_deg = np.atleast_2d(betas), np.atleast_2d(pose_deg)
    views = {"front": (forward(model, betas, pose_deg)[0], PART_NAMES),
             "side": _side_body(model, betas, pose_deg, side_arms)}
    for view, (posed, parts) in views.items():
        write_image(folder / f"{view}.png",
                    lens_photo(posed, model, view, parts, camera, distance_m, camera_height_m))
    return Measurer.from_model(model).measure(rest_shape(model, betas)[0][0])


def lens_photo(vertices, model, view: str, parts, camera: Camera, distance_m: float,
               camera_height_m: float, tilt_deg: tuple[float, float] = (0.0, 0.0)
               ) -> np.ndarray:
    """(H, W, 3) uint8 BGR: :func:`pinhole_photo` of posed ``vertices`` (V, 3) metres
    through ``camera.K`` at ``camera.image_size_px``, recorded through the lens's
    distortion ``camera.dist`` (:func:`bodyfit.calib.synthetic.distort_image`; the
    backdrop fills where the lens sees beyond the pinhole picture)."""
    image = pinhole_photo(np.asarray(vertices, np.float64), model, view, parts, camera.K,
                          camera.image_size_px, distance_m, camera_height_m, tilt_deg)
    if np.any(camera.dist):
        image = distort_image(image, camera.K, camera.dist, BACKDROP_BGR)
    return image


def write_pinhole_subject(folder, model, betas, pose_deg, intrinsics: np.ndarray,
                          size_px: tuple[int, int], distance_m: float,
                          camera_height_m: float, side_arms: str = "down") -> dict[str, float]:
    """Write front.png, side.png (:func:`write_pinhole_photos` through ``intrinsics``, no
    distortion) and that camera as camera.json into ``folder``; return the true
    measurements (key -> mm) of the rest body."""
    camera = Camera(tuple(size_px), np.asarray(intrinsics, float), np.zeros(5))
    truth = write_pinhole_photos(folder, model, betas, pose_deg, camera, distance_m,
                                 camera_height_m, side_arms)
    write_json(Path(folder) / "camera.json", camera_fields(camera))
    return truth
