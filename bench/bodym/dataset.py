"""BodyM's split on disk: its subjects, their truths, their photo pairs, a fixed order.

BodyM (Amazon; N. Ruiz et al., WACV 2023; CC BY-NC 4.0: evaluation only, nothing of it
in the repository) gives per subject a stated height, weight and sex, 14 measurements of
the subject's 3D scan in centimetres, and one or more photo pairs: a front silhouette in
an A-pose (``mask/<photo_id>.png``) and one from the left with the arms down
(``mask_left/<photo_id>.png``), 720 x 960, white on black.

The benchmark's order of a split's subjects is fixed once, by a salted SHA-256 of each
subject's id (:func:`ordered`), so that it needs no list in the repository and does not
change when BodyM's files are read in another order. The first ``CHOICE_COUNT`` subjects
of the train split are the **choice** part (decisions, offsets, baselines), the rest the
**held-out** part (measured once per change that lands).
"""

from __future__ import annotations

import csv
import dataclasses
import hashlib
from pathlib import Path

import numpy as np

__all__ = ["DEFAULT_SPLIT", "BODYM_LETTERS", "SHARED_KEYS", "CHOICE_COUNT", "PARTS",
           "Subject", "read_split", "ordered", "part"]

#: The train split as laid out beside the repository (``../shared/data/bodym/train``).
DEFAULT_SPLIT = Path(__file__).resolve().parents[2].parent / "shared/data/bodym/train"
#: bodyfit measurement letter -> BodyM's column (its README); the height (O) is the input.
BODYM_LETTERS = {"C": "shoulder-to-crotch", "D": "chest", "E": "waist", "F": "hip",
                 "G": "wrist", "H": "bicep", "I": "forearm", "J": "arm-length",
                 "K": "leg-length", "L": "thigh", "M": "calf", "N": "ankle",
                 "P": "shoulder-breadth"}
#: The 13 measurements both have, in bodyfit's order.
SHARED_KEYS = tuple(sorted(BODYM_LETTERS))
#: Subjects of the train split's choice part; the rest are held out.
CHOICE_COUNT = 1000
PARTS = ("choice", "held-out")
_ORDER_SALT = b"bodyfit BodyM order 1:"


@dataclasses.dataclass(frozen=True)
class Subject:
    """One BodyM subject.

    Attributes:
        subject_id: BodyM's id.
        sex: "female" or "male".
        stated_height_cm, weight_kg: as the subject stated them.
        scan_height_cm: the height measured on the scan.
        truth_mm: letter (``SHARED_KEYS``) -> the scan's measurement, mm.
        photo_ids: the subject's photo pairs, the first as BodyM's joined_subjects.csv.
    """

    subject_id: str
    sex: str
    stated_height_cm: float
    weight_kg: float
    scan_height_cm: float
    truth_mm: dict[str, float]
    photo_ids: tuple[str, ...]

    @property
    def bmi(self) -> float:
        """Body mass index from the stated height and weight, kg/m^2."""
        return self.weight_kg / (self.stated_height_cm / 100.0) ** 2

    def truths(self, keys=SHARED_KEYS) -> np.ndarray:
        """(len(keys),) float64 mm."""
        return np.array([self.truth_mm[k] for k in keys])


def read_split(folder: Path = DEFAULT_SPLIT) -> list[Subject]:
    """The subjects of BodyM split ``folder`` (its ``joined_subjects.csv``), in
    :func:`ordered` order."""
    path = Path(folder) / "joined_subjects.csv"
    if not path.exists():
        raise SystemExit(f"{folder}: not a BodyM split (no joined_subjects.csv); see "
                         "../shared/data/bodym/README.md")
    with path.open(newline="") as f:
        rows = list(csv.DictReader(f))
    subjects = [Subject(row["subject_id"], row["gender"], float(row["height_cm"]),
                        float(row["weight_kg"]), float(row["height"]),
                        {k: 10.0 * float(row[c]) for k, c in BODYM_LETTERS.items()},
                        tuple(row["all_photo_ids"].split(";")))
                for row in rows]
    return ordered(subjects)


def ordered(subjects: list[Subject]) -> list[Subject]:
    """``subjects`` in the benchmark's fixed order: by the salted SHA-256 of their ids."""
    return sorted(subjects, key=lambda s: hashlib.sha256(
        _ORDER_SALT + s.subject_id.encode()).hexdigest())


def part(subjects: list[Subject], name: str) -> list[Subject]:
    """The ``name`` part (``PARTS``) of ordered ``subjects``."""
    if name not in PARTS:
        raise ValueError(f"part {name!r} is not one of {PARTS}")
    return subjects[:CHOICE_COUNT] if name == "choice" else subjects[CHOICE_COUNT:]
