"""The girths scaled to the mass (fitter/fit/mass_volume.py): the volume of a box and of
closed bodies, the scale against a body actually scaled across, and a fit given its
body's own mass."""

import dataclasses

import numpy as np
import pytest
import trimesh

from bodyfit.fitter.demo.studio_photos import write_subject
from bodyfit.common.errors import UserError
from bodyfit.fitter.fit.mass_volume import (DENSITY_KG_PER_L, MASS_MISMATCH, SCALED, mass_scale,
                                            mass_scaled, mesh_volume_l)
from bodyfit.fitter.fit.person import PersonInputs
from bodyfit.fitter.fit.person_fit import FitSettings, fit_inputs
from bodyfit.kernels.body_forward import rest_shape

BETAS = np.array([1.2, 0.9, -0.7, 0.4, 0.6] + [0.0] * 15)


@pytest.fixture(scope="module")
def body(body_model):
    return rest_shape(body_model, BETAS[None])[0][0].astype(np.float64)


def test_the_volume_of_a_box_and_of_the_bodies(body_model, body):
    """A box's volume exactly (the analytic case), and the model's bodies closed (a
    mesh with holes has no volume to read) and of an adult's volume."""
    box = np.array([[x, y, z] for x in (0, .3) for y in (0, .2) for z in (0, 1.5)])
    faces = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
                      [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]])
    assert mesh_volume_l(box, faces) == pytest.approx(90.0, rel=1e-12)
    for vertices in (body_model.mean_vertices, body):
        assert trimesh.Trimesh(vertices, body_model.faces, process=False).is_watertight
        assert 40 < mesh_volume_l(vertices, body_model.faces) < 150


def test_the_scale_is_the_bodys_scaled_across(body_model, measurer, body):
    """The body scaled across by 1.08 has 1.08^2 its volume; given that mass, the fit's body
    scales by 1.08, and its horizontal girths are the scaled body's."""
    across = body * np.array([1.08, 1.08, 1.0])
    litres = mesh_volume_l(across, body_model.faces)
    assert litres == pytest.approx(1.08 ** 2 * mesh_volume_l(body, body_model.faces))
    scale = mass_scale(litres * DENSITY_KG_PER_L, body, body_model.faces)
    assert scale == pytest.approx(1.08)
    measured = measurer.measure(body.astype(np.float32))
    scaled = mass_scaled(measured, scale)
    wider = measurer.measure(across.astype(np.float32))
    for key in ("D", "E", "F", "L"):  # horizontal sections: exactly the scaled body's
        assert scaled[key] == pytest.approx(wider[key], rel=2e-3), key
    for key in set(measured) - set(SCALED):
        assert scaled[key] == measured[key]


def test_a_mass_not_the_bodys_is_refused(body_model, body):
    """A mass within MASS_MISMATCH of what the body holds scales it; pounds given as
    kilograms (2.2 times), or under 1 / MASS_MISMATCH of it, are refused in one line."""
    held = DENSITY_KG_PER_L * mesh_volume_l(body, body_model.faces)
    for factor in (0.99 * MASS_MISMATCH, 1.01 / MASS_MISMATCH):
        assert mass_scale(factor * held, body, body_model.faces) == pytest.approx(
            np.sqrt(factor))
    for factor in (2.2, 1.01 * MASS_MISMATCH, 0.99 / MASS_MISMATCH):
        with pytest.raises(UserError, match=rf"--mass-kg {factor * held:g} is .* times what "
                                            rf"the body in the photos weighs \(about "
                                            rf"{held:.0f} kg\): give this person's mass in "
                                            "kilograms"):
            mass_scale(factor * held, body, body_model.faces)


def test_a_fit_given_its_bodys_mass_keeps_its_girths_near_the_truth(body_model, tmp_path):
    truth = write_subject(tmp_path, body_model, BETAS, np.array([6.0, 6.0, 3.0, 3.0]))
    true_body = rest_shape(body_model, BETAS[None])[0][0]
    mass = DENSITY_KG_PER_L * mesh_volume_l(true_body, body_model.faces)
    settings = dataclasses.replace(FitSettings(), projection="orthographic",
                                   measurement_prior="none")
    inputs = PersonInputs(str(tmp_path / "front.png"), str(tmp_path / "side.png"),
                          truth["O"] / 10, check=False)
    plain = fit_inputs(body_model, inputs, settings, progress=False)
    weighed = fit_inputs(body_model, dataclasses.replace(inputs, mass_kg=mass), settings,
                         progress=False)
    assert plain.mass_scale is None
    assert weighed.mass_scale == pytest.approx(1.0, abs=0.03)  # the fit's volume is right
    for key, value in plain.measurements.items():
        expected = value * weighed.mass_scale if key in SCALED else value
        assert weighed.measurements[key] == pytest.approx(expected, rel=1e-9), key
    assert np.mean([abs(weighed.measurements[k] - truth[k]) for k in "DEF"]) < 8.0
    off = fit_inputs(body_model, dataclasses.replace(inputs, mass_kg=1.2 * mass),
                     settings, progress=False)
    assert off.mass_scale == pytest.approx(np.sqrt(1.2) * weighed.mass_scale, rel=1e-9)
