"""The measurements' prior (fitter/fit/measurement_prior.py): ANSUR II's conditional
normal against a Monte Carlo regression on draws of the same normal, the sexes' mixture,
and the precision-weighted combination against hand-computed cases."""

import numpy as np
import pytest

from bodyfit.fitter.fit.measurement_prior import PRIOR_KEYS, MeasurementPrior, combined
from bodyfit.fitter.run.config import run_config


@pytest.fixture(scope="module")
def prior():
    return MeasurementPrior.load()


@pytest.mark.parametrize("sex,with_mass", [("female", False), ("male", True)])
def test_the_prediction_is_the_regression_of_draws_of_ansurs_normal(prior, sex, with_mass):
    """A least-squares line of each measurement on the stature (and mass) over 400,000
    draws of the sex's normal predicts what the conditional does, with its residual SD."""
    st = prior.stats
    draws = np.random.default_rng(1).multivariate_normal(st.mean[sex], st.covariance(sex),
                                                         400_000)
    given = ["O", "mass_kg"] if with_mass else ["O"]
    design = np.c_[np.ones(len(draws)), draws[:, [st.keys.index(k) for k in given]]]
    targets = draws[:, [st.keys.index(k) for k in PRIOR_KEYS]]
    coef, *_ = np.linalg.lstsq(design, targets, rcond=None)
    residual_sd = (targets - design @ coef).std(axis=0)
    person = [1.0, 1700.0] + ([95.0] if with_mass else [])
    mean, sd = prior.predict(sex, 1700.0, 95.0 if with_mass else None)
    np.testing.assert_allclose([mean[k] for k in PRIOR_KEYS], np.array(person) @ coef, rtol=2e-3)
    np.testing.assert_allclose([sd[k] for k in PRIOR_KEYS], residual_sd, rtol=1e-2)


def test_the_mass_narrows_and_moves_the_girths(prior):
    light, light_sd = prior.predict("male", 1780.0, 60.0)
    heavy, heavy_sd = prior.predict("male", 1780.0, 120.0)
    _, no_mass_sd = prior.predict("male", 1780.0)
    for key in ("D", "E", "F", "L"):
        assert heavy[key] > light[key] + 100.0  # mm: 60 kg more on the same stature
        assert heavy_sd[key] == pytest.approx(light_sd[key])
        assert heavy_sd[key] < 0.6 * no_mass_sd[key]


def test_an_unknown_sex_mixes_the_sexes_by_their_likelihood(prior):
    male, male_sd = prior.predict("male", 1900.0, 95.0)  # a tall, heavy person: a man
    mixed, mixed_sd = prior.predict("unknown", 1900.0, 95.0)
    assert mixed["D"] == pytest.approx(male["D"], abs=2.0)
    female, _ = prior.predict("female", 1640.0)
    middle, middle_sd = prior.predict("unknown", 1690.0)
    # between the sexes: the mixture's mean lies between theirs, its SD wider than either
    men, men_sd = prior.predict("male", 1690.0)
    women, women_sd = prior.predict("female", 1690.0)
    assert min(men["P"], women["P"]) < middle["P"] < max(men["P"], women["P"])
    assert middle_sd["P"] > max(men_sd["P"], women_sd["P"])
    assert female["K"] < male["K"]


def test_the_combination_weighs_each_reading_by_its_precision():
    values, sds = combined({"D": 1000.0, "E": 900.0, "H": 300.0, "K": float("nan")},
                           {"D": 20.0, "E": 1.0, "H": 10.0, "K": 5.0},
                           {"D": 1100.0, "E": 800.0, "K": 800.0},
                           {"D": 20.0, "E": 1000.0, "K": 5.0})
    assert values["D"] == pytest.approx(1050.0) and sds["D"] == pytest.approx(20 / np.sqrt(2))
    # a sound fit (± 1 mm) against a vague prior keeps its value
    assert values["E"] == pytest.approx(900.0 - 100.0 / 1_000_001)
    assert (values["H"], sds["H"]) == (300.0, 10.0)  # no prior: the fit's
    assert np.isnan(values["K"]) and sds["K"] == 5.0  # no fitted value: nothing to weigh


def test_runs_recorded_before_the_prior_repeat_without_it():
    record = {"inputs": {"front": "f.png", "side": "s.png", "height_cm": 170.0},
              "settings": {"projection": "orthographic"}}
    assert run_config(record).settings.measurement_prior == "none"
    assert run_config(record).settings.mass_scaling == "none"  # nor the mass's scaling
    record["settings"] = {"measurement_prior": "ansur", "mass_scaling": "girths"}
    assert run_config(record).settings.measurement_prior == "ansur"
    assert run_config(record).settings.mass_scaling == "girths"
