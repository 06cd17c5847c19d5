"""The learned segmentation (calib/segment.py) and `calib silhouette` on real photos taken
in an ordinary room (tests/data/real-photos/: a wall, a tiled floor meeting it)."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest

from bodyfit.calib.segment import person_segmenter
from bodyfit.calib.silhouette import extract_silhouette
from bodyfit.common.errors import UserError

PHOTOS = Path(__file__).parents[1] / "data" / "real-photos"
# BlazePose's landmark numbers: the nose, and the ankles, heels and toes
NOSE, FEET = 0, slice(27, 33)
# today's masks of the A-pose photos (regression pins): top row, bottom row, area in pixels
PINNED = {"ramzan2": (345, 1345, 237454), "saif2": (262, 1342, 216329)}


def photo(name: str) -> np.ndarray:
    return cv2.imread(str(PHOTOS / f"{name}.jpeg"))


@pytest.mark.parametrize("name", list(PINNED))
def test_a_pose_photos_give_one_full_body_mask_without_the_floor(name, run_calib, tmp_path):
    """`calib silhouette` (auto: the floor reaches the frame's edges, so no plain backdrop
    surrounds the person) gives one region from above the nose to the feet, with none of
    the floor: its lowest rows are a pair of shoes wide, not the frame."""
    result = run_calib("silhouette", PHOTOS / f"{name}.jpeg", "-o", tmp_path / "mask.png")
    assert result.code == 0, result.stderr
    mask = cv2.imread(str(tmp_path / "mask.png"), cv2.IMREAD_GRAYSCALE) > 127
    count, _ = cv2.connectedComponents(mask.astype(np.uint8), connectivity=8)
    assert count == 2  # the background and one region
    rows, cols = np.nonzero(mask)
    landmarks = person_segmenter()(photo(name)).landmarks
    assert rows.min() < landmarks[NOSE, 1] - 60  # the head above the nose
    feet = landmarks[FEET, 1].max()
    assert feet < rows.max() < feet + 40  # the soles below the feet's landmarks, no floor
    lowest = mask[rows.max() - (rows.max() - rows.min()) // 20:rows.max() + 1].any(axis=0)
    assert lowest.sum() < 0.25 * mask.shape[1]
    top, bottom, area = PINNED[name]
    assert abs(rows.min() - top) <= 3 and abs(rows.max() - bottom) <= 3
    assert mask.sum() == pytest.approx(area, rel=0.01)


def test_the_backdrop_alone_takes_the_floor_for_the_person():
    """Why rooms need the learned segmentation: the backdrop's colour model takes the floor
    (another colour than the wall) for the person, who then reaches the frame's sides."""
    with pytest.raises(UserError, match="touches the left and right edge"):
        extract_silhouette(photo("saif2"), segmenter="backdrop")


def test_the_learned_outline_is_refined_within_a_few_pixels():
    """The refinement moves the learned mask's outline by a few pixels, not more: the two
    masks differ on a thin band (under 3 px of the outline's length on average)."""
    image = photo("ramzan2")
    learned = person_segmenter()(image).probability >= 0.5
    refined = extract_silhouette(image, segmenter="learned")
    outline = cv2.findContours(refined.astype(np.uint8), cv2.RETR_EXTERNAL,
                               cv2.CHAIN_APPROX_NONE)[0]
    length = sum(len(contour) for contour in outline)
    assert 0 < np.sum(learned ^ refined) / length < 3.0


def test_an_empty_room_has_no_person(run_calib, tmp_path):
    result = run_calib("silhouette", PHOTOS / "background.jpeg", "-o", tmp_path / "out" / "m.png")
    assert result.code == 2 and result.stderr.count("\n") == 1
    assert "no person found" in result.stderr
    assert not (tmp_path / "out").exists()


def test_two_people_side_by_side_are_refused():
    both = np.hstack([photo("ramzan2"), photo("saif2")])
    with pytest.raises(UserError, match="2 people found"):
        extract_silhouette(both, segmenter="learned")


def test_landmarks_lie_on_the_person():
    """The 33 landmarks of a person standing in an A-pose lie inside or near the refined
    mask, the nose above the hips above the ankles, and the person's left (odd numbers)
    on the photo's right."""
    image = photo("saif2")
    found = person_segmenter()(image)
    mask = extract_silhouette(image)
    near = cv2.dilate(mask.astype(np.uint8), np.ones((31, 31), np.uint8)).astype(bool)
    x, y = np.round(found.landmarks[:, :2]).astype(int).T
    assert near[y, x].all()
    assert y[NOSE] < y[23] < y[27] and y[NOSE] < y[24] < y[28]
    assert x[11] > x[12] and x[15] > x[16]  # shoulders, wrists
    assert 0.9 < found.score <= 1.0


def test_the_same_photo_gives_the_same_mask_whatever_ran_before():
    """GrabCut's k-means draws from OpenCV's global generator: disturbed between two
    extractions, the masks are still the same."""
    image = photo("saif2")
    first = extract_silhouette(image, segmenter="learned")
    cv2.randu(np.zeros((100, 100), np.uint8), 0, 255)
    assert np.array_equal(extract_silhouette(image, segmenter="learned"), first)
