"""Where the body model comes from: the user's own build, else the one shipped with bodyfit.

bodyfit ships its default body model inside the package (``bodyfit/fitter/data/
body_model.npz``, compressed, built by ``fitter model build --output
fitter/data/body_model.npz`` with the default settings; its metadata records those
settings and the Anny version). ``fitter model build`` writes a user-built model to the
cache, ``$BODYFIT_CACHE_DIR`` if set, else ``$XDG_CACHE_HOME/bodyfit``, else
``~/.cache/bodyfit``, as ``body_model.npz``; when that file exists it is used instead of
the shipped one. A corrupt or outdated cached model is an error (never silently rebuilt
or bypassed): the message says to rebuild it or to delete it. Anny keeps its own data
cache (``$ANNY_CACHE_DIR`` or ``~/.cache/anny``, about 1.1 GB), which only a build fills.
"""

from __future__ import annotations

import os
from importlib import resources
from pathlib import Path

from bodyfit.common.errors import UserError
from bodyfit.fitter.model.body_model import BodyModel

__all__ = ["CACHE_ENV_VAR", "SHIPPED_MODEL", "cache_dir", "model_path", "active_model_path",
           "load_model"]

CACHE_ENV_VAR = "BODYFIT_CACHE_DIR"
#: The default model's file name inside the package ``bodyfit.fitter.data``.
SHIPPED_MODEL = "body_model.npz"


def cache_dir() -> Path:
    """The directory holding bodyfit's cached files (not created here)."""
    if os.environ.get(CACHE_ENV_VAR):
        return Path(os.environ[CACHE_ENV_VAR]).expanduser()
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "bodyfit"


def model_path() -> Path:
    """Where ``fitter model build`` writes a user-built model (it may not exist)."""
    return cache_dir() / "body_model.npz"


def shipped_model_path() -> Path:
    return Path(str(resources.files("bodyfit.fitter.data").joinpath(SHIPPED_MODEL)))


def active_model_path() -> Path:
    """The model file :func:`load_model` reads: the user-built one if any, else the shipped."""
    return model_path() if model_path().exists() else shipped_model_path()


def load_model() -> BodyModel:
    """The user-built model in the cache if there is one, else the model shipped with
    bodyfit. Raises UserError if the chosen file is unusable."""
    path = active_model_path()
    if path == model_path():
        try:
            return BodyModel.load(path)
        except UserError as exc:
            raise UserError(f"{exc} (or delete {path} to use the model shipped with "
                            "bodyfit)") from None
    if not path.exists():
        raise UserError(f"this bodyfit install lacks its body model ({path}); reinstall "
                        "bodyfit or run `fitter model build`")
    return BodyModel.load(path)
