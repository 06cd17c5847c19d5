"""The ± of a fit's measurements (fitter/fit/spreads.py): the calibration, its file, when it
applies, and the answer cost it scales with."""

import dataclasses
import json

import numpy as np
import pytest

from bodyfit.fitter.fit.person_fit import METHODS, FitSettings
from bodyfit.fitter.fit.search import SearchSettings
from bodyfit.fitter.fit.spreads import (COVERAGE, SpreadCalibration, answer_cost,
                                        bodyfit_calibration, calibration_applies, read_calibration,
                                        recorded_answer_cost)
from bodyfit.fitter.measure.measurements import MEASUREMENTS


def test_made_from_errors_proportional_to_the_cost_gives_their_ratio():
    """Errors that are each measurement's own multiple of the cost (signs mixed): the
    factor is that multiple, and the ± of a new cost scales with it."""
    costs = np.array([10.0, 14.0, 20.0, 31.0, 25.0])
    multiples = np.linspace(0.05, 0.8, 16)
    signs = np.where(np.arange(5) % 2, 1.0, -1.0)[:, None]
    calibration = SpreadCalibration.made_from(signs * costs[:, None] * multiples, costs, "test")
    np.testing.assert_allclose(list(calibration.per_cost.values()), multiples, rtol=1e-12)
    np.testing.assert_allclose(list(calibration.spreads(40.0).values()), 40.0 * multiples)
    assert calibration.subjects == 5 and calibration.coverage == COVERAGE


def test_made_from_holds_its_share_of_the_subjects():
    """On the subjects it is made from, the ± holds the truth for the coverage's share (the
    quantile of |error| / cost, NumPy's linear interpolation: floor(0.6827 (N - 1)) + 1 of
    N within when the ratios are distinct, 69 of 101)."""
    rng = np.random.default_rng(3)
    costs = rng.uniform(10, 40, 101)
    errors = rng.normal(0, 1, (101, 16)) * costs[:, None] * rng.uniform(0.1, 0.5, 16)
    calibration = SpreadCalibration.made_from(errors, costs, "test")
    within = np.abs(errors) <= np.array([list(calibration.spreads(c).values()) for c in costs])
    np.testing.assert_array_equal(within.sum(axis=0), 69)


def test_calibration_file_round_trips_and_bad_files_are_refused():
    calibration = SpreadCalibration.made_from(np.ones((3, 16)), np.array([1.0, 2.0, 4.0]),
                                              "python -m bench.accuracy spread ...")
    assert read_calibration(json.dumps(calibration.as_json())) == calibration
    with pytest.raises(ValueError, match="not a spread calibration"):
        read_calibration(json.dumps({"format": "bodyfit.camera/1"}))
    record = calibration.as_json()
    del record["per_cost"]["D"]
    with pytest.raises(KeyError):
        read_calibration(json.dumps(record))


def test_bodyfits_calibration_covers_every_measurement():
    own = bodyfit_calibration()
    assert list(own.per_cost) == list(MEASUREMENTS) and own.coverage == COVERAGE
    assert own.subjects >= 20 and "bench.accuracy spread" in own.source
    assert all(factor > 0 for factor in own.per_cost.values())
    assert own.per_cost["O"] < 0.01  # the stature is given


def test_calibration_applies_to_the_default_method_alone():
    default = METHODS["bodyfit"]
    assert calibration_applies(FitSettings(), default)
    assert calibration_applies(dataclasses.replace(
        default, device="cuda:0", threads=3,
        search=dataclasses.replace(default.search, seed=7)), default)
    assert not calibration_applies(METHODS["paper"], default)
    assert not calibration_applies(METHODS["thorough"], default)
    assert not calibration_applies(dataclasses.replace(
        default, solver=dataclasses.replace(default.solver, iterations=5)), default)
    assert not calibration_applies(dataclasses.replace(
        default, search=SearchSettings(refinements=4)), default)
    assert not calibration_applies(dataclasses.replace(default, projection="orthographic"),
                                   default)


@dataclasses.dataclass
class _Answer:
    cost: float
    averaged_from: tuple = ()


def test_answer_cost_is_the_mean_of_the_answers_averaged():
    assert answer_cost(_Answer(9.0, (_Answer(10.0), _Answer(14.0), _Answer(21.0)))) == 15.0
    assert answer_cost(_Answer(9.0)) == 9.0
    assert recorded_answer_cost({"result": {"best_cost": 9.0, "averaged": [
        {"cost": 10.0}, {"cost": 14.0}, {"cost": 21.0}]}}) == 15.0
    assert recorded_answer_cost({"result": {"best_cost": 9.0, "averaged": []}}) == 9.0
