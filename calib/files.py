"""Atomic output files: a reader never sees a half-written result.

Every output of the `calib` commands goes through :func:`write_atomic`: the bytes are
written to a temporary file in the destination folder and renamed over the
destination, so a crash or an error leaves either the old file or the new one.
"""

from __future__ import annotations

import os
import secrets
from pathlib import Path

from bodyfit.calib.errors import UserError

__all__ = ["check_writable_dir", "write_atomic"]


def check_writable_dir(directory: str | os.PathLike) -> Path:
    """Return ``directory`` as a Path, or raise UserError if outputs cannot go there.

    Called before any work starts, so that a long calibration does not end in a
    failed write.
    """
    path = Path(directory) if str(directory) else Path(".")
    if not path.is_dir():
        raise UserError(f"output folder {str(path)!r} does not exist; create it first")
    if not os.access(path, os.W_OK):
        raise UserError(f"output folder {str(path)!r} is not writable")
    return path


def write_atomic(path: str | os.PathLike, payload: bytes) -> None:
    """Write ``payload`` to ``path`` through a temporary file and a rename.

    Raises UserError when the folder is missing or not writable, or the write fails
    (disk full); no temporary file is left behind on failure.
    """
    target = Path(path)
    folder = check_writable_dir(target.parent)
    # open(..., "xb") rather than mkstemp: the file gets the umask's permissions, not 0600.
    temp_name = folder / f".{target.name}.{os.getpid()}.{secrets.token_hex(4)}.part"
    try:
        with open(temp_name, "xb") as stream:
            stream.write(payload)
            stream.flush()
            os.fsync(stream.fileno())
        os.replace(temp_name, target)
    except OSError as error:
        raise UserError(f"cannot write {target}: {error.strerror or error}") from None
    finally:
        temp_name.unlink(missing_ok=True)  # gone already after a successful rename
