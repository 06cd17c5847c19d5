"""The photography check: is each photo one the fit can measure?

Before a fit, each photo is judged from two readings: its silhouette
(:mod:`bodyfit.fitter.check.shape`) and the 33 body landmarks of the learned pose model
(:mod:`bodyfit.calib.segment`; its detector also counts the people). Each problem is one
line that says what to do; a problem stops the fit, a warning does not.

The rules, and where their thresholds come from (the standing set: the accuracy
benchmark's people as they stand, seed 0, its first 48 front and side photos; the real
photos: tests/data/real-photos):

- **big enough**: the person at least :data:`MIN_HEIGHT_PX` pixels tall (the fit draws
  people 600 px tall; at 400 the benchmark lost 1.5 mm, docs/history.md);
- **whole, with a margin**: at least :data:`MIN_MARGIN` of the height free above the
  head, below the feet and beside the person (the standing set: 0.08 at least);
- **upright**: the silhouette taller than wide, and the landmarks' body axis (the
  ankles' middle to the shoulders') within :data:`MAX_LEAN_DEG` of vertical;
- **a level camera at a sensible height**: the photo's middle row, where a level
  camera's horizon lies, crosses the person within :data:`HORIZON_RANGE` of their height
  up from the soles (the standing set: 0.38-1.05; a camera tilted or placed far above or
  below that shows the body from above or below);
- **front, facing the camera**: turned when the shoulders are less than
  :data:`FACING_SHARE` of the torso's length apart *and* an arm clears the torso by less
  than :data:`MIN_ARM_GAP` (a turned body hides the near arm's gap). The real photos:
  0.65-0.72; the standing set: 0.37 at least, but the in-space set's part-coloured bodies
  read 0.04 where the pose model misplaced the shoulders of a body facing the camera;
- **front, arms apart**: an arm is down when its angle between the shoulder-to-wrist and
  shoulder-to-hip lines is under :data:`MIN_ARM_DEG` *and* its silhouette clears the
  torso by less than :data:`MIN_ARM_GAP` of the height. Both: the pose model misplaces
  the arms of the benchmark's part-coloured bodies, and a silhouette alone cannot tell a
  broad person's hanging arms from a narrow one's A-pose. The real photos' arms hanging
  down: 21-26 degrees and 0.07-0.09; their A-pose: 43-59 degrees and 0.18-0.27; the
  standing set's (25-50 degrees out): either at least 32 degrees or 0.19;
- **front, feet apart**: together when the silhouette's legs are less than
  :data:`MIN_FEET_GAP` of the height apart at the ankles *and* the ankles' landmarks less
  than :data:`MIN_ANKLES_APART` (the gap and an ankle's width) across, where the pose
  model found the person: a room's dark floor can take a shoe from the silhouette (the
  standing set: 0.14 at least; the real photos: 0.21-0.27; the room set's first 24: one
  front photo whose silhouette lost a shoe, 0.02);
- **side, turned 90 degrees**: the shoulders at most :data:`SIDE_SHARE` of the torso's
  length apart (the standing set: 0.19 at most); either side of the person will do;
- **side, arms hanging down**: each arm's shoulder-to-wrist line within
  :data:`MAX_SIDE_ARM_DEG` of vertical (the standing set: 13 at most);
- **no hand raised** (a mirror selfie's phone, a wave): no wrist above the shoulders;
- **warning, loose clothing**: with the feet apart, the legs part lower than
  :data:`MIN_LEG_SPLIT` of the height (bare or fitted legs: 0.45-0.53 on the standing
  set; a real photo's knee-long tunic: 0.24).

Where the pose model finds no one in a photo whose silhouette was found (it misses a
third of the benchmark's part-coloured side photos), that photo's landmark rules are
skipped and its verdict says so.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bodyfit.calib.segment import NoPersonFound, person_segmenter
from bodyfit.common.errors import UserError
from bodyfit.fitter.check.shape import SilhouetteShape, silhouette_shape

__all__ = ["FACING_SHARE", "HORIZON_RANGE", "MAX_LEAN_DEG", "MAX_SIDE_ARM_DEG", "MIN_ANKLES_APART",
           "MIN_ARM_DEG", "MIN_ARM_GAP", "MIN_FEET_GAP", "MIN_HEIGHT_PX", "MIN_LEG_SPLIT",
           "MIN_MARGIN", "SIDE_SHARE", "PhotoCheckFailed", "ViewVerdict", "check_view",
           "failed_lines"]

MIN_HEIGHT_PX = 400
MIN_MARGIN = 0.01
MAX_LEAN_DEG = 45.0
HORIZON_RANGE = (0.15, 1.15)
FACING_SHARE = 0.3
MIN_ARM_DEG = 30.0
MIN_ARM_GAP = 0.12
MIN_FEET_GAP = 0.05
MIN_ANKLES_APART = 0.08
SIDE_SHARE = 0.3
MAX_SIDE_ARM_DEG = 35.0
MIN_LEG_SPLIT = 0.35

# BlazePose's landmarks: (left, right) pairs, the person's own sides
_SHOULDERS, _WRISTS, _HIPS, _ANKLES = (11, 12), (15, 16), (23, 24), (27, 28)
_EDGES = ("the head", "the feet", "the left side", "the right side")


def _not_upright(view: str) -> str:
    return (f"the {view} photo: the person is not upright (lying down, or the photo turned on "
            "its side); photograph the person standing, the phone held upright")


class PhotoCheckFailed(UserError):
    """The photos failed the check: one line per problem."""


@dataclass(frozen=True)
class ViewVerdict:
    """The check of one photo.

    Attributes:
        view: "front" or "side".
        shape: its silhouette's measures.
        readings: what the rules judged besides ``shape``: ``horizon`` (where the photo's
            middle row crosses the person, a share of the height up from the soles) and,
            where the pose model found the person, ``lean_deg`` (the body axis from
            vertical), ``ankles`` (their span across, a share of the height),
            ``shoulders`` (their span over the torso's length), ``arm_deg``
            (front: the arm nearer the body, degrees out from the torso's side; side: the
            arm nearer the camera, degrees from vertical) and ``hand_raised`` (1.0 when a
            wrist is above the shoulders; a side photo's nearer one).
        landmarks: (33, 5) the pose model's landmarks
            (:attr:`bodyfit.calib.segment.PersonFound.landmarks`), or None where it found
            no one (the silhouette's rules only).
        problems: one line each, saying what to do; any of them stops a fit.
        warnings: one line each; the fit goes on.
    """

    view: str
    shape: SilhouetteShape
    readings: dict[str, float]
    landmarks: np.ndarray | None
    problems: tuple[str, ...]
    warnings: tuple[str, ...]

    def summary(self) -> str:
        """One line of what was read, for people."""
        shape, read = self.shape, self.readings
        parts = [f"{shape.height_px} px tall",
                 f"the photo's middle {read['horizon']:.0%} up the body"]
        if self.view == "front":
            parts += [f"feet {shape.feet_gap:.0%} of the height apart",
                      f"legs parting {shape.leg_split:.0%} up",
                      f"arms clear of the torso by {min(shape.arm_gaps):.0%}"]
        if self.landmarks is not None:
            arms = "out from the torso" if self.view == "front" else "from vertical"
            parts += [f"shoulders {read['shoulders']:.2f} of the torso apart",
                      f"arm {read['arm_deg']:.0f} degrees {arms}"]
        else:
            parts.append("no landmarks (the pose model found no one: the silhouette's "
                         "rules only)")
        return f"the {self.view} photo: " + ", ".join(parts)


def _angle_deg(a: np.ndarray, b: np.ndarray) -> float:
    """Angle between two 2-D vectors, degrees."""
    cosine = a @ b / max(np.linalg.norm(a) * np.linalg.norm(b), 1e-9)
    return float(np.degrees(np.arccos(np.clip(cosine, -1.0, 1.0))))


def _landmark_readings(view: str, landmarks: np.ndarray, height_px: int) -> dict[str, float]:
    """:attr:`ViewVerdict.readings` of the landmarks ((33, 5): x, y pixels, z depth;
    ``height_px``: the silhouette's height). A side photo's arm rules read the arm nearer
    the camera only (its shoulder's z the smaller): the model guesses the hidden arm, and
    laid one along a table's edge at shoulder height with a visibility of 0.8."""
    xy = landmarks[:, :2].astype(np.float64)
    shoulders, hips = xy[list(_SHOULDERS)].mean(0), xy[list(_HIPS)].mean(0)
    arms = list(zip(_SHOULDERS, _WRISTS, _HIPS))
    if view == "front":
        arm_deg = min(_angle_deg(xy[wrist] - xy[shoulder], xy[hip] - xy[shoulder])
                      for shoulder, wrist, hip in arms)
    else:
        arms = [arms[int(np.argmin(landmarks[list(_SHOULDERS), 2]))]]
        arm_deg = max(_angle_deg(xy[wrist] - xy[shoulder], np.array([0.0, 1.0]))
                      for shoulder, wrist, _ in arms)
    wrists = [wrist for _, wrist, _ in arms]
    return {"lean_deg": _angle_deg(shoulders - xy[list(_ANKLES)].mean(0), np.array([0.0, -1.0])),
            "ankles": abs(xy[_ANKLES[0], 0] - xy[_ANKLES[1], 0]) / height_px,
            "shoulders": abs(xy[_SHOULDERS[0], 0] - xy[_SHOULDERS[1], 0])
                         / max(np.linalg.norm(hips - shoulders), 1.0),
            "arm_deg": arm_deg,
            "hand_raised": float((xy[wrists, 1] < shoulders[1]).any())}


def _framing(view: str, shape: SilhouetteShape, horizon: float) -> list[str]:
    """The problems the silhouette tells, besides the front's feet."""
    problems = []
    if shape.height_px < MIN_HEIGHT_PX:
        problems.append(f"the {view} photo: the person is only {shape.height_px} pixels tall; "
                        f"come closer or use the camera's full resolution (at least "
                        f"{MIN_HEIGHT_PX} pixels)")
    close = [edge for edge, margin in zip(_EDGES, shape.margins) if margin < MIN_MARGIN]
    if close:
        problems.append(f"the {view} photo: {' and '.join(close)} reach the frame's edge; step "
                        "back or zoom out, so that there is space all round the person")
    if not HORIZON_RANGE[0] <= horizon <= HORIZON_RANGE[1]:
        where = "high or tilted down" if horizon > HORIZON_RANGE[1] else "low or tilted up"
        problems.append(f"the {view} photo: the camera is too {where} (the photo's middle "
                        f"passes {horizon:.0%} of the way up the body); hold it level at "
                        "about waist height")
    return problems


def _posture(view: str, read: dict[str, float], shape: SilhouetteShape) -> list[str]:
    """The problems the landmarks tell (``read``: their readings)."""
    problems = []
    if read["hand_raised"]:
        problems.append(f"the {view} photo: a hand is raised above the shoulders (a mirror "
                        "selfie's phone?); have someone else take the photo, or stand the "
                        "phone and use its timer")
    if view == "front":
        if read["shoulders"] < FACING_SHARE and min(shape.arm_gaps) < MIN_ARM_GAP:
            problems.append(f"the front photo: the person is turned from the camera (the "
                            f"shoulders {read['shoulders']:.2f} of the torso's length apart); "
                            "face the camera squarely")
        if read["arm_deg"] < MIN_ARM_DEG and min(shape.arm_gaps) < MIN_ARM_GAP:
            problems.append(f"the front photo: an arm is close to the body "
                            f"({read['arm_deg']:.0f} degrees out); raise both arms about 30 "
                            "degrees from the body, hands clear of the hips (an A-pose)")
    else:
        if read["shoulders"] > SIDE_SHARE:
            problems.append(f"the side photo: the person is not side-on (the shoulders "
                            f"{read['shoulders']:.2f} of the torso's length apart); turn 90 "
                            "degrees from the camera, so that it sees the person's left or "
                            "right side")
        if read["arm_deg"] > MAX_SIDE_ARM_DEG:
            problems.append(f"the side photo: an arm is not hanging down "
                            f"({read['arm_deg']:.0f} degrees from vertical); let both arms "
                            "hang straight at the sides")
    return problems


def check_view(view: str, image: np.ndarray, mask: np.ndarray) -> ViewVerdict:
    """The check of one photo (module docstring).

    Args:
        view: "front" or "side".
        image: (H, W, 3) uint8 BGR, the photo upright (and undistorted, as the mask is).
        mask: (H, W) bool, its silhouette.

    Raises:
        UserError: the pose model found more than one person.
    """
    shape = silhouette_shape(mask)
    soles = mask.shape[0] - shape.margins[1] * shape.height_px  # the soles' row + 1
    readings = {"horizon": (soles - mask.shape[0] / 2) / shape.height_px}
    try:
        landmarks = person_segmenter()(image).landmarks
    except NoPersonFound:
        landmarks = None  # the silhouette's rules only
    if landmarks is not None:
        readings |= _landmark_readings(view, landmarks, shape.height_px)
    if shape.width_px > shape.height_px or readings.get("lean_deg", 0.0) > MAX_LEAN_DEG:
        return ViewVerdict(view, shape, readings, landmarks, (_not_upright(view),), ())
    problems = _framing(view, shape, readings["horizon"])
    if landmarks is not None:
        problems += _posture(view, readings, shape)
    warnings = []
    if view == "front":
        if shape.feet_gap < MIN_FEET_GAP and readings.get("ankles", 0.0) < MIN_ANKLES_APART:
            problems.append("the front photo: the feet are together; stand with them apart, "
                            "about a hand's width between the ankles")
        elif shape.feet_gap >= MIN_FEET_GAP and shape.leg_split < MIN_LEG_SPLIT:
            warnings.append(f"the front photo: the legs part only {shape.leg_split:.0%} of the "
                            "height above the soles (bare or fitted legs: about 45 %); a long "
                            "top, a skirt or a dress hides the hips and thighs, so wear fitted "
                            "clothes")
    return ViewVerdict(view, shape, readings, landmarks, tuple(problems), tuple(warnings))


def failed_lines(verdicts: list[ViewVerdict]) -> list[str]:
    """Every problem of the verdicts, one line each, front first."""
    return [line for verdict in verdicts for line in verdict.problems]
