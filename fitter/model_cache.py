"""Where the built body model lives, and loading it (building it on first use).

The model is cached in ``$BODYFIT_CACHE_DIR`` if set, else ``$XDG_CACHE_HOME/bodyfit``,
else ``~/.cache/bodyfit``, as ``body_model.npz``. Anny keeps its own data cache
(``$ANNY_CACHE_DIR`` or ``~/.cache/anny``), which a first build fills.
"""

from __future__ import annotations

import logging
import os
from pathlib import Path

from bodyfit.calib.errors import UserError
from bodyfit.fitter.body_model import BodyModel

__all__ = ["CACHE_ENV_VAR", "cache_dir", "model_path", "load_model", "build_and_save"]

logger = logging.getLogger(__name__)

CACHE_ENV_VAR = "BODYFIT_CACHE_DIR"


def cache_dir() -> Path:
    """The directory holding bodyfit's cached files (not created here)."""
    if os.environ.get(CACHE_ENV_VAR):
        return Path(os.environ[CACHE_ENV_VAR]).expanduser()
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "bodyfit"


def model_path() -> Path:
    return cache_dir() / "body_model.npz"


def build_and_save(settings=None) -> BodyModel:
    """Build the model (see :mod:`bodyfit.fitter.model_build`) and write it to the cache."""
    from bodyfit.fitter.model_build import ModelBuildSettings, build_model

    model = build_model(settings or ModelBuildSettings())
    model.save(model_path())
    logger.info("wrote %s", model_path())
    return model


def load_model(build_if_needed: bool = True) -> BodyModel:
    """The cached model; a missing, corrupt or outdated cache is rebuilt with the
    default settings (a few minutes), or raises UserError if ``build_if_needed`` is False."""
    path = model_path()
    try:
        return BodyModel.load(path)
    except UserError as exc:
        if not build_if_needed:
            raise
        if path.exists():
            logger.warning("the cached body model is unusable (%s); rebuilding it", exc)
        else:
            logger.warning("no body model cached at %s yet; building it (a few minutes, "
                           "once)", path)
    return build_and_save()
