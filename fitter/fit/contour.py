"""The paper's contour registration on the CPU (Section 3.3, Eq. 13-16), for overlays.

The fitter scores candidates with the kernels (:mod:`bodyfit.kernels`), which align each
candidate by silhouette moments (:class:`bodyfit.kernels.alignment.SilhouetteMoments`:
centroid and principal axis). This module keeps the paper's own path for the final
body, to draw its matched contours: trace both boundaries, normalise them, register the
person's contour onto the model's by 2D rigid ICP (nearest neighbours from a KD-tree,
then the closed-form rotation and translation, repeated), and pair every person point
with its nearest model point.

Points are (column, row) pixels, float64.
"""

from __future__ import annotations

import dataclasses

import cv2
import numpy as np
from scipy.spatial import cKDTree

__all__ = ["RigidFit", "contour_points", "normalise_contour", "rigid_icp"]


@dataclasses.dataclass(frozen=True)
class RigidFit:
    """A 2D rigid registration: ``rotation @ z + translation`` maps source onto target.

    Attributes:
        rotation: (2, 2) float64, det +1.
        translation: (2,) float64, the points' units.
        distances: (N,) float64, each moved source point's distance to its match.
        matches: (N,) int, index of each source point's nearest target point.
        iterations: ICP iterations run.
    """

    rotation: np.ndarray
    translation: np.ndarray
    distances: np.ndarray
    matches: np.ndarray
    iterations: int

    def apply(self, points: np.ndarray) -> np.ndarray:
        """(N, 2) points moved by the fit."""
        return np.asarray(points, dtype=np.float64) @ self.rotation.T + self.translation


def contour_points(mask: np.ndarray) -> np.ndarray:
    """(N, 2) float64 outer boundary of the largest region of a (H, W) bool mask, traced in
    order (OpenCV's border following, like the paper's Moore-neighbour tracing).

    Raises:
        ValueError: the mask is not 2D or has no pixel.
    """
    mask = np.asarray(mask)
    if mask.ndim != 2 or not mask.any():
        raise ValueError(f"mask must be a non-empty (H, W) array, got shape {mask.shape}")
    contours, _ = cv2.findContours(mask.astype(np.uint8), cv2.RETR_EXTERNAL,
                                   cv2.CHAIN_APPROX_NONE)
    largest = max(contours, key=cv2.contourArea)
    return largest[:, 0, :].astype(np.float64)


def normalise_contour(points: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """The paper's contour normalisation: centred on its centroid, unit RMS radius.

    Returns:
        normalised: (N, 2) float64.
        centre: (2,) the centroid removed.
        scale: the RMS radius divided out (``points = normalised * scale + centre``).
    """
    points = np.asarray(points, dtype=np.float64)
    centre = points.mean(axis=0)
    scale = float(np.sqrt(((points - centre) ** 2).sum(axis=1).mean()))
    return (points - centre) / scale, centre, scale


def _procrustes(source: np.ndarray, target: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rotation and translation minimising sum ||R s_i + t - t_i||^2 (Kabsch, 2D)."""
    source_mean, target_mean = source.mean(axis=0), target.mean(axis=0)
    u, _, vt = np.linalg.svd((source - source_mean).T @ (target - target_mean))
    flip = np.diag([1.0, np.sign(np.linalg.det(vt.T @ u.T))])
    rotation = vt.T @ flip @ u.T
    return rotation, target_mean - rotation @ source_mean


def rigid_icp(source: np.ndarray, target: np.ndarray, max_iterations: int = 50,
              tolerance: float = 1e-6) -> RigidFit:
    """Register ``source`` onto ``target`` by iterative closest points (Eq. 13-16).

    Starts from the translation that matches the centroids; each iteration matches every
    moved source point to its nearest target point (KD-tree) and solves the rigid
    transform of the matches in closed form; stops when the mean distance improves by
    less than ``tolerance`` (the points' units).

    Args:
        source: (N, 2) float points, e.g. the person's contour.
        target: (M, 2) float points, e.g. the model's contour.
    """
    source = np.asarray(source, dtype=np.float64)
    target = np.asarray(target, dtype=np.float64)
    tree = cKDTree(target)
    rotation, translation = np.eye(2), target.mean(axis=0) - source.mean(axis=0)
    previous = np.inf
    for iteration in range(1, max_iterations + 1):
        distances, matches = tree.query(source @ rotation.T + translation)
        if previous - distances.mean() < tolerance:
            break
        previous = distances.mean()
        rotation, translation = _procrustes(source, target[matches])
    distances, matches = tree.query(source @ rotation.T + translation)
    return RigidFit(rotation, translation, distances, matches, iteration)
