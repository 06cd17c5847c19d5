"""Writing result files atomically: a failed run leaves no half-written output.

Single files go through :func:`bodyfit.common.files.write_atomic` (a temporary file and
a rename); a run's set of files is staged in a directory and moved in at the end.
"""

from __future__ import annotations

import contextlib
import csv
import io
import json
import re
import secrets
import shutil
from pathlib import Path

from bodyfit.common.files import created_folders, write_atomic
from bodyfit.fitter.measure.measurements import MEASUREMENTS

__all__ = ["STAGE_PATTERN", "staged_directory", "write_text", "write_json",
           "write_measurements", "write_fitted_measurements"]


#: The name of a staging directory beside OUT: ``.{OUT's name}.{8 hex digits}.partial``,
#: OUT's name its group 1 (a ``fitter batch`` rerun removes those a killed run left).
STAGE_PATTERN = re.compile(r"\.(.+)\.[0-9a-f]{8}\.partial")


@contextlib.contextmanager
def staged_directory(out_dir: Path):
    """Yield a fresh staging directory beside ``out_dir``; on success move it into place,
    on any error delete it, so ``out_dir`` never holds the files of a failed run.

    When ``out_dir`` does not exist yet (or, on POSIX, is an empty folder) the staging
    directory is renamed to it, one atomic step: a process killed at any moment leaves
    ``out_dir`` complete or absent (and at worst a staging directory, named as
    ``STAGE_PATTERN`` says). Otherwise its files are moved into ``out_dir`` one by one.
    """
    out_dir = Path(out_dir)
    with created_folders(out_dir.parent):  # the same folder rule as every single file
        # mkdir rather than mkdtemp: the folder gets the umask's permissions, not 0700,
        # as it becomes out_dir itself
        stage = out_dir.parent / f".{out_dir.name}.{secrets.token_hex(4)}.partial"
        stage.mkdir()
        try:
            yield stage
            try:  # one atomic step where out_dir is absent (or, on POSIX, an empty folder)
                stage.rename(out_dir)
            except OSError:  # out_dir holds files: they are replaced one by one
                for item in sorted(stage.iterdir()):
                    item.replace(out_dir / item.name)
        finally:
            shutil.rmtree(stage, ignore_errors=True)


def write_text(path: Path, text: str) -> None:
    write_atomic(path, text.encode())


def write_json(path: Path, payload: dict) -> None:
    write_text(path, json.dumps(payload, indent=2) + "\n")


def write_measurements(json_path: Path, bodies: dict[str, dict[str, float]],
                       provenance: dict) -> Path:
    """Write measurements as JSON and, beside it, CSV (same stem), millimetres.

    Args:
        json_path: target .json path; the CSV goes to the same path with suffix .csv.
        bodies: body name -> measurement key ("A".."P") -> value in mm.
        provenance: what produced them (command, model, inputs), stored in the JSON.

    Returns:
        The CSV path.
    """
    json_path = Path(json_path)
    payload = {
        "units": "mm",
        "definitions": {k: {"name": n, "label": label}
                        for k, (n, label) in MEASUREMENTS.items()},
        "bodies": {b: {k: round(float(v), 2) for k, v in m.items()} for b, m in bodies.items()},
        "provenance": provenance,
    }
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(["body", "key", "measurement", "value_mm"])
    for body, values in bodies.items():
        for key, value in values.items():
            writer.writerow([body, key, MEASUREMENTS[key][0], f"{value:.2f}"])
    csv_path = json_path.with_suffix(".csv")
    write_json(json_path, payload)
    write_text(csv_path, buffer.getvalue())
    return csv_path


def write_fitted_measurements(json_path: Path, values: dict[str, float],
                              spreads: dict[str, float], spread_basis: str,
                              provenance: dict) -> Path:
    """Write one fitted body's 16 measurements with their spreads, JSON and CSV (mm).

    Both are keyed by measurement name (``MEASUREMENTS``), with the paper's letter kept
    as a field: ``{"chest_circumference": {"letter": "D", "value_mm": ..., "spread_mm":
    ...}, ...}``; the JSON also names the kind of spread (``spread_basis``, one of
    :data:`bodyfit.fitter.fit.spreads.SPREAD_BASES`). Returns the CSV path.
    """
    json_path = Path(json_path)
    table = {name: {"letter": key, "label": label, "value_mm": round(float(values[key]), 2),
                    "spread_mm": round(float(spreads[key]), 2)}
             for key, (name, label) in MEASUREMENTS.items()}
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(["measurement", "letter", "value_mm", "spread_mm"])
    for name, row in table.items():
        writer.writerow([name, row["letter"], f"{row['value_mm']:.2f}", f"{row['spread_mm']:.2f}"])
    csv_path = json_path.with_suffix(".csv")
    write_json(json_path, {"units": "mm", "spread_basis": spread_basis, "measurements": table,
                           "provenance": provenance})
    write_text(csv_path, buffer.getvalue())
    return csv_path
