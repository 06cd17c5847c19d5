"""The studio's records: the people measured, their fits and the cameras, in SQLite.

One database file, DATA/studio.sqlite (the standard library's sqlite3), beside the fits'
folders (DATA/fits/<fit id>/) and the cameras' (DATA/cameras/<camera id>/). A person is
the id or name the studio typed, kept as text only; every path on disk is made of the
server's own numbers. Each change is one
transaction, so a restart finds every record as the last one left it.

A fit's ``state``: "queued", "fitting", "done" or "failed" (with its ``reason``, one line).
"""

from __future__ import annotations

import dataclasses
import datetime
import json
import sqlite3
import threading
from pathlib import Path

from bodyfit.common.errors import UserError

__all__ = ["FIT_STATES", "FitRecord", "Store"]

FIT_STATES = ("queued", "fitting", "done", "failed")
_SCHEMA = """
CREATE TABLE IF NOT EXISTS people (
    person TEXT PRIMARY KEY COLLATE NOCASE,
    created TEXT NOT NULL);
CREATE TABLE IF NOT EXISTS fits (
    id INTEGER PRIMARY KEY AUTOINCREMENT,
    person TEXT NOT NULL REFERENCES people(person),
    created TEXT NOT NULL,
    state TEXT NOT NULL,
    reason TEXT NOT NULL DEFAULT '',
    height_cm REAL NOT NULL,
    sex TEXT NOT NULL,
    mass_kg REAL,
    camera INTEGER REFERENCES cameras(id),
    seconds REAL,
    measurements TEXT);
CREATE TABLE IF NOT EXISTS cameras (
    id INTEGER PRIMARY KEY AUTOINCREMENT,
    name TEXT NOT NULL UNIQUE COLLATE NOCASE,
    created TEXT NOT NULL,
    rms_px REAL NOT NULL,
    views TEXT NOT NULL);
"""


def _now() -> str:
    return datetime.datetime.now().isoformat(sep=" ", timespec="seconds")


@dataclasses.dataclass(frozen=True)
class FitRecord:
    """One fit of a person.

    Attributes:
        fit_id: the fit's number (its folder's name).
        person: who was measured, as typed.
        created: when it was asked for, local time, "YYYY-MM-DD HH:MM:SS".
        state: one of :data:`FIT_STATES`; reason: why it failed, one line.
        height_cm, sex, mass_kg: the inputs given (mass None: not given).
        camera: the registered camera's id, or None (the photos' EXIF focal length).
        seconds: the fit's wall seconds, once done.
        measurements: measurements.json's ``measurements`` (name -> {"value_mm", ...}),
            once done; else None.
    """

    fit_id: int
    person: str
    created: str
    state: str
    reason: str
    height_cm: float
    sex: str
    mass_kg: float | None
    camera: int | None
    seconds: float | None
    measurements: dict | None


class Store:
    """The studio's database at ``path`` (created with its tables when missing); usable
    from any thread, one statement at a time. UserError where ``path`` is not one."""

    def __init__(self, path: Path):
        self._lock = threading.Lock()
        try:
            self._db = sqlite3.connect(str(path), check_same_thread=False,
                                       isolation_level=None)
            self._db.row_factory = sqlite3.Row
            self._db.executescript(_SCHEMA)
        except sqlite3.DatabaseError as error:
            raise UserError(f"{path}: not a studio database that can be opened ({error}); "
                            "give another --data folder") from None

    def _run(self, sql: str, args: tuple = ()) -> list[sqlite3.Row]:
        with self._lock:
            self._db.execute("BEGIN IMMEDIATE")
            try:
                rows = self._db.execute(sql, args).fetchall()
            except BaseException:
                self._db.execute("ROLLBACK")
                raise
            self._db.execute("COMMIT")
            return rows

    def add_fit(self, person: str, height_cm: float, sex: str, mass_kg: float | None,
                camera: int | None) -> int:
        """A queued fit of ``person`` (added to the people when new); its number."""
        self._run("INSERT OR IGNORE INTO people (person, created) VALUES (?, ?)",
                  (person, _now()))
        rows = self._run("INSERT INTO fits (person, created, state, height_cm, sex, mass_kg, "
                         "camera) VALUES ((SELECT person FROM people WHERE person = ?), ?, "
                         "'queued', ?, ?, ?, ?) RETURNING id",
                         (person, _now(), height_cm, sex, mass_kg, camera))
        return int(rows[0]["id"])

    def set_state(self, fit_id: int, state: str, reason: str = "",
                  seconds: float | None = None, measurements: dict | None = None) -> None:
        if state not in FIT_STATES:
            raise ValueError(f"unknown fit state {state!r}")
        self._run("UPDATE fits SET state = ?, reason = ?, seconds = ?, measurements = ? "
                  "WHERE id = ?", (state, reason, seconds,
                                   None if measurements is None else json.dumps(measurements),
                                   fit_id))

    @staticmethod
    def _record(row: sqlite3.Row) -> FitRecord:
        values = dict(row)
        values["fit_id"] = values.pop("id")
        values["measurements"] = (json.loads(values["measurements"])
                                  if values["measurements"] else None)
        return FitRecord(**values)

    def fit(self, fit_id: int) -> FitRecord | None:
        rows = self._run("SELECT * FROM fits WHERE id = ?", (fit_id,))
        return self._record(rows[0]) if rows else None

    def fits(self, person: str | None = None, states: tuple[str, ...] = FIT_STATES
             ) -> list[FitRecord]:
        """Fits, oldest first: every one, or ``person``'s; of ``states`` only."""
        marks = ", ".join("?" * len(states))
        where = f"state IN ({marks})" + ("" if person is None else
                                          " AND person = ? COLLATE NOCASE")
        args = (*states, *(() if person is None else (person,)))
        return [self._record(row) for row in
                self._run(f"SELECT * FROM fits WHERE {where} ORDER BY id", args)]

    def people(self, query: str = "") -> list[tuple[str, int, str | None]]:
        """(person, fits, latest fit's time) of everyone whose id or name holds ``query``
        (any case), most recently measured first."""
        pattern = "%" + query.replace("\\", "\\\\").replace("%", "\\%").replace("_", "\\_") + "%"
        rows = self._run(
            "SELECT p.person, COUNT(f.id) AS n, MAX(f.created) AS latest FROM people p "
            "LEFT JOIN fits f ON f.person = p.person WHERE p.person LIKE ? ESCAPE '\\' "
            "GROUP BY p.person ORDER BY MAX(f.id) DESC, p.person", (pattern,))
        return [(row["person"], row["n"], row["latest"]) for row in rows]

    def add_camera(self, name: str, rms_px: float, views: str) -> int:
        """Register a camera (``views``: its calibration's views used and rejected, in
        words); its id. A name already registered raises sqlite3.IntegrityError."""
        rows = self._run("INSERT INTO cameras (name, created, rms_px, views) VALUES "
                         "(?, ?, ?, ?) RETURNING id", (name, _now(), rms_px, views))
        return int(rows[0]["id"])

    def cameras(self) -> list[sqlite3.Row]:
        """The registered cameras (id, name, created, rms_px, views), by name."""
        return self._run("SELECT * FROM cameras ORDER BY name")

    def camera(self, camera_id: int) -> sqlite3.Row | None:
        rows = self._run("SELECT * FROM cameras WHERE id = ?", (camera_id,))
        return rows[0] if rows else None
