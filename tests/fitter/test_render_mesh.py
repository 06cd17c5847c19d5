"""The lighter render mesh: the model's own vertices, the same extremes, nearly the same
silhouettes as the full mesh (rendered by the kernels)."""

import numpy as np
import pytest

from bodyfit import kernels
from bodyfit.fitter.fit.render_mesh import CLUSTERED_PARTS, render_model
from bodyfit.fitter.model.body_model import PART_NAMES, forward
from bodyfit.kernels.target import visible_faces
from bodyfit.kernels.view_camera import camera_matrices


@pytest.fixture(scope="module")
def light(body_model):
    return render_model(body_model, 8.0)


def test_only_head_and_feet_lose_triangles(body_model, light):
    full = np.bincount(body_model.face_parts, minlength=len(PART_NAMES))
    kept = np.bincount(light.face_parts, minlength=len(PART_NAMES))
    for part, name in enumerate(PART_NAMES):
        if name in CLUSTERED_PARTS:
            assert kept[part] < 0.75 * full[part], name
        else:
            assert kept[part] == full[part], name
    assert render_model(body_model, 0.0) is body_model
    with pytest.raises(ValueError):
        render_model(body_model, -1.0)


def test_vertices_are_the_models_own_and_skin_alike(body_model, light):
    """Every kept vertex is one of the model's, with its shape directions and weights, so
    a posed light body is a subset of the posed full body; top and bottom are kept."""
    index = {tuple(v): i for i, v in enumerate(body_model.mean_vertices)}
    kept = np.array([index[tuple(v)] for v in light.mean_vertices])
    rng = np.random.default_rng(3)
    betas, pose = rng.normal(size=(3, 20)), rng.uniform(-10, 30, (3, 4))
    full, mine = forward(body_model, betas, pose), forward(light, betas, pose)
    np.testing.assert_allclose(mine, full[:, kept], atol=1e-6)
    np.testing.assert_allclose(mine[..., 2].max(axis=1), full[..., 2].max(axis=1), atol=1e-6)
    np.testing.assert_allclose(mine[..., 2].min(axis=1), full[..., 2].min(axis=1), atol=1e-6)


def test_silhouettes_match_the_full_mesh(body_model, light):
    """Front and side at 400 px for random bodies: at most 0.1 % of the silhouette's pixels
    differ (ears, toes: 0.04 %; with the hands clustered too the side view's differed by
    0.23 %); the full mesh itself differs by 0."""
    rng = np.random.default_rng(5)
    betas, pose = np.clip(rng.normal(size=(4, 20)), -2, 2), rng.uniform(-5, 25, (4, 4))
    posed = forward(body_model, betas, pose)
    for view_deg in (kernels.FRONT_VIEW_DEG, kernels.SIDE_VIEW_DEG):
        k, r, t = camera_matrices(kernels.orthographic_camera(view_deg, 235.0, (0.0, 0.0)))
        px = (posed.reshape(-1, 3) @ r.T + t)[:, :2] @ k[:2, :2].T
        camera = kernels.orthographic_camera(view_deg, 235.0, 10.0 - px.min(axis=0))
        width, height = np.ceil(px.max(axis=0) - px.min(axis=0)).astype(int) + 20
        maps = []
        for model in (body_model, light):
            faces, parts = visible_faces(model.faces, model.face_parts, PART_NAMES)
            maps.append(kernels.rasterize(forward(model, betas, pose), faces, parts, camera,
                                          height, width).numpy() >= 0)
        full, mine = maps
        assert full.sum(axis=(1, 2)).min() > 10000
        assert not full[:, [0, -1]].any() and not full[:, :, [0, -1]].any()  # in frame
        assert (full ^ mine).sum() <= 0.001 * full.sum()
