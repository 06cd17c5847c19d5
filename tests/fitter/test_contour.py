"""The paper's CPU contour registration: tracing, normalisation, rigid ICP."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from bodyfit.fitter.fit.contour import contour_points, normalise_contour, rigid_icp


def _figure() -> np.ndarray:
    """A (200, 160) bool mask shaped roughly like a person: no symmetry ICP could confuse."""
    mask = np.zeros((200, 160), np.uint8)
    cv2.ellipse(mask, (80, 30), (16, 20), 0, 0, 360, 1, -1)      # head
    cv2.ellipse(mask, (80, 90), (30, 45), 0, 0, 360, 1, -1)      # torso
    cv2.line(mask, (60, 70), (20, 130), 1, 9)                    # arms, not mirror images
    cv2.line(mask, (100, 70), (135, 120), 1, 9)
    cv2.line(mask, (70, 120), (60, 190), 1, 14)                  # legs
    cv2.line(mask, (90, 120), (105, 190), 1, 14)
    return mask.astype(bool)


def test_contour_is_the_traced_outer_boundary():
    mask = np.zeros((20, 30), bool)
    mask[5:15, 4:24] = True
    points = contour_points(mask)
    assert len(points) == 2 * (10 - 1) + 2 * (20 - 1)
    assert set(map(tuple, points.astype(int))) == {
        (x, y) for y in range(5, 15) for x in range(4, 24) if y in (5, 14) or x in (4, 23)}


def test_normalised_contour_has_zero_mean_and_unit_radius():
    points = contour_points(_figure())
    normalised, centre, scale = normalise_contour(points)
    assert np.allclose(normalised.mean(axis=0), 0.0, atol=1e-12)
    assert np.sqrt((normalised ** 2).sum(axis=1).mean()) == pytest.approx(1.0)
    assert np.allclose(normalised * scale + centre, points)


@pytest.mark.parametrize("angle_deg, shift", [(6.0, (15.0, -9.0)), (-10.0, (-4.0, 22.0))])
def test_icp_recovers_a_known_rotation_and_translation(angle_deg, shift):
    person = contour_points(_figure())
    t = np.deg2rad(angle_deg)
    rotation = np.array([[np.cos(t), -np.sin(t)], [np.sin(t), np.cos(t)]])
    model = person[::2] @ rotation.T + shift  # every other point: not the same samples
    fit = rigid_icp(person, model)
    # point-to-point ICP settles within about a sample spacing (here 1-2 px) of the truth
    estimated_deg = np.rad2deg(np.arctan2(fit.rotation[1, 0], fit.rotation[0, 0]))
    assert estimated_deg == pytest.approx(angle_deg, abs=0.5)
    assert np.abs(fit.apply(person) - (person @ rotation.T + shift)).max() < 1.0
    assert fit.distances.max() < 2.0 and fit.matches.shape == (len(person),)
    # from the centroid start alone (no iterations) the error is several pixels
    assert np.abs(person + model.mean(0) - person.mean(0) - (person @ rotation.T + shift)).max() > 5
