"""Part labels (paper Table 2) and landmarks of the topology."""

import numpy as np
from scipy.spatial import cKDTree

from bodyfit.fitter.model.body_model import PART_NAMES


def test_every_vertex_has_one_of_the_ten_parts(body_model):
    labels = body_model.vertex_parts
    assert labels.shape == (body_model.num_vertices,)
    assert labels.min() >= 0 and labels.max() < len(PART_NAMES)
    counts = np.bincount(labels, minlength=len(PART_NAMES))
    assert np.all(counts > 50), dict(zip(PART_NAMES, counts))


def mirror_pairs(vertices):
    mirrored = vertices * np.array([-1.0, 1.0, 1.0])
    dist, idx = cKDTree(vertices).query(mirrored)
    return dist, idx


def test_labels_are_left_right_symmetric(body_model):
    dist, idx = mirror_pairs(body_model.mean_vertices)
    paired = dist < 1e-3  # metres: the mesh is symmetric
    assert paired.mean() > 0.99
    labels = body_model.vertex_parts
    assert np.array_equal(labels[paired], labels[idx[paired]])


def test_parts_are_ordered_from_head_to_feet(body_model):
    z = body_model.mean_vertices[:, 2]
    height = {p: np.median(z[body_model.vertex_parts == i]) for i, p in enumerate(PART_NAMES)}
    torso_down = ("head", "neck", "chest", "waist", "hip", "leg", "foot")
    assert [height[part] for part in torso_down] == sorted(
        (height[part] for part in torso_down), reverse=True)
    assert height["arm"] > height["elbow"] > height["hand"]


def test_sided_landmarks_mirror_each_other(body_model):
    v = body_model.mean_vertices
    for name in ("acromion", "bust", "radiale", "stylion"):
        left, right = v[body_model.landmarks[name]]
        assert left[0] > 0 > right[0]
        np.testing.assert_allclose(left * [-1, 1, 1], right, atol=1e-3)
