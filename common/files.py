"""Atomic output files (a reader never sees a half-written result), and input fingerprints.

Every output of the `calib` and `fitter` commands goes through :func:`write_atomic`: the
bytes are written to a temporary file in the destination folder and renamed over the
destination, so a crash or an error leaves either the old file or the new one.

Output folders follow one rule for every command: a folder that does not exist yet is
created (with its missing parents) when the first file is written into it, and a write
that fails removes the folders it created, so a failed command leaves nothing behind.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import re
import secrets
from pathlib import Path

from bodyfit.common.errors import UserError

__all__ = ["TEMP_FILE_PATTERN", "read_json_file", "check_input_file", "check_writable_dir",
           "created_folders", "file_sha256", "write_atomic"]


def _missing_folders(path: Path) -> list[Path]:
    """``path`` and its parents that do not exist, deepest first."""
    missing = []
    while not path.exists() and path != path.parent:
        missing.append(path)
        path = path.parent
    return missing


def check_writable_dir(directory: str | os.PathLike) -> Path:
    """Return ``directory`` as a Path, or raise UserError if outputs cannot go there.

    The folder may not exist yet: then its nearest existing parent must be a writable
    folder (the folder is created by the first :func:`write_atomic` into it). Called
    before any work starts, so that a long calibration does not end in a failed write.
    """
    path = Path(directory) if str(directory) else Path(".")
    missing = _missing_folders(path)
    existing = missing[-1].parent if missing else path
    if not existing.is_dir():
        raise UserError(f"output folder {str(path)!r} cannot be created: {str(existing)!r} is a file")
    if not os.access(existing, os.W_OK):
        raise UserError(f"output folder {str(path)!r} is not writable")
    return path


@contextlib.contextmanager
def created_folders(folder: str | os.PathLike):
    """Create ``folder`` and its missing parents for the block; if the block (or a
    ``mkdir``) fails, remove again the folders this made, so a failed command leaves no
    empty folder behind. Raises OSError as ``mkdir`` does."""
    made: list[Path] = []
    try:
        for missing in reversed(_missing_folders(Path(folder))):
            missing.mkdir()
            made.append(missing)
        yield
    except BaseException:
        for missing in reversed(made):
            with contextlib.suppress(OSError):  # something else wrote into it meanwhile
                missing.rmdir()
        raise


#: The name of :func:`write_atomic`'s temporary file for a target named N:
#: ``.N.{pid}.{8 hex digits}.part``, N its group 1 (a process killed mid-write leaves it).
TEMP_FILE_PATTERN = re.compile(r"\.(.+)\.[0-9]+\.[0-9a-f]{8}\.part")


def write_atomic(path: str | os.PathLike, payload: bytes) -> None:
    """Write ``payload`` to ``path`` through a temporary file and a rename.

    Creates the destination folder if needed. Raises UserError when the folder cannot be
    created or written, or the write fails (disk full); nothing is left behind on failure:
    no temporary file, and no folder this call created.
    """
    target = Path(path)
    folder = check_writable_dir(target.parent)
    # open(..., "xb") rather than mkstemp: the file gets the umask's permissions, not 0600.
    temp_name = folder / f".{target.name}.{os.getpid()}.{secrets.token_hex(4)}.part"
    temp_made = False
    try:
        with created_folders(folder):
            with open(temp_name, "xb") as stream:
                temp_made = True
                stream.write(payload)
                stream.flush()
                os.fsync(stream.fileno())
            os.replace(temp_name, target)
            temp_made = False
    except OSError as error:
        raise UserError(f"cannot write {target}: {error.strerror or error}") from None
    finally:
        if temp_made:  # only when open() succeeded: a name too long cannot even be unlinked
            temp_name.unlink(missing_ok=True)


def file_sha256(path: str | os.PathLike) -> str:
    """Hex SHA-256 of a file's bytes: recognises an input however its path is spelled.

    Raises UserError when the file cannot be read.
    """
    digest = hashlib.sha256()
    try:
        with open(path, "rb") as stream:
            for block in iter(lambda: stream.read(1 << 20), b""):
                digest.update(block)
    except OSError as error:
        raise UserError(f"{path}: cannot read it ({error.strerror or error})") from None
    return digest.hexdigest()


def check_input_file(path: str | os.PathLike, label: str | None = None) -> None:
    """Check that a user's input ``path`` is a file.

    Raises:
        UserError: ``"{label}: no such file"``, or ``"{label}: is a folder, ..."`` naming
            the files instead (``label`` defaults to the path).
    """
    path, label = Path(path), label or str(path)
    if path.is_dir():
        raise UserError(f"{label}: is a folder, not a file; name the files in it "
                        f"(e.g. {path}/*.jpg)")
    if not path.is_file():
        raise UserError(f"{label}: no such file")


def read_json_file(path: str | os.PathLike, label: str, advice: str = ""):
    """The parsed JSON of a user's file.

    Raises:
        UserError: ``"{label}: no such file"``, ``"... cannot read it (...)"`` or ``"... not
            valid JSON (...){advice}"``.
    """
    try:
        text = Path(path).read_text(encoding="utf-8")
    except FileNotFoundError:
        raise UserError(f"{label}: no such file") from None
    except (OSError, UnicodeDecodeError) as error:
        raise UserError(f"{label}: cannot read it ({error})") from None
    try:
        return json.loads(text)
    except json.JSONDecodeError as error:
        raise UserError(f"{label}: not valid JSON ({error.msg} at line {error.lineno}){advice}"
                        ) from None
