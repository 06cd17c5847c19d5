"""A benchmark subject's fit as `fitter run` saw it, to measure bodies of its search again.

The search's answer does not depend on how it is measured, so a change of the measuring
(:func:`bodyfit.fitter.fit.person_fit.fitted_measurements`, e.g. the girths scaled to the photos)
is measured on kept fits without fitting again: the fit's record (run.json) gives its
settings and answers, the set gives the subject's photos and camera.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

from bodyfit import kernels
from bodyfit.fitter.fit.canvas import extreme_bodies
from bodyfit.fitter.fit.person import PersonInputs, person_silhouettes
from bodyfit.fitter.fit.person_fit import (FitSettings, fitted_bodies, fitted_measurements,
                                           person_views, view_photos)
from bodyfit.fitter.fit.photo_extents import ViewPhoto
from bodyfit.fitter.measure.measurements import Measurer
from bodyfit.fitter.model.body_model import POSE_NAMES, BodyModel
from bodyfit.fitter.run.config import run_config

__all__ = ["FitPhotos", "answer_pose", "recorded_twist"]


def answer_pose(record: dict) -> np.ndarray:
    """(4,) degrees: the fit's answered angles, in ``POSE_NAMES`` order, of run.json's
    payload ``record``."""
    return np.array([record["result"]["pose_deg"][name] for name in POSE_NAMES])


def recorded_twist(record: dict) -> np.ndarray | None:
    """(2,) degrees: the front photo's left and right hands' twists the fit answered with,
    of run.json's payload ``record``; None: the rest pose's (fits before them too)."""
    twist = record["result"].get("hand_twist_deg")
    return None if twist is None else np.array([twist["left"], twist["right"]])


@dataclasses.dataclass(frozen=True)
class FitPhotos:
    """A fitted subject as its fit saw it.

    Attributes:
        settings: the run's settings.
        masks: view name -> (H, W) bool, the silhouettes of the subject's photos.
        intrinsics: view name -> (3, 3) K of the photos (None: orthographic views).
        views: view name -> the view its fit started on (its parts and pose are read).
        stature_m: the person's stature, metres.
        flexion_deg: the elbows' flexion the fit answered with (None: the rest pose's).
        twist_deg: (2,) the front photo's hands' twists it answered with (None: the rest
            pose's).
    """

    settings: FitSettings
    masks: dict[str, np.ndarray]
    intrinsics: dict[str, np.ndarray] | None
    views: dict[str, kernels.ViewTarget]
    stature_m: float
    flexion_deg: float | None
    twist_deg: np.ndarray | None

    @classmethod
    def of(cls, model: BodyModel, set_folder: Path, subject: str, record: dict) -> "FitPhotos":
        """The subject ``subject`` of the set in ``set_folder`` as run.json's payload
        ``record`` fitted it: its photos are SET/SUBJECT/<the recorded photo's name>, its
        camera SET/<the recorded camera's name>, wherever the run was made; its views are
        prepared on the CPU, whatever device the fit ran on (a GPU's fits are measured
        again on a machine without one)."""
        settings = dataclasses.replace(run_config(record).settings, device="cpu")
        given = record["inputs"]
        folder = Path(set_folder)
        inputs = PersonInputs(**given | {
            view: str(folder / subject / Path(given[view]).name) for view in ("front", "side")}
            | ({"camera": str(folder / Path(given["camera"]).name)} if given["camera"] else {}))
        photos = person_silhouettes(inputs, settings.projection)
        masks, intrinsics = photos.masks, photos.intrinsics
        s = settings.search
        stature_m = inputs.height_cm / 100.0
        views = person_views(model, masks, stature_m, settings, intrinsics,
                             extreme_bodies(model, s.components, s.pose_lower_deg,
                                            s.pose_upper_deg, s.beta_limit))
        return cls(settings, masks, intrinsics, views, stature_m,
                   record["result"].get("elbow_deg"), recorded_twist(record))

    def measure(self, model: BodyModel, measurer: Measurer, betas: np.ndarray,
                pose_deg: np.ndarray
                ) -> tuple[np.ndarray, dict[str, float], dict[str, ViewPhoto] | None]:
        """(rest (V, 3) metres, key -> mm, the view photos or None) of a body of the fit's
        search (betas (K,), the first solved to the stature when the search conditions it;
        pose (4,) degrees; the elbows and hands as the fit answered), measured as `fitter run`
        measures its answer."""
        _, rest, view_bodies = fitted_bodies(model, betas, pose_deg, self.views, self.stature_m,
                                             self.settings.search.condition_stature,
                                             self.flexion_deg, self.twist_deg)
        values = fitted_measurements(model, measurer, self.settings, rest, view_bodies,
                                     self.views, self.masks, self.intrinsics)
        return rest, values, view_photos(self.settings, self.views, view_bodies, self.masks,
                                         self.intrinsics)
