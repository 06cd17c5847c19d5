"""A learned person segmentation: MediaPipe's BlazePose models run through LiteRT.

For photos whose backdrop does not fill the frame (a room: a wall and a floor of other
colours, furniture at the edges), :mod:`bodyfit.calib.silhouette` takes the person's
region from this mask and refines its outline with its own colour model.

The models (``data/``, shipped with the package; ``data/README.md`` names their source and
licence) are the static-image path of MediaPipe's legacy Pose solution (0.10.21,
``model_complexity=1``), re-run here through ``ai-edge-litert`` because MediaPipe's own
package pulls in a GUI build of OpenCV:

1. **Detection** (``pose_detection.tflite``): the photo letterboxed to a square (grey
   padding, the detector's zero) at 224 x 224; 2254 SSD anchors each give a box, four
   keypoints and a score. The boxes above ``DETECTION_SCORE``, grouped by OpenCV's
   non-maximum suppression, are the candidates (``CANDIDATES`` at most, best first); each
   group's boxes (box IoU over ``NMS_IOU`` with its best) are averaged into its
   keypoints, weighted by score.
2. **Region** of each candidate: a square about keypoint 0 (the hips' centre), its side
   twice the distance to keypoint 1 (a point above the head) times ``REGION_SCALE``,
   turned so that this direction points up.
3. **Landmarks and mask** (``pose_landmark_full.tflite``, the region at 256 x 256): 33
   landmarks, refined by the model's heatmaps (``HEATMAP_KERNEL``), and a person
   probability over the region, both mapped back into the photo, with the model's own
   flag of whether a person is there. The person is the best-scored candidate the flag
   passes (in a room photo the detector's best box was once an armchair's, 0.55 against
   the person's 0.51); another it passes that scores at least ``SECOND_PERSON_SCORE``,
   or ``SECOND_PERSON_SHARE`` of the person's score, is a second person.

Units: pixels of the photo as given (x right, y down). The detector's grey padding
instead of MediaPipe's black raised a side photo's score from 0.18 to 0.62; masks agree
with MediaPipe's at IoU 0.976-0.986 and landmarks within a median 2-4 px.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from importlib import resources

import cv2
import numpy as np

from bodyfit.calib.images import native_messages_logged
from bodyfit.common.errors import UserError

__all__ = ["DETECTION_SCORE", "SECOND_PERSON_SCORE", "SECOND_PERSON_SHARE", "NoPersonFound",
           "PersonFound", "PersonSegmenter", "person_segmenter"]

#: A detection's least score (after the sigmoid) to count as a person.
DETECTION_SCORE = 0.5
#: Another candidate the landmark model takes for a person is a second person when it
#: scores at least this (rooms hold faces in pictures, cushions and the like that score
#: 0.5-0.6) ...
SECOND_PERSON_SCORE = 0.8
#: ... or this share of the person's score: two of the demo's part-coloured bodies side
#: by side score 0.69 and 0.59 (0.84 of it), where the benchmark's room and plain photos'
#: and the real photos' next best boxes reach 0.67 of their best's at most (192 benchmark
#: photos and the real photos).
SECOND_PERSON_SHARE = 0.75
#: The detections (groups of boxes) the landmark model looks at, best first.
CANDIDATES = 3
#: Boxes overlapping the best one by more than this IoU are the same person.
NMS_IOU = 0.3
#: The region's side over twice the hips-to-head distance (MediaPipe's 1.25).
REGION_SCALE = 1.25
#: Side of the heatmap window that refines each landmark, heatmap cells.
HEATMAP_KERNEL = 7
_DETECTOR_SIDE, _LANDMARK_SIDE, _LANDMARKS = 224, 256, 33
_MODELS = ("pose_detection.tflite", "pose_landmark_full.tflite")
_NO_PERSON = ("no person found in the photo: photograph the whole person, standing, facing or "
              "side-on to the camera")


class NoPersonFound(UserError):
    """The models found no one in the photo."""

    def __init__(self) -> None:
        super().__init__(_NO_PERSON)


@dataclass(frozen=True)
class PersonFound:
    """What the segmentation found in a photo.

    Attributes:
        probability: (H, W) float32 in [0, 1], that each pixel shows the person (0 outside
            the detector's region).
        landmarks: (33, 5) float32: x, y (pixels), z (depth, pixels at the region's scale,
            negative towards the camera), visibility and presence (0..1), in BlazePose's
            order (0 nose, 11/12 shoulders, 23/24 hips, 27/28 ankles, 29/30 heels, 31/32
            toes; odd numbers the person's left).
        score: the detection's score (0..1).
    """

    probability: np.ndarray
    landmarks: np.ndarray
    score: float


def _ssd_anchors() -> np.ndarray:
    """(2254, 2) float32 anchor centres, 0..1 of the detector's square: strides 8 and 16
    with 2 anchors a cell, stride 32 with 6 (MediaPipe's SsdAnchorsCalculator for this
    model, fixed anchor size)."""
    centres = []
    for stride, per_cell in ((8, 2), (16, 2), (32, 6)):
        cells = int(np.ceil(_DETECTOR_SIDE / stride))
        rows, cols = np.mgrid[0:cells, 0:cells]
        centre = np.stack([(cols + 0.5) / cells, (rows + 0.5) / cells], -1).reshape(-1, 1, 2)
        centres.append(np.repeat(centre, per_cell, axis=1).reshape(-1, 2))
    return np.concatenate(centres).astype(np.float32)


def _sigmoid(x: np.ndarray) -> np.ndarray:
    return 1.0 / (1.0 + np.exp(-np.clip(x, -80, 80)))


def _box_iou(lo: np.ndarray, hi: np.ndarray, index: int) -> np.ndarray:
    """(N,) IoU of each box (corners ``lo``, ``hi``: (N, 2)) with box ``index``."""
    inter = np.prod(np.clip(np.minimum(hi, hi[index]) - np.maximum(lo, lo[index]), 0, None), 1)
    area = np.prod(hi - lo, 1)
    return inter / (area + area[index] - inter + 1e-9)


class PersonSegmenter:
    """BlazePose's detector and landmark model on LiteRT (module docstring).

    Args:
        threads: LiteRT's CPU threads.
    """

    def __init__(self, threads: int = 2) -> None:
        from ai_edge_litert.interpreter import Interpreter  # loaded only when used

        folder = resources.files("bodyfit.calib.data")
        with native_messages_logged("LiteRT"):
            self._detector, self._landmarker = (
                Interpreter(model_content=folder.joinpath(name).read_bytes(),
                            num_threads=threads) for name in _MODELS)
            for interpreter in (self._detector, self._landmarker):
                interpreter.allocate_tensors()
        self._anchors = _ssd_anchors()

    @staticmethod
    def _run(interpreter, tensor: np.ndarray) -> list[np.ndarray]:
        """The model's outputs for one (side, side, 3) float32 input, in output-name order
        (``Identity``, ``Identity_1``, ...)."""
        interpreter.set_tensor(interpreter.get_input_details()[0]["index"], tensor[None])
        interpreter.invoke()
        outputs = sorted(interpreter.get_output_details(), key=lambda d: d["name"])
        return [interpreter.get_tensor(d["index"])[0] for d in outputs]

    def _detections(self, rgb: np.ndarray) -> list[tuple[np.ndarray, float]]:
        """[((2, 2) keypoints 0 and 1 in photo pixels, score)] of up to ``CANDIDATES``
        people the detector may have found, best first: its boxes scoring at least
        ``DETECTION_SCORE``, grouped by OpenCV's non-maximum suppression, each group's
        keypoints averaged over its boxes (box IoU over ``NMS_IOU`` with its best one),
        weighted by score.

        Raises:
            NoPersonFound: no box scores ``DETECTION_SCORE``.
        """
        height, width = rgb.shape[:2]
        side = max(height, width)
        pad_x, pad_y = (side - width) // 2, (side - height) // 2
        square = cv2.copyMakeBorder(rgb, pad_y, side - height - pad_y, pad_x,
                                    side - width - pad_x, cv2.BORDER_CONSTANT,
                                    value=(128, 128, 128))
        tensor = cv2.resize(square, (_DETECTOR_SIDE,) * 2,
                            interpolation=cv2.INTER_AREA).astype(np.float32) / 127.5 - 1
        boxes, logits = self._run(self._detector, tensor)
        score = _sigmoid(logits[:, 0])
        found = np.flatnonzero(score >= DETECTION_SCORE)
        if not len(found):
            raise NoPersonFound()
        size = boxes[:, 2:4] / _DETECTOR_SIDE
        centre = boxes[:, :2] / _DETECTOR_SIDE + self._anchors
        lo, hi = centre - size / 2, centre + size / 2
        keypoints = boxes[:, 4:8].reshape(-1, 2, 2) / _DETECTOR_SIDE + self._anchors[:, None]
        groups = cv2.dnn.NMSBoxes(np.hstack([lo, hi - lo])[found].tolist(),
                                  score[found].tolist(), DETECTION_SCORE, NMS_IOU)
        people = []
        for best in found[np.asarray(groups, int).ravel()][:CANDIDATES]:
            weight = score * ((_box_iou(lo, hi, best) > NMS_IOU) & (score >= DETECTION_SCORE))
            averaged = (keypoints * weight[:, None, None]).sum(0) / weight.sum()
            people.append((averaged * side - [pad_x, pad_y], float(score[best])))
        return people

    def _person_at(self, rgb: np.ndarray, keypoints: np.ndarray, score: float
                   ) -> PersonFound | None:
        """The landmark model's person in the region of a detection's ``keypoints``
        (hips' centre, above the head), or None where it says no person is there."""
        height, width = rgb.shape[:2]
        hips, head = keypoints
        side = 2 * np.linalg.norm(head - hips) * REGION_SCALE
        angle = np.pi / 2 - np.arctan2(-(head[1] - hips[1]), head[0] - hips[0])
        turn = np.array([[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]])
        linear = turn * (side / _LANDMARK_SIDE)
        to_photo = np.hstack([linear, (hips - linear @ np.full(2, _LANDMARK_SIDE / 2))[:, None]])
        to_photo = to_photo.astype(np.float32)  # region pixel (x, y, 1) -> photo pixel
        crop = cv2.warpAffine(rgb, to_photo, (_LANDMARK_SIDE,) * 2,
                              flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP,
                              borderMode=cv2.BORDER_REPLICATE)
        raw, flag, mask_logits, heatmaps, _ = self._run(self._landmarker,
                                                        crop.astype(np.float32) / 255)
        if float(flag[0]) < DETECTION_SCORE:
            return None
        landmarks = _refined(raw.reshape(-1, 5)[:_LANDMARKS].copy(), heatmaps)
        xy = landmarks[:, :2] @ to_photo[:, :2].T + to_photo[:, 2]
        landmarks = np.column_stack([xy, landmarks[:, 2] * side / _LANDMARK_SIDE,
                                     _sigmoid(landmarks[:, 3:5])]).astype(np.float32)
        probability = cv2.warpAffine(_sigmoid(mask_logits[..., 0]).astype(np.float32),
                                     to_photo, (width, height), flags=cv2.INTER_LINEAR,
                                     borderMode=cv2.BORDER_CONSTANT, borderValue=0)
        return PersonFound(probability, landmarks, score)

    def __call__(self, image_bgr: np.ndarray) -> PersonFound:
        """The person in an (H, W, 3) uint8 BGR photo: the best-scored detection whose
        region the landmark model takes for a person.

        Raises:
            NoPersonFound: no detection the landmark model takes for a person.
            UserError: another such detection, scoring at least ``SECOND_PERSON_SCORE``
                or ``SECOND_PERSON_SHARE`` of the person's score.
        """
        rgb = cv2.cvtColor(image_bgr, cv2.COLOR_BGR2RGB)
        person, others = None, 0
        for keypoints, score in self._detections(rgb):  # best first
            if person is not None and score < min(SECOND_PERSON_SCORE,
                                                  SECOND_PERSON_SHARE * person.score):
                break  # this one and those after it score too low to be a second person
            found = self._person_at(rgb, keypoints, score)
            if found is not None:
                others += person is not None
                person = person or found
        if person is None:
            raise NoPersonFound()
        if others:
            raise UserError(f"{1 + others} people found in the photo; photograph one "
                            "person at a time")
        return person


def _refined(landmarks: np.ndarray, heatmaps: np.ndarray) -> np.ndarray:
    """(33, 5) region landmarks whose x, y are moved to the score-weighted centre of their
    heatmap (H, H, 39) within a ``HEATMAP_KERNEL`` window, where the heatmap is confident
    (MediaPipe's RefineLandmarksFromHeatmapCalculator)."""
    cells, half = heatmaps.shape[0], HEATMAP_KERNEL // 2
    for j in range(_LANDMARKS):
        col, row = (int(v / _LANDMARK_SIDE * cells) for v in landmarks[j, :2])
        if not (0 <= col < cells and 0 <= row < cells):
            continue
        r0, r1 = max(row - half, 0), min(row + half + 1, cells)
        c0, c1 = max(col - half, 0), min(col + half + 1, cells)
        confidence = _sigmoid(heatmaps[r0:r1, c0:c1, j])
        if confidence.max() >= 0.5:
            rows, cols = np.mgrid[r0:r1, c0:c1]
            landmarks[j, 0] = (cols * confidence).sum() / confidence.sum() / cells * _LANDMARK_SIDE
            landmarks[j, 1] = (rows * confidence).sum() / confidence.sum() / cells * _LANDMARK_SIDE
    return landmarks


@functools.cache
def person_segmenter() -> PersonSegmenter:
    """The process's one :class:`PersonSegmenter` (made on first use)."""
    return PersonSegmenter()
