"""Removing lens distortion from photos with kornia.

``kornia.geometry.calibration.undistort_image`` keeps the camera matrix: the output is
the image an ideal pinhole camera with the same K would have taken, the same size, so
straight lines in the scene are straight and ``K`` projects into it. Corners that the
lens never saw come out black. It agrees with ``cv2.undistort(image, K, dist)``.
"""

from __future__ import annotations

import numpy as np
import torch
from kornia.geometry.calibration import undistort_image as kornia_undistort_image

from bodyfit.calib.camera import Camera

__all__ = ["undistort_image"]


def undistort_image(image: np.ndarray, camera: Camera, name: str = "image") -> np.ndarray:
    """The photo as an ideal pinhole camera with ``camera.K`` would have taken it.

    Args:
        image: (H, W) or (H, W, C) uint8 or float32, sensor frame, the size the camera
            was calibrated on (UserError otherwise; ``name`` says which image).
        camera: the calibrated camera.

    Returns:
        Same shape and dtype as ``image``; bilinear resampling, black outside the lens's view.
    """
    camera.check_image(image, name)
    if image.dtype not in (np.uint8, np.float32):
        raise ValueError(f"undistort_image() takes uint8 or float32 pixels, got {image.dtype}")
    planes = image[..., None] if image.ndim == 2 else image
    tensor = torch.from_numpy(np.ascontiguousarray(planes)).permute(2, 0, 1)[None].to(torch.float32)
    K = torch.as_tensor(camera.K, dtype=torch.float32)
    dist = torch.as_tensor(camera.dist, dtype=torch.float32)
    with torch.inference_mode():
        result = kornia_undistort_image(tensor, K, dist)[0].permute(1, 2, 0).numpy()
    if image.dtype == np.uint8:
        result = np.clip(np.rint(result), 0, 255).astype(np.uint8)
    return result.reshape(image.shape)
