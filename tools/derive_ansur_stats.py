"""Derive bodyfit's compact ANSUR II table: per-sex means, SDs and correlations.

ANSUR II (2012 US Army Anthropometric Survey, public data: 4,082 men, 1,986 women) is
bodyfit's reference for what real adult bodies measure. The model build samples its
population to match this table (``fitter/data/ansur2_stats.json``), which ships with the
project because users do not have the survey files.

Usage:
    python tools/derive_ansur_stats.py [--ansur-dir ../shared/data/ansur2] \
        [-o fitter/data/ansur2_stats.json]
"""

from __future__ import annotations

import argparse
import csv
import json
from pathlib import Path

import numpy as np

#: bodyfit measurement key (paper Fig. 10), and ``mass_kg`` -> ANSUR II columns summed (a
#: leading "-" subtracts one), all millimetres; C (shoulder-crotch length) is the acromion's
#: height less the crotch's, bodyfit's definition.
COLUMNS = {
    "A": ["headcircumference"],
    "B": ["neckcircumference"],
    "C": ["acromialheight", "-crotchheight"],
    "D": ["chestcircumference"],
    "E": ["waistcircumference"],
    "F": ["buttockcircumference"],
    "G": ["wristcircumference"],
    "H": ["bicepscircumferenceflexed"],
    "I": ["forearmcircumferenceflexed"],
    "J": ["acromionradialelength", "radialestylionlength"],
    "K": ["crotchheight"],
    "L": ["thighcircumference"],
    "M": ["calfcircumference"],
    "N": ["anklecircumference"],
    "O": ["stature"],
    "P": ["biacromialbreadth"],
    "mass_kg": ["weightkg"],
}
#: ANSUR II's units per column where they are not millimetres: weightkg is in tenths of a
#: kilogram.
SCALES = {"weightkg": 0.1}
FILES = {"male": "ANSUR_II_MALE_Public.csv", "female": "ANSUR_II_FEMALE_Public.csv"}


def read_sex(path: Path) -> np.ndarray:
    """(n, len(COLUMNS)) float64 millimetres (the mass in kg), one row per subject."""
    with open(path, newline="", encoding="latin-1") as fh:
        rows = list(csv.DictReader(fh))
    def value(row: dict, column: str) -> float:
        sign, name = (-1.0, column[1:]) if column.startswith("-") else (1.0, column)
        return sign * SCALES.get(name, 1.0) * float(row[name])

    return np.array([[sum(value(r, c) for c in cols) for cols in COLUMNS.values()]
                     for r in rows])


def main() -> None:
    here = Path(__file__).resolve().parent.parent
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--ansur-dir", type=Path, default=here.parent / "shared/data/ansur2")
    parser.add_argument("-o", "--output", type=Path,
                        default=here / "fitter/data/ansur2_stats.json")
    args = parser.parse_args()
    table = {"source": "ANSUR II public data (2012), derived by tools/derive_ansur_stats.py",
             "units": "mm (mass_kg: kg)", "keys": list(COLUMNS),
             "columns": {k: v[0] + "".join(c if c.startswith("-") else "+" + c for c in v[1:])
                         for k, v in COLUMNS.items()}, "sexes": {}}
    for sex, name in FILES.items():
        x = read_sex(args.ansur_dir / name)
        table["sexes"][sex] = {
            "n": len(x),
            "mean": np.round(x.mean(axis=0), 2).tolist(),
            "std": np.round(x.std(axis=0, ddof=1), 2).tolist(),
            "correlation": np.round(np.corrcoef(x, rowvar=False), 4).tolist(),
        }
    args.output.write_text(json.dumps(table, indent=1) + "\n")
    print(f"wrote {args.output}")


if __name__ == "__main__":
    main()
