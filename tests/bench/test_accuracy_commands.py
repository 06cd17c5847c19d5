"""The accuracy benchmark's supported commands (``python -m bench.accuracy``), each over
the shared small run (conftest.py): make, fit, keep, report, spread, figures."""

from __future__ import annotations

import json
import re
import subprocess
import sys
from pathlib import Path

import cv2
import pytest
from accuracy_runs import bench

from bench.accuracy.runs import KEPT_COLUMNS, TRUTH_COLUMNS, read_source, read_truths
from bodyfit.fitter.batch.tables import SUMMARY_COLUMNS, SUMMARY_FILE, read_table
from bodyfit.fitter.fit.spreads import read_calibration


ROOT = Path(__file__).resolve().parents[2]
#: The small run's 7 important measurements' mean error with bodyfit's default, mm (the
#: report's figure, to its 0.01 mm; 1.50 with the shape prior's fixed part alone, before
#: it grew with the misfit; 1.45 without the measurements' prior; before it, 1.40
#: with the hands at rest, 1.52 with the cameras placed anew through all 40 iterations,
#: 1.42 with 10 iterations, 1.34 with the solver started from the mean body).
PINNED_MEAN_OF_7 = 1.55


def mean_of_7(report: str, label: str) -> float:
    """The 7 important measurements' mean |error| of ``label``'s Table 4 row."""
    row = next(line for line in report.splitlines() if line.startswith(f"| {label} |"))
    return float(re.search(r"\*\*([\d.]+)\*\*", row.split("|")[-2]).group(1))


def tables(report: str) -> str:
    """A report without its first paragraphs (the heading and where the subjects ran)."""
    return report.split("\n\n", 2)[2]


def test_make_draws_photographs_and_tables_the_set(small_run):
    folder = small_run.set_folder
    rows = (folder / "subjects.csv").read_text().splitlines()
    assert rows[0].startswith("id,front,side,height_cm")
    assert [row.split(",")[0] for row in rows[1:]] == [
        "s0000-female", "s0001-male", "s0002-female", "s0003-male"]
    for row in rows[1:]:
        subject = folder / row.split(",")[0]
        truth = json.loads((subject / "truth.json").read_text())
        # the table's stature is the truth's, in centimetres
        assert float(row.split(",")[3]) == pytest.approx(truth["measurements"]["O"] / 10, abs=0.05)
        for view in ("front", "side"):
            assert cv2.imread(str(subject / f"{view}.jpg")) is not None
    assert len(list((folder / "board").glob("*.png"))) >= 10


def test_fit_calibrates_the_camera_and_fits_every_subject(small_run):
    camera = json.loads((small_run.set_folder / "camera.json").read_text())
    assert camera["rms_px"] < 0.5
    summary = read_table(small_run.run / SUMMARY_FILE, SUMMARY_COLUMNS)
    assert [row["status"] for row in summary] == ["fitted"] * 4
    record = json.loads((small_run.run / "bench.json").read_text())["runs"][-1]
    assert "--camera" in record["command"] and record["peak_rss_mb"] > 100


def test_fit_continues_a_run_on_the_rows_asked_for(small_run, capsys):
    """Rows 2-3 only, all fitted already by this run: it resumes and fits none, and the
    run's summary keeps rows 0-1 as they were."""
    summary = small_run.run / SUMMARY_FILE
    before = summary.read_text().splitlines()
    bench(capsys, "fit", str(small_run.set_folder), small_run.name, "--first", "4", "--skip", "2")
    rows = (small_run.set_folder / "subjects-rows2-3.csv").read_text().splitlines()
    assert [row.split(",")[0] for row in rows[1:]] == ["s0002-female", "s0003-male"]
    after = summary.read_text().splitlines()
    assert after[:3] == before[:3] and len(after) == 5
    assert [line.split(",")[:2] for line in after[3:]] == [
        [line.split(",")[0], "fitted earlier"] for line in before[3:]]


def test_report_shows_a_working_fitter(small_run, capsys):
    report = bench(capsys, "report", "--main", f"small={small_run.run}")
    row = next(line for line in report.splitlines() if line.startswith("| small |"))
    assert [cell.strip() for cell in row.split("|")[2:4]] == ["4", "0"]  # 4 fitted, 0 failed
    # the accuracy regression: bodyfit's default through a calibrated phone camera, on
    # these four (seed 2), pinned; a change in the fit's accuracy shows here
    assert mean_of_7(report, "small") == pytest.approx(PINNED_MEAN_OF_7, abs=0.05)
    stature = next(line for line in report.splitlines() if line.startswith("| O stature"))
    assert float(stature.split("|")[2].split("±")[0]) <= 0.1  # the stature is given


def test_keep_round_trips_a_run_through_the_kept_setting(small_run, capsys, tmp_path):
    """A run kept in two halves (as a run continued in another session) reports as the run
    itself, without the set; its truths and answer costs come with it."""
    run_report = bench(capsys, "report", "--main", f"small={small_run.run}")
    half = small_run.set_folder / "runs" / "half"
    half.mkdir()
    lines = (small_run.run / SUMMARY_FILE).read_text().splitlines(keepends=True)
    (half / SUMMARY_FILE).write_text("".join(lines[:3]))  # rows 0-1 only
    for subject in ("s0000-female", "s0001-male"):
        (half / subject).mkdir()
        (half / subject / "run.json").write_text((small_run.run / subject / "run.json").read_text())
    printed = bench(capsys, "keep", str(small_run.set_folder), "half", "--setting", "small",
                    "--to", str(tmp_path))
    assert printed.endswith(": 2 subjects\n")
    bench(capsys, "keep", str(small_run.set_folder), small_run.name, "--to", str(tmp_path))
    kept = tmp_path / "in-space" / "small.csv"
    assert [row["id"] for row in read_table(kept, KEPT_COLUMNS)] == [
        "s0000-female", "s0001-male", "s0002-female", "s0003-male"]
    truths = read_truths(tmp_path / "in-space" / "truths.csv")
    own = json.loads((small_run.set_folder / "s0003-male" / "truth.json").read_text())
    assert truths["s0003-male"]["measurements"] == own["measurements"]
    assert read_table(tmp_path / "in-space" / "truths.csv", TRUTH_COLUMNS)
    kept_report = bench(capsys, "report", "--main", f"small={kept}")
    assert tables(kept_report) == tables(run_report)
    assert (read_source(kept).answer_costs == read_source(small_run.run).answer_costs).all()
    # --first 3 --skip 1: the set's rows 1-2, picked by their ids
    windowed = bench(capsys, "report", "--first", "3", "--skip", "1", "--ablation", f"w={kept}")
    row = next(line for line in windowed.splitlines() if line.startswith("| w |"))
    assert row.split("|")[2].strip() == "2"


def test_report_joins_sources_each_subject_from_the_first(small_run, capsys, tmp_path):
    """A source that holds rows 0-1 joined before the whole run: the same tables, each
    part's subjects counted apart."""
    first_half = tmp_path / "runs" / "first-half"
    first_half.mkdir(parents=True)
    lines = (small_run.run / SUMMARY_FILE).read_text().splitlines(keepends=True)
    (first_half / SUMMARY_FILE).write_text("".join(  # rows 2-3 not run
        lines[:3] + [re.sub(r"^([^,]+),[^,]+,", r"\1,not run,", line) for line in lines[3:]]))
    report = bench(capsys, "report", "--main", f"small={small_run.run}")
    # the first source's truths are its set's: give it the run's set as parent
    set_copy = tmp_path
    for subject in small_run.set_folder.glob("s0*"):
        (set_copy / subject.name).mkdir()
        (set_copy / subject.name / "truth.json").write_text((subject / "truth.json").read_text())
    joined = bench(capsys, "report", "--main", f"small={first_half}+{small_run.run}")
    assert tables(joined) == tables(report)
    assert "first-half: 2 fitted" in joined and "small: 2 fitted" in joined


def test_spread_writes_the_calibration_it_prints(small_run, capsys, tmp_path):
    """The factors printed are those written (a round trip through the file), made from
    the 4 subjects; tested on its own 4 subjects, each factor is the 68.3 % quantile of 4
    ratios, between the third and the fourth, so the truth lies within for 3 of the 4
    (all 4 where those two tie)."""
    written = tmp_path / "spread_calibration.json"
    printed = bench(capsys, "spread", str(small_run.run), "--write", str(written))
    calibration = read_calibration(written.read_text())
    assert calibration.subjects == 4 and "spread" in calibration.source
    factors = dict(re.findall(r"^\| ([A-P]) [^|]+\| ([.\d]+) \|", printed, re.M))
    assert factors.keys() == calibration.per_cost.keys()
    for key, factor in factors.items():
        assert float(factor) == pytest.approx(calibration.per_cost[key], abs=5.01e-4)
    printed = bench(capsys, "spread", str(small_run.run), "--calibration", str(written))
    assert f"{written}'s calibration (4 subjects)" in printed
    rows = re.findall(r"^\| ([A-P]) [^|]+\| ([.\d]+) \| ([.\d]+) \| (\d+)% \|", printed, re.M)
    assert [key for key, *_ in rows] == list(calibration.per_cost)
    for key, made, tested, within in rows:  # the file keeps 6 decimals: a last digit may turn
        assert float(made) == pytest.approx(float(tested), abs=1.01e-3)
        assert within in ("75", "100")


@pytest.mark.parametrize("text", [None, "not json", '{"format": "other"}',
                                  '{"format": "bodyfit.spread_calibration/1"}'])
def test_spread_refuses_a_calibration_file_it_cannot_read(tmp_path, text):
    """`spread --calibration FILE`: a missing, corrupt or foreign file is one line and a
    non-zero exit, before any fit is read."""
    calibration = tmp_path / "calibration.json"
    if text is not None:
        calibration.write_text(text)
    done = subprocess.run([sys.executable, "-m", "bench.accuracy", "spread", str(tmp_path),
                           "--calibration", str(calibration)], capture_output=True, text=True,
                          cwd=ROOT)
    assert done.returncode == 1 and "Traceback" not in done.stderr
    assert done.stderr.strip().splitlines()[-1].startswith(
        f"{calibration}: not a readable spread calibration (")


def test_figures_last_generation_is_the_runs_own_error(small_run, capsys, tmp_path):
    """Fig. 12's error after the last generation is the run's own (a round trip through
    run.json's per-generation answers); both pictures are written."""
    mean7 = mean_of_7(bench(capsys, "report", "--main", f"small={small_run.run}"), "small")
    printed = bench(capsys, "figures", str(small_run.set_folder), "--curve",
                    f"small={small_run.name}", "--meshes", "small", "--generations", "80",
                    "--docs", str(tmp_path))
    assert float(re.search(r"g80 ([\d.]+)", printed).group(1)) == pytest.approx(mean7, abs=0.06)
    for name in ("accuracy_error_per_generation.png", "accuracy_meshes.png"):
        assert cv2.imread(str(tmp_path / name)) is not None
