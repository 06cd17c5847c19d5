"""A learned start for the local solver: the shape components and the four angles read
straight off the two silhouettes, the stature and the sex.

The silhouettes are read as width profiles (:func:`silhouette_profile`): each view's
person, from the top of the head to the soles, cut into :data:`BANDS` bands of equal
height; per band, the mean width of the person's pixels and the mean reach of the
leftmost and rightmost pixels from the person's centre column, each divided by the
person's height in pixels, so that neither the camera's distance nor its focal length
matters. Multiplied by the stature they are metres (:func:`start_inputs`).

A ridge regression maps them to the components 1..K-1 and the front photo's four angles
(the first component follows from the stature, :mod:`bodyfit.fitter.fit.stature`). Its
weights ship in the package (``bodyfit/fitter/data/learned_start.npz``), made by
``fitter model train-start -o bodyfit/fitter/data/learned_start.npz``
(:mod:`bodyfit.fitter.training.start_training`) for the shipped body model; a start a
user trains (for a model they built) goes to the cache and is read instead. Weights of
another body model than the one in use are refused.
"""

from __future__ import annotations

import dataclasses
import functools
import hashlib
import io
import json
from importlib import resources
from pathlib import Path

import numpy as np

from bodyfit.common.errors import UserError
from bodyfit.common.files import write_atomic
from bodyfit.fitter.model.body_model import BodyModel
from bodyfit.fitter.model.cache import cache_dir

__all__ = ["BANDS", "SEX_CODES", "SHIPPED_START", "LearnedStart", "silhouette_profile",
           "start_inputs", "model_fingerprint", "shipped_start_path", "trained_start_path",
           "active_start_path", "active_start"]

#: Horizontal bands each silhouette is read in.
BANDS = 48
#: The sex as the regression reads it (unknown: between the two).
SEX_CODES = {"female": 1.0, "male": -1.0, "unknown": 0.0}
#: The shipped weights' file name inside the package ``bodyfit.fitter.data``.
SHIPPED_START = "learned_start.npz"
_FORMAT_VERSION = 1


def silhouette_profile(mask: np.ndarray) -> np.ndarray:
    """(3 * BANDS,) float64: a silhouette's width profile, in units of the person's height
    in pixels: per band (top to bottom) the mean pixel count of its rows, then the mean
    reach of the leftmost pixel, then of the rightmost, from the person's centre column
    (the mean column of the person's pixels). ``mask``: (H, W) bool, the person.

    Raises:
        ValueError: the mask is empty.
    """
    rows = np.flatnonzero(mask.any(axis=1))
    if not len(rows):
        raise ValueError("the silhouette is empty")
    top, bottom = rows[0], rows[-1] + 1
    height = float(bottom - top)
    person = mask[top:bottom]
    covered = person.any(axis=1)
    width = person.sum(axis=1).astype(np.float64)
    columns = np.arange(mask.shape[1], dtype=np.float64)
    centre = float((person * columns).sum() / width.sum())
    left = np.where(covered, centre - np.argmax(person, axis=1), 0.0)
    right = np.where(covered, mask.shape[1] - 1 - np.argmax(person[:, ::-1], axis=1) - centre,
                     0.0)
    band = np.minimum((np.arange(len(person)) * BANDS) // len(person), BANDS - 1)
    rows_in = np.maximum(np.bincount(band, weights=covered, minlength=BANDS), 1.0)
    return np.concatenate([np.bincount(band, weights=values, minlength=BANDS) / rows_in
                           for values in (width, left, right)]) / height


def start_inputs(masks: dict[str, np.ndarray], stature_m: float, sex: str) -> np.ndarray:
    """(6 * BANDS + 2,) float64: the regression's inputs: the front and the side
    silhouette's profiles (:func:`silhouette_profile`) times the stature (metres), the
    stature (metres) and the sex's code (:data:`SEX_CODES`)."""
    profiles = [silhouette_profile(masks[name]) for name in ("front", "side")]
    return np.r_[np.concatenate(profiles) * stature_m, stature_m, SEX_CODES[sex]]


def model_fingerprint(model: BodyModel, components: int) -> str:
    """A short hash of the body model's mean body and first ``components`` shape
    directions: the learned start's weights hold only for the model they were made for."""
    digest = hashlib.sha256(np.ascontiguousarray(model.mean_vertices, np.float32).tobytes())
    digest.update(np.ascontiguousarray(model.eigenvalues[:components], np.float32).tobytes())
    return digest.hexdigest()[:16]


@dataclasses.dataclass(frozen=True)
class LearnedStart:
    """A ridge regression from :func:`start_inputs` to a start for the local solver.

    Attributes:
        input_mean, input_scale: (F,) the inputs are standardised by these.
        weights: (F + 1, K - 1 + 4): standardised inputs and a 1 -> the components
            1..K-1 (sigma) and the four angles (degrees, ``POSE_NAMES`` order).
        components: K.
        fingerprint: :func:`model_fingerprint` of the model it was trained for.
        metadata: how it was made (the training command's settings, its held-out errors).
    """

    input_mean: np.ndarray
    input_scale: np.ndarray
    weights: np.ndarray
    components: int
    fingerprint: str
    metadata: dict

    def predict(self, inputs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(components 1..K-1 (N, K-1) sigma, angles (N, 4) degrees) of inputs (N, F)."""
        z = (np.atleast_2d(inputs) - self.input_mean) / self.input_scale
        out = np.c_[z, np.ones(len(z))] @ self.weights
        return out[:, :self.components - 1], out[:, self.components - 1:]

    def start(self, masks: dict[str, np.ndarray], stature_m: float,
              sex: str) -> tuple[np.ndarray, np.ndarray]:
        """(components 1..K-1 (K-1,), angles (4,) degrees) of one person
        (:func:`start_inputs`)."""
        betas, pose = self.predict(start_inputs(masks, stature_m, sex))
        return betas[0], pose[0]

    def check_model(self, model: BodyModel, path: Path | str) -> None:
        """Raise UserError unless these weights were trained for ``model``."""
        if (self.components > model.num_components
                or model_fingerprint(model, self.components) != self.fingerprint):
            raise UserError(f"the learned start {path} was trained for another body model; "
                            "run `fitter model train-start` for this one")

    def save(self, path: Path) -> None:
        """Write a compressed .npz atomically."""
        buffer = io.BytesIO()
        meta = dict(self.metadata, format_version=_FORMAT_VERSION, components=self.components,
                    fingerprint=self.fingerprint)
        np.savez_compressed(buffer, input_mean=self.input_mean, input_scale=self.input_scale,
                            weights=self.weights, metadata_json=np.array(json.dumps(meta)))
        write_atomic(Path(path), buffer.getvalue())

    @classmethod
    def load(cls, path: Path | str) -> "LearnedStart":
        """Read weights written by :meth:`save`.

        Raises:
            UserError: the file is missing, corrupt, or of another format (one line).
        """
        again = "run `fitter model train-start` to make it again"
        try:
            with np.load(path, allow_pickle=False) as npz:
                arrays = {name: npz[name] for name in
                          ("input_mean", "input_scale", "weights", "metadata_json")}
            meta = json.loads(str(arrays.pop("metadata_json")))
            if meta.get("format_version") != _FORMAT_VERSION:
                raise UserError(f"the learned start {path} has format "
                                f"{meta.get('format_version')}, this bodyfit reads "
                                f"{_FORMAT_VERSION}; {again}")
            start = cls(**arrays, components=int(meta["components"]),
                        fingerprint=str(meta["fingerprint"]), metadata=meta)
        except FileNotFoundError:
            raise UserError(f"no learned start at {path}; {again}") from None
        except UserError:
            raise
        except Exception:  # zip, key, JSON and value errors: all mean "corrupt"
            raise UserError(f"the learned start {path} is corrupt; {again}") from None
        features = start.input_mean.shape
        if (start.input_scale.shape != features or features != (6 * BANDS + 2,)
                or start.weights.shape != (features[0] + 1, start.components + 3)):
            raise UserError(f"the learned start {path} is corrupt (its arrays disagree); "
                            f"{again}")
        return start


def shipped_start_path() -> Path:
    """The learned start bodyfit ships (for the shipped body model)."""
    return Path(str(resources.files("bodyfit.fitter.data").joinpath(SHIPPED_START)))


def trained_start_path() -> Path:
    """Where ``fitter model train-start`` writes a user-trained start (it may not exist)."""
    return cache_dir() / SHIPPED_START


def active_start_path() -> Path:
    """The weights :func:`active_start` reads: the user-trained ones if any, else the
    shipped (as :func:`bodyfit.fitter.model.cache.active_model_path` chooses the model)."""
    return trained_start_path() if trained_start_path().exists() else shipped_start_path()


def active_start(model: BodyModel) -> LearnedStart:
    """The learned start of :func:`active_start_path`, checked against ``model``.

    Raises:
        UserError: the weights are missing, corrupt, or of another body model (one line).
    """
    path = active_start_path()
    start = _loaded(path)
    start.check_model(model, path)
    return start


@functools.lru_cache(maxsize=4)
def _loaded(path: Path) -> LearnedStart:
    return LearnedStart.load(path)
