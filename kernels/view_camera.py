"""View cameras: the paper's orthographic front and side projections, and a calibrated pinhole.

A :class:`ViewCamera` is the projection every candidate of one view is rendered with, on
the device. It is not :class:`bodyfit.calib.camera.Camera`, the calibrated phone camera
(intrinsics, lens distortion and their uncertainties, read from camera.json); a pinhole
``ViewCamera`` takes that camera's K once the photos are undistorted.

A view camera maps the model frame (metres, z up, -y forward, +x the body's left) to pixels:

    x_cam = rotation @ x + translation        camera frame: x right, y down, z forward
    pinhole:      u = fx * x_cam/z_cam + skew * y_cam/z_cam + cx,   v = fy * y_cam/z_cam + cy
    orthographic: u = fx * x_cam + skew * y_cam + cx,               v = fy * y_cam + cy

with fx, fy in pixels (pinhole) or pixels per metre (orthographic). ``(u, v)`` is
(column, row) with pixel centres at integer coordinates, as in OpenCV. ``z_cam`` is the
depth used by the depth test; orthographic cameras sit ``distance_m`` in front of the
model origin so that it is positive.

The paper's projections (Section 3.2, Eq. 4-12) rotate the model by R_x(D_x), then R_y(D_y),
then R_z(D_z), and keep the first two coordinates: front D = (90, 0, 0) degrees, which
looks at the body's front (the image's right is the body's left); side D = (90, 90, 0),
which looks at the body's left side (the body faces the image's left).
"""

from __future__ import annotations

import numpy as np
import warp as wp

__all__ = [
    "ViewCamera",
    "FRONT_VIEW_DEG",
    "SIDE_VIEW_DEG",
    "paper_rotation",
    "orthographic_camera",
    "pinhole_camera",
    "camera_matrices",
    "project_point",
]

#: (D_x, D_y, D_z) in degrees of the paper's front and side projections (Eq. 10-12).
FRONT_VIEW_DEG = (90.0, 0.0, 0.0)
SIDE_VIEW_DEG = (90.0, 90.0, 0.0)


@wp.struct
class ViewCamera:
    """One view's projection, shared by every candidate (see the module docstring); made by
    :func:`orthographic_camera` or :func:`pinhole_camera`.

    Attributes:
        rotation: model frame -> camera frame rotation (det +1).
        translation: metres, camera frame.
        fx, fy: focal lengths, pixels (pinhole) or pixels per metre (orthographic).
        cx, cy: principal point, pixels.
        skew: pixels (pinhole) or pixels per metre; the K[0, 1] entry.
        pinhole: 1 for a pinhole (perspective) camera, 0 for an orthographic one.
    """

    rotation: wp.mat33
    translation: wp.vec3
    fx: float
    fy: float
    cx: float
    cy: float
    skew: float
    pinhole: int


@wp.func
def project_point(cam: ViewCamera, x: wp.vec3):
    """Pixel coordinates (u, v) and the screen-linear depth value q of a model-frame point.

    q is z_cam for an orthographic camera and 1/z_cam for a pinhole one: in both cases q
    varies linearly across a projected triangle, so it can be interpolated per pixel (and
    the depth is q, or 1/q).
    """
    c = cam.rotation * x + cam.translation
    s = float(1.0)
    q = c[2]
    if cam.pinhole != 0:
        s = 1.0 / c[2]
        q = s
    return wp.vec3(cam.fx * c[0] * s + cam.skew * c[1] * s + cam.cx, cam.fy * c[1] * s + cam.cy, q)


def paper_rotation(view_deg) -> np.ndarray:
    """R_z(D_z) @ R_y(D_y) @ R_x(D_x) of the paper's Eq. 7-12, (3, 3) float64.

    Args:
        view_deg: (3,) (D_x, D_y, D_z) projection angles in degrees.
    """
    tx, ty, tz = np.deg2rad(np.asarray(view_deg, dtype=np.float64))
    rx = np.array([[1, 0, 0], [0, np.cos(tx), -np.sin(tx)], [0, np.sin(tx), np.cos(tx)]])
    ry = np.array([[np.cos(ty), 0, np.sin(ty)], [0, 1, 0], [-np.sin(ty), 0, np.cos(ty)]])
    rz = np.array([[np.cos(tz), -np.sin(tz), 0], [np.sin(tz), np.cos(tz), 0], [0, 0, 1]])
    return rz @ ry @ rx


def _make_camera(rotation, translation, fx, fy, cx, cy, skew, pinhole) -> ViewCamera:
    cam = ViewCamera()
    cam.rotation = wp.mat33(*np.asarray(rotation, dtype=np.float64).ravel())
    cam.translation = wp.vec3(*np.asarray(translation, dtype=np.float64))
    cam.fx, cam.fy, cam.cx, cam.cy, cam.skew = (float(v) for v in (fx, fy, cx, cy, skew))
    cam.pinhole = int(pinhole)
    return cam


def orthographic_camera(view_deg, pixels_per_metre: float, principal_point_px,
                        distance_m: float = 10.0) -> ViewCamera:
    """The paper's orthographic projection (Eq. 4-12), scaled to pixels.

    Args:
        view_deg: (3,) (D_x, D_y, D_z) degrees; ``FRONT_VIEW_DEG`` or ``SIDE_VIEW_DEG``.
        pixels_per_metre: image scale, px/m (the fitter derives it from the known stature).
        principal_point_px: (2,) (column, row) pixel where the model origin lands.
        distance_m: depth of the model origin in front of the camera; only the depth test
            sees it (depths must stay in (0, 128) m).

    Raises:
        ValueError: a non-positive scale or distance, or a principal point not of shape (2,).
    """
    centre = np.asarray(principal_point_px, dtype=np.float64)
    if centre.shape != (2,):
        raise ValueError(f"principal_point_px must have shape (2,), got {centre.shape}")
    if not pixels_per_metre > 0 or not 0 < distance_m < 100:
        raise ValueError("pixels_per_metre must be > 0 and distance_m in (0, 100) m")
    return _make_camera(paper_rotation(view_deg), (0.0, 0.0, distance_m), pixels_per_metre,
                        pixels_per_metre, centre[0], centre[1], 0.0, 0)


def pinhole_camera(intrinsics, rotation, translation_m) -> ViewCamera:
    """A calibrated pinhole camera (OpenCV conventions, lens distortion already removed).

    Args:
        intrinsics: (3, 3) K = [[fx, skew, cx], [0, fy, cy], [0, 0, 1]], pixels.
        rotation: (3, 3) model frame -> camera frame rotation (det +1).
        translation_m: (3,) metres, camera frame; a person photographed from 2.5-3.5 m away
            has translation_m[2] around 3.

    Raises:
        ValueError: wrong shapes, K not upper-triangular with positive fx, fy and
            K[2, 2] = 1, or a rotation that is not a proper rotation matrix.
    """
    k = np.asarray(intrinsics, dtype=np.float64)
    r = np.asarray(rotation, dtype=np.float64)
    t = np.asarray(translation_m, dtype=np.float64)
    if k.shape != (3, 3) or r.shape != (3, 3) or t.shape != (3,):
        raise ValueError(f"intrinsics and rotation must have shape (3, 3) and translation_m "
                         f"(3,), got {k.shape}, {r.shape} and {t.shape}")
    if k[0, 0] <= 0 or k[1, 1] <= 0 or np.any(k[[1, 2, 2], [0, 0, 1]] != 0) or k[2, 2] != 1:
        raise ValueError("intrinsics must be [[fx, skew, cx], [0, fy, cy], [0, 0, 1]] "
                         "with fx, fy > 0")
    if not np.allclose(r @ r.T, np.eye(3), atol=1e-5) or np.linalg.det(r) < 0:
        raise ValueError("rotation must be a proper rotation matrix (orthonormal, det +1)")
    return _make_camera(r, t, k[0, 0], k[1, 1], k[0, 2], k[1, 2], k[0, 1], 1)


def camera_matrices(cam: ViewCamera) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A camera's (K (3, 3), R (3, 3), t (3,)) as float64 NumPy arrays, for host code.

    For an orthographic camera K holds the pixels-per-metre scale and the principal point
    (K[2, 2] = 1), so that [u, v] = K[:2] @ [x_cam, y_cam, 1].
    """
    k = np.array([[cam.fx, cam.skew, cam.cx], [0.0, cam.fy, cam.cy], [0.0, 0.0, 1.0]])
    r = np.array(cam.rotation, dtype=np.float64).reshape(3, 3)
    t = np.array(cam.translation, dtype=np.float64)
    return k, r, t
