"""Conditioning candidates on the known stature: every candidate is as tall as the person.

Along the first shape component (mostly stature) the cost is steep: +-0.1 sigma costs as
much as a whole sigma of most others, so a search spends its budget there. Here the first
beta is not searched but solved, per candidate, so that the candidate has the person's
height, and the search is over the shape's other components and the pose. Which height
(``posed``):

- **the rest stature** (pinhole views, the default): the candidate's stature in the rest
  pose, where stature is measured, equals the person's. The person's own body is then a
  candidate (with their pose), and the camera placed for a candidate
  (:func:`bodyfit.fitter.fit.person_fit.placement_body`) shows it at the person's size.
- **the posed height** (orthographic views): the candidate's silhouette height, top of
  the head to the lowest sole with its legs apart, equals the stature, as the
  orthographic canvas is scaled so that the person's silhouette is the stature tall
  (:mod:`bodyfit.fitter.fit.canvas`). A person standing with the legs apart is a few
  millimetres lower than their stature, so such a candidate is the person scaled by
  ``stature / (stature - delta)``; :func:`stature_scale` undoes that: the fitted body is
  scaled uniformly so that its rest stature is the given one.

Conditioning on the posed height in pinhole views too (the default before) left every
candidate 0.2-0.7 % taller than the person and changed its shape along the first
component to get there; on the rest stature the in-space error fell (docs/history.md, [13]).

The vertices are linear in the betas for a fixed pose (Eq. 1-3 with the rotations
fixed), so a height is piecewise linear in the first beta; Newton steps on the vertices
near the top and the bottom of the body converge in a few iterations.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from bodyfit.fitter.model.body_model import BodyModel, forward

__all__ = ["StatureConditioner", "stature_scale", "scaled_to_stature"]

#: Vertices within this distance (metres) of the top or bottom of any extreme body are
#: the candidates for a body's highest and lowest points (679 of 13,348 vertices; over
#: 3,000 random bodies of the search's range, +-3 sigma and every pose, the highest and
#: the lowest vertex were always among them; 5 mm missed 5 per cent of the lowest).
_EXTREME_BAND_M = 0.01
_ITERATIONS = 6


class StatureConditioner:
    """Solves each candidate's first beta so that its height is the person's ``stature_m``.

    Args:
        model: the body model.
        num_components: K, the betas of a full candidate.
        stature_m: the person's stature, the height every candidate must have, metres.
        beta_limit: the solved beta is kept within +-this (a body that cannot reach the
            height inside it keeps the limit, and its silhouette's height then differs).
        bodies: (B, V, 3) metres, bodies spanning the search's shapes and poses
            (:func:`bodyfit.fitter.fit.canvas.extreme_bodies`): the vertices near their highest
            and lowest points are the only ones a candidate's height is read from.
        posed: condition the posed height (the silhouette's, orthographic views) instead
            of the rest stature (module docstring).
    """

    def __init__(self, model: BodyModel, num_components: int, stature_m: float,
                 beta_limit: float, bodies: np.ndarray, *, posed: bool = False):
        self.num_components = num_components
        self.posed = posed
        self.stature_m = float(stature_m)
        self.beta_limit = float(beta_limit)
        band = self._extreme_vertices(np.asarray(bodies)[..., 2])
        self._model = dataclasses.replace(
            model, mean_vertices=model.mean_vertices[band],
            vertex_components=model.vertex_components[:, band],
            chain_weights=model.chain_weights[band], vertex_parts=model.vertex_parts[band])

    @staticmethod
    def _extreme_vertices(z: np.ndarray) -> np.ndarray:
        """Indices of the vertices that can be a body's highest or lowest point, from the
        (B, V) heights of the extreme bodies."""
        top = z >= z.max(axis=1, keepdims=True) - _EXTREME_BAND_M
        bottom = z <= z.min(axis=1, keepdims=True) + _EXTREME_BAND_M
        return np.flatnonzero((top | bottom).any(axis=0))

    def _z(self, betas: np.ndarray, pose_deg: np.ndarray) -> np.ndarray:
        """(P, V') float64 heights of the extreme vertices, metres: posed, or in the rest
        pose (zero angles) unless ``posed``."""
        if not self.posed:
            pose_deg = np.zeros_like(pose_deg)
        return forward(self._model, betas, pose_deg)[..., 2].astype(np.float64)

    def complete(self, other_betas: np.ndarray, pose_deg: np.ndarray) -> np.ndarray:
        """(P, K) float64 betas: the solved first beta, then ``other_betas``.

        Args:
            other_betas: (P, K - 1) betas 2..K, standard deviations.
            pose_deg: (P, 4) degrees (unused unless ``posed``).
        """
        other_betas = np.asarray(other_betas, np.float64)
        # for a fixed pose the vertices are linear in the betas (Eq. 1-3 with the
        # rotations fixed), so the heights are base + first beta * slope
        zero = np.zeros((len(other_betas), 1))
        base = self._z(np.hstack([zero, other_betas]), pose_deg)  # (P, V')
        slope = self._z(np.hstack([zero + 1.0, other_betas]), pose_deg) - base
        first = np.zeros(len(other_betas))
        rows = np.arange(len(first))
        for _ in range(_ITERATIONS):
            z = base + first[:, None] * slope
            top, bottom = z.argmax(axis=1), z.argmin(axis=1)
            height = z[rows, top] - z[rows, bottom]
            rate = slope[rows, top] - slope[rows, bottom]  # metres per sigma
            first = np.clip(first + (self.stature_m - height) / rate,
                            -self.beta_limit, self.beta_limit)
        return np.concatenate([first[:, None], other_betas], axis=1)


def stature_scale(rest_vertices: np.ndarray, stature_m: float) -> float:
    """The uniform scale that gives a (V, 3) rest body the stature ``stature_m``."""
    return float(stature_m / np.ptp(rest_vertices[:, 2]))


def scaled_to_stature(rest_bodies: np.ndarray, stature_m) -> np.ndarray:
    """(N, V, 3) rest bodies, each scaled by its own :func:`stature_scale` to ``stature_m``
    (metres: one for all, or (N,) one per body)."""
    statures = np.broadcast_to(np.asarray(stature_m, dtype=np.float64), (len(rest_bodies),))
    return np.stack([body * stature_scale(body, s) for body, s in zip(rest_bodies, statures)])
