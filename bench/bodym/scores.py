"""A BodyM run's errors against the scans, their statistics and the two baselines.

Errors are estimate - truth, millimetres, in ``SHARED_KEYS`` order. The **offset** of a
measurement is its mean signed error over the choice part's fits: a constant difference
of definition between bodyfit's measurement and BodyM's, reported apart from the error
that varies from person to person and removed for the "after offsets" figures. Both
baselines are made per evaluation, never shipped.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from bench.accuracy.scores import error_stats
from bench.bodym.dataset import SHARED_KEYS, Subject

__all__ = ["PAPER_TABLE2", "BMI_BANDS", "PhotoFits", "MeasurementStats", "measurement_stats",
           "offsets", "height_weight_predictions", "precision_sd", "bmi_band_errors"]

#: BodyM paper's Table 2 (Test-A, mean absolute error, mm) for the chest, waist and hip:
#: input -> letter -> mm.
PAPER_TABLE2 = {"front + side + height": {"D": 19.4, "E": 18.7, "F": 16.0},
                "front + side + height + weight": {"D": 15.9, "E": 15.4, "F": 9.7}}
#: Body mass index bands, kg/m^2: (label, low, high).
BMI_BANDS = (("under 18.5", 0.0, 18.5), ("18.5-25", 18.5, 25.0), ("25-30", 25.0, 30.0),
             ("30-35", 30.0, 35.0), ("35 and over", 35.0, np.inf))


@dataclasses.dataclass(frozen=True)
class PhotoFits:
    """A run's fitted photo pairs, row-aligned.

    Attributes:
        subjects: (N,) the subject of each fitted pair.
        photo_ids: (N,) str.
        estimates, spreads: (N, 13) mm, ``SHARED_KEYS`` order.
        costs: (N,) the fit's best cost, weighted mm.
        failures: (photo id, reason) of every pair the run refused or failed.
    """

    subjects: list[Subject]
    photo_ids: list[str]
    estimates: np.ndarray
    spreads: np.ndarray
    costs: np.ndarray
    failures: list[tuple[str, str]]

    @property
    def truths(self) -> np.ndarray:
        """(N, 13) mm."""
        return np.array([s.truths() for s in self.subjects]).reshape(-1, len(SHARED_KEYS))

    @property
    def errors(self) -> np.ndarray:
        """(N, 13) estimate - truth, mm."""
        return self.estimates - self.truths

    def first_photos(self) -> "PhotoFits":
        """Only each subject's first photo pair (BodyM's joined_subjects.csv)."""
        keep = [i for i, (s, p) in enumerate(zip(self.subjects, self.photo_ids))
                if s.photo_ids[0] == p]
        return dataclasses.replace(
            self, subjects=[self.subjects[i] for i in keep],
            photo_ids=[self.photo_ids[i] for i in keep], estimates=self.estimates[keep],
            spreads=self.spreads[keep], costs=self.costs[keep])


@dataclasses.dataclass(frozen=True)
class MeasurementStats:
    """Per-measurement statistics of (N, 13) errors, each (13,) unless said.

    Attributes:
        count: N.
        mae, median: mean and median |error|, mm.
        offset, offset_ci: mean signed error and its 95 % interval's half-width, mm.
        over_50, over_100: share (0-1) of people whose |error| exceeds 50 / 100 mm.
        covered: share (0-1) whose |error| <= the fit's ±.
        mae_after: mean |error - the given offsets|, mm.
        covered_after: share (0-1) whose |error - the given offsets| <= the fit's ±.
    """

    count: int
    mae: np.ndarray
    median: np.ndarray
    offset: np.ndarray
    offset_ci: np.ndarray
    over_50: np.ndarray
    over_100: np.ndarray
    covered: np.ndarray
    mae_after: np.ndarray
    covered_after: np.ndarray


def measurement_stats(errors: np.ndarray, spreads: np.ndarray,
                      removed_offsets: np.ndarray) -> MeasurementStats:
    """:class:`MeasurementStats` of ``errors`` and ``spreads`` (N, 13) mm, N >= 2, with
    ``removed_offsets`` (13,) mm subtracted for ``mae_after``."""
    errors = np.asarray(errors, float)
    raw = error_stats(errors, spreads)  # the accuracy benchmark's: mean, bias, intervals
    absolute = np.abs(errors)
    after = np.abs(errors - removed_offsets)
    return MeasurementStats(raw.count, raw.mae, np.median(absolute, 0), raw.bias,
                            raw.bias_ci, (absolute > 50).mean(0), (absolute > 100).mean(0),
                            raw.covered, after.mean(0), (after <= spreads).mean(0))


def offsets(choice_fits: PhotoFits) -> np.ndarray:
    """(13,) mm: the mean signed error of the choice part's fits (first photos)."""
    return choice_fits.first_photos().errors.mean(axis=0)


def _design(subjects: list[Subject]) -> np.ndarray:
    """(N, 4): 1, stated height (cm), weight (kg), male (0/1)."""
    return np.array([[1.0, s.stated_height_cm, s.weight_kg, float(s.sex == "male")]
                     for s in subjects])


def height_weight_predictions(train: list[Subject], people: list[Subject]) -> np.ndarray:
    """(N, 13) mm: each of ``people``'s measurements predicted from the stated height,
    the weight and the sex by a least-squares line per measurement over ``train``."""
    coef, *_ = np.linalg.lstsq(_design(train), np.array([s.truths() for s in train]),
                               rcond=None)
    return _design(people) @ coef


def precision_sd(fits: PhotoFits) -> tuple[np.ndarray, int]:
    """(13,) mm: the root mean square over subjects with two or more fitted photo pairs of
    the standard deviation of their measurements across their pairs (repeat photos of one
    body: a precision), and how many subjects that is."""
    by_subject: dict[str, list[int]] = {}
    for i, s in enumerate(fits.subjects):
        by_subject.setdefault(s.subject_id, []).append(i)
    variances = [fits.estimates[rows].var(axis=0, ddof=1)
                 for rows in by_subject.values() if len(rows) >= 2]
    if not variances:
        return np.full(len(SHARED_KEYS), np.nan), 0
    return np.sqrt(np.mean(variances, axis=0)), len(variances)


def bmi_band_errors(fits: PhotoFits, keys=("D", "E", "F")) -> list[tuple[str, int, np.ndarray,
                                                                          np.ndarray]]:
    """Per ``BMI_BANDS`` band with people: (label, count, (k,) mean signed error, (k,)
    mean |error|) of ``keys``, mm."""
    bmi = np.array([s.bmi for s in fits.subjects])
    columns = [SHARED_KEYS.index(k) for k in keys]
    errors = fits.errors[:, columns]
    out = []
    for label, low, high in BMI_BANDS:
        inside = (bmi >= low) & (bmi < high)
        if inside.any():
            out.append((label, int(inside.sum()), errors[inside].mean(0),
                        np.abs(errors[inside]).mean(0)))
    return out
