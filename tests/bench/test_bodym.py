"""The real-people benchmark's parts (bench.bodym) on a made-up split in BodyM's layout:
its order, its statistics against hand computations, its baselines, and its commands end
to end (two people fitted through fitter batch)."""

import csv

import cv2
import numpy as np
import pytest

from bench.bodym import cli
from bench.bodym.dataset import BODYM_LETTERS, SHARED_KEYS, Subject, ordered, part, read_split
from bench.bodym.scores import (PhotoFits, bmi_band_errors, height_weight_predictions,
                                measurement_stats, offsets, precision_sd)
from bodyfit.fitter.batch.tables import csv_text

_COLUMNS = ["split", "subject_id", "photo_id", "gender", "height_cm", "weight_kg",
            *sorted(set(BODYM_LETTERS.values()) | {"height"}), "front_mask", "side_mask",
            "n_photos", "all_photo_ids"]


def _subject(i: int, sex: str = "female", height: float = 165.0, weight: float = 60.0,
             photos: tuple[str, ...] = ()) -> Subject:
    truth = {k: 100.0 * (j + 1) + i for j, k in enumerate(SHARED_KEYS)}
    return Subject(f"s{i}", sex, height, weight, height + 1.0, truth,
                   photos or (f"p{i}a", f"p{i}b"))


def _write_split(folder, subjects: list[Subject], masks: dict[str, tuple] | None = None):
    """BodyM's joined_subjects.csv for ``subjects`` (truths in cm) and, if given, each
    photo's (front, side) masks."""
    rows = []
    for s in subjects:
        cm = {c: s.truth_mm[k] / 10.0 for k, c in BODYM_LETTERS.items()}
        cm["height"] = s.scan_height_cm
        rows.append(["train", s.subject_id, s.photo_ids[0], s.sex, s.stated_height_cm,
                     s.weight_kg, *[cm[c] for c in sorted(cm)], "", "", len(s.photo_ids),
                     ";".join(s.photo_ids)])
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "joined_subjects.csv").write_text(csv_text(_COLUMNS, rows))
    for view in ("mask", "mask_left"):
        (folder / view).mkdir(exist_ok=True)
    for photo_id, (front, side) in (masks or {}).items():
        cv2.imwrite(str(folder / "mask" / f"{photo_id}.png"), front)
        cv2.imwrite(str(folder / "mask_left" / f"{photo_id}.png"), side)


def test_the_split_is_read_in_centimetres_and_in_a_fixed_order(tmp_path):
    subjects = [_subject(i, photos=(f"p{i}",)) for i in range(5)]
    _write_split(tmp_path, subjects)
    read = read_split(tmp_path)
    # the order is the salted hash's, not the file's: reversing the file changes nothing
    _write_split(tmp_path / "reversed", subjects[::-1])
    assert [s.subject_id for s in read_split(tmp_path / "reversed")] == \
        [s.subject_id for s in read]
    assert [s.subject_id for s in read] != [s.subject_id for s in subjects]
    by_id = {s.subject_id: s for s in read}
    assert by_id["s3"].truth_mm == pytest.approx(subjects[3].truth_mm)
    assert by_id["s3"].scan_height_cm == 166.0
    assert part(read, "choice") == read[:1000] and part(read, "held-out") == []
    assert ordered(list(reversed(read))) == read


def test_statistics_against_hand_computed_values():
    errors = np.array([[10.0, -60.0], [-30.0, 120.0], [20.0, 0.0]])
    spreads = np.array([[15.0, 50.0], [20.0, 200.0], [25.0, 1.0]])
    st = measurement_stats(errors, spreads, np.array([0.0, 20.0]))
    np.testing.assert_allclose(st.mae, [20.0, 60.0])
    np.testing.assert_allclose(st.median, [20.0, 60.0])
    np.testing.assert_allclose(st.offset, [0.0, 20.0])
    np.testing.assert_allclose(st.over_50, [0.0, 2 / 3])
    np.testing.assert_allclose(st.over_100, [0.0, 1 / 3])
    np.testing.assert_allclose(st.covered, [2 / 3, 2 / 3])
    np.testing.assert_allclose(st.mae_after, [20.0, (80 + 100 + 20) / 3])
    np.testing.assert_allclose(st.covered_after, [2 / 3, 1 / 3])
    # the interval of the offset: Student's t on 2 degrees of freedom
    np.testing.assert_allclose(st.offset_ci[0], 4.302653 * 26.457513 / np.sqrt(3), rtol=1e-5)
    with pytest.raises(ValueError):
        measurement_stats(errors[:1], spreads[:1], np.zeros(2))


def _fits(subjects, photo_ids, estimates):
    estimates = np.asarray(estimates, float)
    return PhotoFits(subjects, photo_ids, estimates, np.full_like(estimates, 10.0),
                     np.zeros(len(subjects)), [])


def test_offsets_precision_and_bands_of_repeat_photos():
    a, b = _subject(0, weight=40.0), _subject(1, weight=120.0)  # BMI 14.7 and 44.1
    truth_a, truth_b = a.truths(), b.truths()
    fits = _fits([a, a, a, b, b], ["p0a", "p0b", "p0c", "p1a", "p1b"],
                 [truth_a + 4, truth_a + 8, truth_a, truth_b - 10, truth_b - 20])
    a = Subject(**{**a.__dict__, "photo_ids": ("p0a", "p0b", "p0c")})
    fits.subjects[:3] = [a] * 3
    # offsets from first photos only: +4 and -10
    np.testing.assert_allclose(offsets(fits), np.full(13, -3.0))
    sd, count = precision_sd(fits)
    assert count == 2  # RMS of the SDs 4 and sqrt(50)
    np.testing.assert_allclose(sd, np.full(13, np.sqrt((16 + 50) / 2)))
    bands = bmi_band_errors(fits.first_photos())
    assert [(label, n) for label, n, _, _ in bands] == [("under 18.5", 1), ("35 and over", 1)]
    np.testing.assert_allclose(bands[1][2], [-10.0] * 3)
    np.testing.assert_allclose(bands[1][3], [10.0] * 3)


def test_height_weight_regression_recovers_a_linear_truth():
    rng = np.random.default_rng(0)
    train = []
    for i in range(30):
        h, w, male = rng.uniform(150, 190), rng.uniform(45, 110), i % 2
        truth = {k: 3.0 * h + (j + 1) * w + 25.0 * male + j for j, k in enumerate(SHARED_KEYS)}
        train.append(Subject(f"s{i}", "male" if male else "female", h, w, h, truth, ("p",)))
    new = [Subject("n", "male", 170.0, 80.0, 170.0, {}, ("q",))]
    expected = [3.0 * 170 + (j + 1) * 80 + 25 + j for j in range(13)]
    np.testing.assert_allclose(height_weight_predictions(train, new)[0], expected, atol=1e-8)


def _person_masks(model):
    """(front, side) uint8 masks of the model's mean body drawn orthographically in
    BodyM's 720 x 960 crop, the person touching its bottom edge as BodyM's do."""
    from bodyfit.fitter.fit.side_arms import side_photo_pose
    from bodyfit.fitter.model.body_model import forward
    from bodyfit.kernels.raster import rasterize
    from bodyfit.kernels.view_camera import FRONT_VIEW_DEG, SIDE_VIEW_DEG, orthographic_camera

    betas = np.zeros((1, 20), np.float32)
    masks = []
    for view_deg, pose in ((FRONT_VIEW_DEG, np.full(4, 10.0)),
                           (SIDE_VIEW_DEG, side_photo_pose(model, betas[0], np.zeros(4)))):
        body = forward(model, betas, np.asarray(pose, np.float32)[None])[0]
        scale = 900.0 / np.ptp(body[:, 2])
        camera = orthographic_camera(view_deg, scale, (360.0, 30.0 + body[:, 2].max() * scale))
        labels = rasterize(body[None], model.faces, model.face_parts, camera, 960, 720)
        mask = (labels.numpy()[0] >= 0).astype(np.uint8) * 255
        rows = np.flatnonzero(mask.any(axis=1))
        masks.append(np.roll(mask, 959 - rows[-1], axis=0))
    return tuple(masks)


def test_fit_and_report_two_people_end_to_end(tmp_path, monkeypatch, body_model, capsys):
    split = tmp_path / "train"
    people = [_subject(0, "female", 163.0, 58.0, ("p0a",)),
              _subject(1, "male", 171.0, 70.0, ("p1a", "p1b"))]
    mask = _person_masks(body_model)
    _write_split(split, people, {p: mask for s in people for p in s.photo_ids})
    monkeypatch.chdir(tmp_path)
    cli.main(["fit", "two", "--split", str(split), "--first", "2", "--photos", "all"])
    table = list(csv.DictReader(open(cli.RUNS / "two" / "subjects.csv")))
    assert [row["id"] for row in table] == [p for s in read_split(split) for p in s.photo_ids]
    padded = cv2.imread(table[0]["mask_front"], cv2.IMREAD_GRAYSCALE)
    assert padded.shape == (960 + 2 * cli.PAD_PX, 720 + 2 * cli.PAD_PX)
    fits = cli.read_fits("two", read_split(split))
    assert sorted(fits.photo_ids) == ["p0a", "p1a", "p1b"] and not fits.failures
    # the same body and stature in both of p1's photos: the same measurements
    same = [i for i, p in enumerate(fits.photo_ids) if p.startswith("p1")]
    np.testing.assert_allclose(fits.estimates[same[0]], fits.estimates[same[1]], atol=1e-6)
    cli.main(["report", "two", "--split", str(split), "--first", "2"])
    text = capsys.readouterr().out
    assert "2 fitted, 0 refused" in text
    first = fits.first_photos()
    chest = measurement_stats(first.errors, first.spreads, offsets(first))
    i = SHARED_KEYS.index("D")
    assert f"| D chest circumference | {chest.mae[i]:.1f} | " in text
    assert "Repeat photos (1 subjects with two or more fitted pairs, 3 pairs)" in text

    # a refusal's reason is printed with its numbers (the person's own) left out
    (cli.RUNS / "two" / "failures.csv").write_text(
        'id,reason\np0a,"--mass-kg 28.7 is 0.5 times what the body in the photos weighs '
        '(about 58 kg): give this person\'s mass in kilograms, or leave it out"\n')
    cli.main(["report", "two", "--split", str(split), "--first", "2"])
    text = capsys.readouterr().out
    assert ("- refused: --mass-kg # is # times what the body in the photos weighs (about "
            "# kg)") in text and "28.7" not in text
