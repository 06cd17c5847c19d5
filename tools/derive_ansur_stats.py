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

#: bodyfit measurement key (paper Fig. 10) -> ANSUR II columns summed, all millimetres.
#: C (shoulder-crotch length) has no ANSUR II column.
COLUMNS = {
    "A": ["headcircumference"],
    "B": ["neckcircumference"],
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
}
FILES = {"male": "ANSUR_II_MALE_Public.csv", "female": "ANSUR_II_FEMALE_Public.csv"}


def read_sex(path: Path) -> np.ndarray:
    """(n, len(COLUMNS)) float64 millimetres, one row per subject."""
    with open(path, newline="", encoding="latin-1") as fh:
        rows = list(csv.DictReader(fh))
    return np.array([[sum(float(r[c]) for c in cols) for cols in COLUMNS.values()]
                     for r in rows])


def main() -> None:
    here = Path(__file__).resolve().parent.parent
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--ansur-dir", type=Path, default=here.parent / "shared/data/ansur2")
    parser.add_argument("-o", "--output", type=Path,
                        default=here / "fitter/data/ansur2_stats.json")
    args = parser.parse_args()
    table = {"source": "ANSUR II public data (2012), derived by tools/derive_ansur_stats.py",
             "units": "mm", "keys": list(COLUMNS),
             "columns": {k: "+".join(v) for k, v in COLUMNS.items()}, "sexes": {}}
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
