"""The `calib` command: what it writes, what it prints, and one-line errors for bad input."""

import hashlib
import json

import cv2
import numpy as np
import pytest

from bodyfit.calib.boards import BoardDetector, parse_board
from bodyfit.calib.camera import load_camera
from bodyfit.calib.undistort import undistort_image

from calib_scenes import clutter, iou, studio_photo
from calib_true_camera import IMAGE_SIZE, TRUE_DIST, TRUE_K

CHESSBOARD = ("--board", "chessboard:9x6", "--square-mm", "25")


@pytest.fixture(scope="module")
def calibrated(tmp_path_factory, chessboard_shots):
    """camera.json from `calib capture` on the first 9 views plus the blurred one, written
    into a folder that does not exist yet (with the default coverage picture beside it)."""
    from bodyfit.calib.cli import main

    folder = tmp_path_factory.mktemp("capture") / "new" / "calibration"
    output = folder / "camera.json"
    inputs = [str(p) for p in chessboard_shots.sharp[:9]] + [str(chessboard_shots.blurred)]
    assert main(["capture", *inputs, *CHESSBOARD, "-o", str(output)]) == 0
    return output, inputs


def test_capture_writes_camera_json_with_its_provenance(calibrated):
    output, inputs = calibrated
    record = json.loads(output.read_text())
    assert record["format"] == "bodyfit.camera/1"
    assert record["image_size_px"] == list(IMAGE_SIZE)
    np.testing.assert_allclose(record["K"], TRUE_K, rtol=0.005, atol=1.5)
    assert len(record["dist"]) == 5 and record["dist"][2:] == [0.0, 0.0, 0.0]
    assert set(record["std"]) == {"fx", "fy", "cx", "cy", "k1", "k2"}
    for index, name in enumerate(("k1", "k2")):
        assert abs(record["dist"][index] - TRUE_DIST[index]) <= 3 * record["std"][name]
    assert record["model"] == "k1k2" and 0 < record["rms_px"] < 0.15
    assert record["board"]["kind"] == "chessboard" and record["board"]["square_mm"] == 25.0
    statuses = [view["status"] for view in record["views"]]
    assert statuses == ["used"] * 9 + ["too blurry"]
    assert all(view["error_px"] < 0.2 for view in record["views"][:9])
    assert 0 < record["coverage_fraction"] <= 1
    provenance = record["provenance"]
    assert provenance["argv"][:2] == ["calib", "capture"] and provenance["inputs"] == inputs
    assert provenance["input_sha256"] == [hashlib.sha256(open(p, "rb").read()).hexdigest() for p in inputs]
    assert provenance["bodyfit_version"] and provenance["time"].endswith("+00:00")
    assert load_camera(output).board == parse_board("chessboard:9x6", 25)
    coverage = cv2.imread(str(output.with_name("camera_coverage.png")))
    # The frame (1280x720 scaled to 1200x675), then the legend: 3 lines and 3 lines of 4 views.
    assert coverage.shape[1] == 1200 and coverage.shape[0] == 675 + (3 + 3) * 24 + 10


def test_capture_prints_the_summary(chessboard_shots, tmp_path, run_calib):
    result = run_calib(
        "capture",
        *chessboard_shots.sharp[:5],
        chessboard_shots.bent,
        *CHESSBOARD,
        "-o",
        tmp_path / "cameras" / "cam.json",  # neither folder exists yet: both are created
        "--coverage",
        tmp_path / "pictures" / "cover.png",
    )
    assert result.code == 0, result.stderr
    out = result.stdout
    assert "views: 5 used, 1 rejected (1 outlier)" in out
    assert "RMS reprojection error" in out and "worst view" in out
    for name in ("fx", "fy", "cx", "cy", "k1", "k2"):
        assert f"  {name} = " in out
    assert "±" in out and f"wrote {tmp_path / 'cameras' / 'cam.json'}" in out
    assert (tmp_path / "pictures" / "cover.png").is_file()


def test_check_reports_the_error_on_held_out_photos(calibrated, chessboard_shots, run_calib):
    output, _ = calibrated
    held_out = chessboard_shots.sharp[9:]
    result = run_calib("check", output, *held_out)
    assert result.code == 0, result.stderr
    lines = result.stdout.splitlines()
    held_out_line = next(line for line in lines if line.startswith("held-out RMS"))
    rms = float(held_out_line.split()[4])
    assert 0 < rms < 0.2
    assert f"over {len(held_out)} of {len(held_out)} views" in held_out_line
    assert "calibrated on" not in result.stdout


def test_check_reports_calibration_photos_apart_from_held_out_ones(calibrated, chessboard_shots, tmp_path, run_calib):
    output, _ = calibrated
    renamed = tmp_path / "renamed.png"  # a calibration photo under another name: same bytes
    renamed.write_bytes(chessboard_shots.sharp[0].read_bytes())
    result = run_calib("check", output, renamed, chessboard_shots.sharp[1], chessboard_shots.sharp[10])
    assert result.code == 0, result.stderr
    lines = result.stdout.splitlines()
    assert f"  {renamed}: error" in result.stdout and lines[0].endswith(", calibrated on it")
    assert lines[1].endswith(", calibrated on it") and not lines[2].endswith("calibrated on it")
    assert any(line.startswith("held-out RMS reprojection error") and "over 1 of 1 views" in line for line in lines)
    seen = next(line for line in lines if line.startswith("RMS reprojection error on 2 photos"))
    assert "the camera was calibrated on (not held out): " in seen and "over 2 of 2 views" in seen

    result = run_calib("check", output, chessboard_shots.sharp[2])
    assert result.code == 0, result.stderr
    assert "held-out" not in result.stdout
    assert "RMS reprojection error on 1 photo the camera was calibrated on (not held out)" in result.stdout


def test_check_recognises_calibration_photos_by_path_in_files_without_hashes(
    calibrated, chessboard_shots, tmp_path, run_calib, monkeypatch
):
    output, _ = calibrated
    record = json.loads(output.read_text())
    del record["provenance"]["input_sha256"]  # as camera files written before hashes were
    old = tmp_path / "old.json"
    old.write_text(json.dumps(record))
    monkeypatch.chdir(chessboard_shots.sharp[0].parent)
    result = run_calib("check", old, chessboard_shots.sharp[0].name, chessboard_shots.sharp[10].name)
    assert result.code == 0, result.stderr
    assert "held-out RMS reprojection error" in result.stdout
    assert "RMS reprojection error on 1 photo the camera was calibrated on (not held out)" in result.stdout


def test_undistort_writes_the_kornia_result(calibrated, chessboard_shots, tmp_path, run_calib):
    output, _ = calibrated
    photo = chessboard_shots.sharp[4]
    folder = tmp_path / "undistorted" / "today"  # does not exist yet: created
    result = run_calib("undistort", output, photo, "-o", folder)
    assert result.code == 0, result.stderr
    written = cv2.imread(str(folder / photo.name))
    expected = undistort_image(cv2.imread(str(photo)), load_camera(output))
    np.testing.assert_array_equal(written, expected)


def test_silhouette_writes_the_mask(tmp_path, run_calib):
    photo, truth = studio_photo((720, 960), [(360.0, 60.0, 820.0)], np.random.default_rng(4))
    cv2.imwrite(str(tmp_path / "front.png"), photo)
    mask_path = tmp_path / "masks" / "front_mask.png"  # the folder does not exist yet: created
    result = run_calib("silhouette", tmp_path / "front.png", "-o", mask_path)
    assert result.code == 0, result.stderr
    mask = cv2.imread(str(mask_path), cv2.IMREAD_GRAYSCALE)
    assert set(np.unique(mask)) == {0, 255}
    assert iou(mask > 0, truth) >= 0.99


def test_board_draws_a_board_the_detector_finds(tmp_path, run_calib):
    result = run_calib(
        "board",
        "--board",
        "charuco:7x5",
        "--square-mm",
        "30",
        "--marker-mm",
        "22",
        "--dict",
        "DICT_4X4_50",
        "--dpi",
        "150",
        "-o",
        tmp_path / "prints" / "board.png",  # the folder does not exist yet: created
    )
    assert result.code == 0, result.stderr
    assert "mm squares" in result.stdout
    picture = cv2.imread(str(tmp_path / "prints" / "board.png"), cv2.IMREAD_GRAYSCALE)
    assert picture.shape == ((5 + 2) * 177, (7 + 2) * 177)  # 30 mm at 150 dpi: 177 px per square
    detection = BoardDetector(parse_board("charuco:7x5", 30, 22, "DICT_4X4_50")).detect(picture)
    assert detection is not None and len(detection.corner_ids) == 24


# --- bad input: one line, exit code 2, nothing written ------------------------------------


def _write(path, image):
    cv2.imwrite(str(path), image)
    return path


@pytest.fixture
def bad_inputs(tmp_path, chessboard_shots):
    rng = np.random.default_rng(9)
    blank = np.full((IMAGE_SIZE[1], IMAGE_SIZE[0]), 128, np.uint8)
    inputs = {
        "blank1": _write(tmp_path / "blank1.png", blank),
        "blank2": _write(tmp_path / "blank2.png", blank),
        "small": _write(tmp_path / "small.png", blank[:480, :640]),
        "junk": tmp_path / "junk.jpg",
        "corrupt_camera": tmp_path / "corrupt.json",
        "incomplete_camera": tmp_path / "incomplete.json",
        "clutter": _write(
            tmp_path / "room.png",
            studio_photo((720, 960), [(360.0, 60.0, 820.0)], rng, backdrop=clutter((720, 960), rng))[0],
        ),
        "nobody": _write(tmp_path / "nobody.png", studio_photo((720, 960), [], rng)[0]),
        "cut": _write(tmp_path / "cut.png", studio_photo((720, 960), [(360.0, 200.0, 820.0)], rng)[0]),
        "two": _write(
            tmp_path / "two.png", studio_photo((720, 960), [(165.0, 100.0, 500.0), (555.0, 120.0, 500.0)], rng)[0]
        ),
        "view": chessboard_shots.sharp[0],
        "view2": chessboard_shots.sharp[1],
        "folder": tmp_path,
    }
    inputs["junk"].write_bytes(b"\xff\xd8 this is not a JPEG")
    inputs["corrupt_camera"].write_text('{"image_size_px": [1280, 720], "K": [[1050, 0, 648')
    inputs["incomplete_camera"].write_text(json.dumps({"image_size_px": [1280, 720], "dist": [0, 0, 0, 0, 0]}))
    return inputs


OUT = "OUTPUT"  # replaced by the output path of each case

BAD_INPUT_CASES = {
    "no board in any view": (["capture", "blank1", "blank2", *CHESSBOARD, "-o", OUT], "no board found in any"),
    "too few usable views": (["capture", "view", "view2", *CHESSBOARD, "-o", OUT], "only 2 usable views"),
    "photos of different sizes": (["capture", "view", "small", *CHESSBOARD, "-o", OUT], "must all have one size"),
    "unreadable file": (["capture", "view", "junk", *CHESSBOARD, "-o", OUT], "not a readable image"),
    "missing file": (["capture", "view", "nowhere.png", *CHESSBOARD, "-o", OUT], "no such file"),
    "a folder for a photo": (["capture", "view", "folder", *CHESSBOARD, "-o", OUT], "is a folder, not a file"),
    "missing square size": (["capture", "view", "--board", "chessboard:9x6", "-o", OUT], "--square-mm"),
    "bad board": (["capture", "view", "--board", "chess:9", "--square-mm", "25", "-o", OUT], "KIND:COLSxROWS"),
    "corrupt camera.json (undistort)": (["undistort", "corrupt_camera", "view", "-o", "DIR"], "not valid JSON"),
    "incomplete camera.json (check)": (["check", "incomplete_camera", "view"], "missing K"),
    "corrupt camera.json (silhouette)": (
        ["silhouette", "nobody", "--camera", "corrupt_camera", "-o", OUT],
        "not valid JSON",
    ),
    "backdrop not plain": (["silhouette", "clutter", "--segmenter", "backdrop", "-o", OUT],
                           "backdrop is not plain"),
    "no person": (["silhouette", "nobody", "-o", OUT], "no person found"),
    "person touching the frame edge": (["silhouette", "cut", "--segmenter", "backdrop", "-o", OUT],
                                       "touches the bottom edge"),
    "several people": (["silhouette", "two", "--segmenter", "backdrop", "-o", OUT],
                       "2 person-sized regions"),
    "output folder is a file": (["silhouette", "nobody", "-o", "view/mask.png"], "is a file"),
    "usage error": (["capture", "--board", "chessboard:9x6"], "required"),
}


@pytest.mark.parametrize("case", list(BAD_INPUT_CASES))
def test_bad_input_is_one_line_exit_2_and_nothing_written(case, bad_inputs, tmp_path, run_calib):
    """Outputs go into a folder that does not exist yet: a failed command must not leave it behind."""
    arguments, complaint = BAD_INPUT_CASES[case]
    out_dir = tmp_path / "out"
    out_dir.mkdir()
    new_dir = out_dir / "new" / "deeper"
    argv = []
    for argument in arguments:
        if argument == OUT:
            argv.append(new_dir / "result.json")
        elif argument == "DIR":
            argv.append(new_dir)
        elif argument == "view/mask.png":
            argv.append(bad_inputs["view"] / "mask.png")
        else:
            argv.append(bad_inputs.get(argument, argument))
    result = run_calib(*argv)
    assert result.code == 2
    assert result.stderr.startswith("calib: error: ") and result.stderr.count("\n") == 1, result.stderr
    assert complaint in result.stderr
    assert "Traceback" not in result.stderr
    assert list(out_dir.iterdir()) == []


def test_help_states_the_units(run_calib):
    result = run_calib("capture", "--help")
    assert result.code == 0
    assert "millimetres" in result.stdout and "pixels" in result.stdout
