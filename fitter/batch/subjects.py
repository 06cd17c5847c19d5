"""The subjects table of `fitter batch`: SUBJECTS.csv, one row per subject.

A UTF-8 CSV file with a header row. Columns (any order, names as written here):

- ``id`` (required): the subject's name, also its output folder OUT/<id>/: letters,
  digits, ``.``, ``_`` and ``-``, starting with a letter or digit, at most 100 characters
  (no path: ``../x`` or ``/abs`` are refused); unique, ignoring case (a case-insensitive
  file system would give two such ids one folder); not ``summary.csv``, ``failures.csv``
  or ``batch.json``, the batch's own files;
- ``front``, ``side`` (required): the photos (front in an A-pose, side with the arms
  down), as ``fitter run --front/--side``;
- ``height_cm`` (required): stature, centimetres;
- ``camera``, ``mask_front``, ``mask_side`` (optional): as the ``fitter run`` options;
- ``background_front``, ``background_side`` (optional): the subject's background plates,
  as ``fitter run --background-front/--background-side`` (else the batch's, if any);
- ``sex`` (optional): female, male or unknown (empty or unknown: the batch's ``--sex``);
- ``weights`` (optional): a weights preset or a .toml file, as ``--weights``;
- ``mass_kg`` (optional): the body mass, kilograms, as ``fitter run --mass-kg``.

An empty optional cell means "not given" (the batch's option, if any, applies). Relative
paths are relative to the folder of SUBJECTS.csv, so a table travels with its photos;
they are made absolute here. Blank lines are ignored.

Problems of the whole table (unreadable file, a missing, unknown or repeated column)
are :class:`~bodyfit.common.errors.UserError`; problems of one row (a wrong number of
cells, an empty required cell, a height that is not a number or not a stature, a mass
that is not a number or not one in kilograms, an unknown
sex or weights preset, an unsafe or repeated id, a path that does not exist) are
:class:`BadRow`, which ``fitter batch`` reports and stops on, or skips with
``--skip-bad-rows``.
"""

from __future__ import annotations

import csv
import dataclasses
import re
from pathlib import Path

from bodyfit.common.errors import UserError
from bodyfit.fitter.fit.person import MASS_RANGE_KG, SEXES, STATURE_RANGE_CM, PersonInputs
from bodyfit.fitter.fit.weights import PRESETS

__all__ = ["REQUIRED_COLUMNS", "OPTIONAL_COLUMNS", "RESERVED_IDS", "SubjectRow", "BadRow",
           "SubjectTable", "read_subjects", "id_problem"]

REQUIRED_COLUMNS = ("id", "front", "side", "height_cm")
OPTIONAL_COLUMNS = ("camera", "mask_front", "mask_side", "background_front", "background_side",
                    "sex", "weights", "mass_kg")
_PATH_COLUMNS = ("front", "side", "camera", "mask_front", "mask_side", "background_front",
                 "background_side")
#: Names of the batch's own files in OUT, which no subject folder may take.
RESERVED_IDS = ("summary.csv", "failures.csv", "batch.json")
_ID_PATTERN = re.compile(r"[A-Za-z0-9][A-Za-z0-9._-]{0,99}")


@dataclasses.dataclass(frozen=True)
class SubjectRow:
    """One good row of the table: a subject and its inputs, paths absolute.

    Attributes:
        subject_id: the id (its output folder's name).
        inputs: the row's photos, stature, camera, masks, background plates and sex as
            `fitter run` takes them; a camera, plate or sex the row leaves empty is None or
            ``"unknown"``, and the batch's ``--camera``/``--background-*``/``--sex`` apply (:func:`~bodyfit.fitter.batch.job.subject_job`).
        weights: a preset name, a .toml path, or None.
        line: the row's line number in the file (1 is the header).
    """

    subject_id: str
    inputs: PersonInputs
    weights: str | None = None
    line: int = 0


@dataclasses.dataclass(frozen=True)
class BadRow:
    """A row that cannot be run: its line, its id as written ("" when there is none) and
    what is wrong, one line."""

    line: int
    subject_id: str
    reason: str

    def message(self, table: Path) -> str:
        return f"{table} line {self.line}: {self.reason}"


@dataclasses.dataclass(frozen=True)
class SubjectTable:
    """The table's rows in file order: ``rows`` the good ones, ``bad_rows`` the others."""

    path: Path
    rows: list[SubjectRow]
    bad_rows: list[BadRow]


def id_problem(subject_id: str) -> str | None:
    """Why ``subject_id`` cannot name an output folder, or None when it can.

    Example:
        >>> id_problem("s-01") is None
        True
        >>> id_problem("../x").startswith("id '../x' is not a safe folder name")
        True
    """
    if not _ID_PATTERN.fullmatch(subject_id):
        return (f"id {subject_id!r} is not a safe folder name: use letters, digits, '.', '_' "
                "and '-', starting with a letter or digit (at most 100)")
    if subject_id.lower() in RESERVED_IDS:
        return f"id {subject_id!r} is the name of one of the batch's own files"
    return None


def _read_lines(path: Path) -> list[tuple[int, list[str]]]:
    """(line number, cells) of every non-blank CSV record, the header first."""
    try:
        text = path.read_text(encoding="utf-8-sig")  # -sig: spreadsheets write a BOM
    except FileNotFoundError:
        raise UserError(f"{path}: no such file") from None
    except IsADirectoryError:
        raise UserError(f"{path} is a folder, not a CSV file") from None
    except UnicodeDecodeError:
        raise UserError(f"{path} is not UTF-8 text; save the table as CSV (UTF-8)") from None
    except OSError as error:
        raise UserError(f"{path}: cannot read it ({error.strerror or error})") from None
    reader = csv.reader(text.splitlines(keepends=True), strict=True)
    records = []
    try:
        for cells in reader:
            if any(cell.strip() for cell in cells):
                records.append((reader.line_num, [cell.strip() for cell in cells]))
    except csv.Error as error:
        raise UserError(f"{path} line {reader.line_num}: not valid CSV ({error})") from None
    return records


def _check_header(path: Path, header: list[str]) -> None:
    known = REQUIRED_COLUMNS + OPTIONAL_COLUMNS
    if len(header) == 1 and ";" in header[0]:
        raise UserError(f"{path}: its columns are separated by ';'; fitter batch reads "
                        "comma-separated tables")
    repeated = sorted({name for name in header if header.count(name) > 1})
    if repeated:
        raise UserError(f"{path}: column {repeated[0]!r} appears twice")
    unknown = [name for name in header if name not in known]
    if unknown:
        raise UserError(f"{path}: unknown column {unknown[0]!r}; the columns are "
                        f"{', '.join(known)}")
    missing = [name for name in REQUIRED_COLUMNS if name not in header]
    if missing:
        raise UserError(f"{path}: missing column{'s' if len(missing) > 1 else ''} "
                        f"{', '.join(missing)} (required: {', '.join(REQUIRED_COLUMNS)})")


def _quantity(cells: dict[str, str], column: str, what: str, bounds) -> float:
    """The number in ``column``, which must be ``what`` within ``bounds`` (low, high);
    raises ValueError with the row's problem."""
    try:
        value = float(cells[column])
    except ValueError:
        raise ValueError(f"{column} {cells[column]!r} is not a number") from None
    lo, hi = bounds
    if not lo <= value <= hi:
        raise ValueError(f"{column} must be {what}, {lo:.0f}-{hi:.0f}; got {value:g}")
    return value


def _row(cells: dict[str, str], line: int, folder: Path) -> SubjectRow:
    """A good row from its cells (id checked by the caller); raises ValueError with the
    row's problem."""
    for name in REQUIRED_COLUMNS[1:]:
        if not cells[name]:
            raise ValueError(f"no {name}")
    height_cm = _quantity(cells, "height_cm", "a stature in centimetres", STATURE_RANGE_CM)
    mass_kg = (_quantity(cells, "mass_kg", "a body mass in kilograms", MASS_RANGE_KG)
               if cells.get("mass_kg") else None)
    sex = cells.get("sex") or "unknown"
    if sex not in SEXES:
        raise ValueError(f"sex must be one of {', '.join(SEXES)} (or empty), got {sex!r}")
    paths = {}
    for name in _PATH_COLUMNS:
        if cells.get(name):
            path = (folder / Path(cells[name]).expanduser()).resolve()
            if not path.is_file():
                raise ValueError(f"{name} {cells[name]}: no such file")
            paths[name] = str(path)
    weights = cells.get("weights") or None
    if weights is not None and weights not in PRESETS:
        if not weights.endswith(".toml"):
            raise ValueError(f"weights must be a preset ({', '.join(PRESETS)}) or a .toml "
                             f"file, got {weights!r}")
        path = (folder / Path(weights).expanduser()).resolve()
        if not path.is_file():
            raise ValueError(f"weights {weights}: no such file")
        weights = str(path)
    return SubjectRow(cells["id"], PersonInputs(height_cm=height_cm, sex=sex, mass_kg=mass_kg,
                                                **paths),
                      weights, line)


def read_subjects(path: Path) -> SubjectTable:
    """The subjects table at ``path`` (module docstring), every row checked.

    Raises:
        UserError: the file cannot be read as a CSV table, or its columns are wrong.
    """
    path = Path(path)
    records = _read_lines(path)
    if not records:
        raise UserError(f"{path} is empty; it needs a header row ({', '.join(REQUIRED_COLUMNS)}"
                        ", ...) and a row per subject")
    (_, header), records = records[0], records[1:]
    _check_header(path, header)
    if not records:
        raise UserError(f"{path} has a header but no subject rows")
    folder = path.parent.resolve()
    rows, bad_rows, first_line = [], [], {}
    id_column = header.index("id")
    for line, values in records:
        if len(values) != len(header):
            written_id = values[id_column] if id_column < len(values) else ""
            bad_rows.append(BadRow(line, written_id,
                                   f"{len(values)} cells, the header has {len(header)}"))
            continue
        cells = dict(zip(header, values))
        subject_id = cells["id"]
        problem = id_problem(subject_id) if subject_id else "no id"
        if problem is None:
            earlier = first_line.setdefault(subject_id.lower(), line)
            if earlier != line:
                problem = f"id {subject_id!r} is used already on line {earlier} (ids are " \
                          "compared ignoring case)"
        if problem is None:
            try:
                rows.append(_row(cells, line, folder))
                continue
            except ValueError as error:
                problem = str(error)
        bad_rows.append(BadRow(line, subject_id, problem))
    return SubjectTable(path, rows, bad_rows)
