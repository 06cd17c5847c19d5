"""The ± a fit reports with each measurement, millimetres.

Three kinds (``SPREAD_BASES``):

- ``"calibrated"``, for fits with bodyfit's default method (:func:`calibration_applies`):
  the measurement's factor from ``data/spread_calibration.json`` times the fit's
  *answer cost*, the cost (weighted mm, Eq. 17: the search's pixel cost) of its answer
  (the mean of the answers a fit averaged, for the population searches). The factors are
  such that on the accuracy benchmark's people as they stand (full Anny bodies posed by
  their own skeleton, photographed through a hand-held phone: the benchmark's stand-in
  for real people) the truth lay within the ± for 68.3 % of the subjects, each
  measurement (one standard deviation's share of a normal error); they come from
  ``python -m bench.accuracy spread`` on the default's fits of the standing set's choice
  rows (docs/accuracy.md, "People as they stand"; the calibration file names its
  command). The cost scales the ± because a
  body the model's space cannot reproduce leaves its silhouettes matched worse: the
  in-space subjects' answer costs are smaller than the out-of-space ones', their errors
  smaller still. Real photos (clothes, hair, a segmentation less clean than the
  benchmark's) may err more than this ± says.
- ``"solver"``, for fits that end with the local solver alone under other settings (no
  population to measure): the default method's factors times the fit's answer cost, as
  above, but not checked against the truth for these settings.
- ``"population"``, for the population searches' other settings: the best quarter of the
  searches' final populations, pooled (at least three with a finite cost), are measured
  like the fitted body, and each measurement's spread is their standard deviation. It
  says how well the photos pinned a measurement down under that search, not how near the
  truth is (on the benchmark it held the truth for 15-64 % of the subjects per
  measurement, and did not rank the subjects by their errors).

The stature (O) is the person's own, given: its calibrated ± is a few hundredths of a mm.
"""

from __future__ import annotations

import dataclasses
import functools
import json
from importlib import resources

import numpy as np

from bodyfit.fitter.fit.search import SearchResult
from bodyfit.fitter.fit.stature import scaled_to_stature
from bodyfit.fitter.measure.measurements import MEASUREMENTS, Measurer
from bodyfit.fitter.model.body_model import BodyModel, rest_shape

__all__ = ["SPREAD_BASES", "SPREAD_NOTES", "CALIBRATION_FILE", "CALIBRATION_FORMAT", "COVERAGE",
           "POOR_MATCH_COST", "SpreadCalibration", "answer_cost", "bodyfit_calibration",
           "calibration_applies", "match_warning", "population_spreads", "read_calibration",
           "recorded_answer_cost"]

#: The kinds of ± (module docstring); a fit's ``spread_basis`` is one of them.
SPREAD_BASES = ("calibrated", "solver", "population")
#: What each kind of ± means, in a sentence for the report and the command line.
SPREAD_NOTES = {
    "calibrated": "the fit's ± held the truth for 68 % of the accuracy benchmark's people "
                  "as they stand (synthetic photos), scaled by how well this fit matched the "
                  "silhouettes, then weighed with what ANSUR II's adults of this stature "
                  "measure; real photos may err more",
    "solver": "the ± is the default method's calibration applied to this fit's cost; "
              "for these settings it is not checked against the truth",
    "population": "the ± is the measurement's standard deviation over the best quarter of "
                  "the searches' final populations (settings other than the default "
                  "method's), not a confidence interval",
}
CALIBRATION_FILE = "spread_calibration.json"
CALIBRATION_FORMAT = "bodyfit.spread_calibration/1"
#: The calibrated ±'s share of subjects: a normal error's within one standard deviation.
COVERAGE = 0.6827
#: An answer cost (weighted mm, the local solver's) above which a fit is warned of: the
#: default's fits of the benchmark's plain-backdrop photos stay under 60 (in-space,
#: out-of-space and standing, 600 subjects), its room fits whose silhouettes had the
#: person's height under 100; the five of the in-space room set's first 24 whose
#: silhouette took in a picture above the head or a chair below the feet, or lost a foot,
#: scored 170-226 and erred 21-52 mm (docs/accuracy.md, "People in rooms").
POOR_MATCH_COST = 100.0
_POPULATION_SHARE = 0.25
_POPULATION_MIN = 3


@dataclasses.dataclass(frozen=True)
class SpreadCalibration:
    """The calibrated ± per unit of answer cost.

    Attributes:
        per_cost: key ("A".."P") -> mm of ± per weighted mm of answer cost.
        coverage: the share of the calibration's subjects whose |error| lay within the ±,
            each measurement (0.683).
        subjects: how many subjects the factors come from.
        median_cost: their median answer cost, weighted mm (the ± there: ``per_cost`` times
            it).
        source: the command that wrote them.
    """

    per_cost: dict[str, float]
    coverage: float
    subjects: int
    median_cost: float
    source: str

    @classmethod
    def made_from(cls, errors: np.ndarray, costs: np.ndarray, source: str,
                  coverage: float = COVERAGE) -> "SpreadCalibration":
        """The calibration under which the truth lies within the ± for ``coverage`` of the
        subjects, each measurement: ``errors`` (N, 16) estimate - truth, mm, columns in
        ``MEASUREMENTS`` order, of fits whose answer costs were ``costs`` (N,), weighted mm;
        each factor is that quantile of |error| / cost (linear interpolation)."""
        ratios = np.abs(np.asarray(errors, float)) / np.asarray(costs, float)[:, None]
        factors = np.quantile(ratios, coverage, axis=0)
        return cls(dict(zip(MEASUREMENTS, factors.tolist())), coverage, len(ratios),
                   float(np.median(costs)), source)

    def spreads(self, cost: float) -> dict[str, float]:
        """key -> mm: the ± of a fit whose answer cost is ``cost`` (weighted mm)."""
        return {key: factor * cost for key, factor in self.per_cost.items()}

    def as_json(self) -> dict:
        return {"format": CALIBRATION_FORMAT, "coverage": self.coverage,
                "subjects": self.subjects, "median_cost": round(self.median_cost, 6),
                "source": self.source,
                "per_cost": {key: round(value, 6) for key, value in self.per_cost.items()}}


def read_calibration(text: str | None = None) -> SpreadCalibration:
    """The calibration in ``text`` (JSON), or bodyfit's own (``data/``) when None.

    Raises:
        ValueError: not a calibration of this format.
        KeyError: a field or a measurement missing.
    """
    if text is None:
        text = resources.files("bodyfit.fitter.data").joinpath(CALIBRATION_FILE).read_text()
    record = json.loads(text)
    if record.get("format") != CALIBRATION_FORMAT:
        raise ValueError(f"not a spread calibration ({CALIBRATION_FORMAT})")
    per_cost = {key: float(record["per_cost"][key]) for key in MEASUREMENTS}
    return SpreadCalibration(per_cost, float(record["coverage"]), int(record["subjects"]),
                             float(record["median_cost"]), str(record["source"]))


@functools.cache
def bodyfit_calibration() -> SpreadCalibration:
    """bodyfit's own calibration (read once)."""
    return read_calibration()


def answer_cost(result: SearchResult) -> float:
    """The mean cost of the answers ``result`` averaged (weighted mm), or its own cost when
    it averaged none."""
    answers = result.averaged_from or (result,)
    return float(np.mean([answer.cost for answer in answers]))


def recorded_answer_cost(record: dict) -> float:
    """:func:`answer_cost` of the fit whose run.json payload is ``record`` (its
    ``result.averaged`` answers' costs, or its ``best_cost``)."""
    result = record["result"]
    return float(np.mean([a["cost"] for a in result.get("averaged") or []]
                         or [result["best_cost"]]))


def match_warning(cost: float, basis: str) -> str | None:
    """One line for a fit whose answer ``cost`` (weighted mm) exceeds
    :data:`POOR_MATCH_COST`, for the local solver's costs (``basis`` "calibrated" or
    "solver"); None otherwise."""
    if basis == "population" or cost <= POOR_MATCH_COST:
        return None
    return (f"the fitted body matches the silhouettes poorly (cost {cost:.0f} weighted mm; "
            f"sound fits stay under {POOR_MATCH_COST:.0f}): look at photo_front.png and "
            "photo_side.png for a silhouette that took in part of the room or lost a foot, "
            "and photograph again against a plainer background")


def calibration_applies(settings, default) -> bool:
    """Whether the fit settings ``settings`` are the method ``default`` the calibration was
    made with: equal but for where and how fast they run (device, threads) and the seed."""
    def method(s):
        return dataclasses.replace(s, device=default.device, threads=default.threads,
                                   search=dataclasses.replace(s.search, seed=default.search.seed))
    return method(settings) == default


def population_spreads(model: BodyModel, measurer: Measurer, result: SearchResult,
                       stature_m: float | None) -> dict[str, float]:
    """key -> mm, the ``"population"`` spread (module docstring); each candidate rescaled
    to ``stature_m`` first when given (as the fitted body is)."""
    finite = np.flatnonzero(np.isfinite(result.final_costs))
    count = max(_POPULATION_MIN, int(np.ceil(_POPULATION_SHARE * len(result.final_costs))))
    chosen = finite[np.argsort(result.final_costs[finite])][:count]
    k = len(result.betas)
    rest, _ = rest_shape(model, result.final_genes[chosen, :k])
    if stature_m is not None:
        rest = scaled_to_stature(rest, stature_m)
    values = measurer.measure_many(rest)
    spread = np.nanstd(values, axis=0, ddof=1) if len(chosen) > 1 else np.full(16, np.nan)
    return dict(zip(MEASUREMENTS, spread.tolist()))
