"""`fitter batch` end to end on small synthetic subjects: results, failures, resuming after
a kill, dying workers, the Ray engine, and bad input."""

import contextlib
import csv
import io
import json
import logging
import os
import shutil
import signal
import subprocess
import sys
import time

import cv2
import numpy as np
import pytest

from bodyfit.fitter.batch.job import WORKER_EXIT_HOOK, subject_job
from bodyfit.fitter.batch.subjects import read_subjects
from bodyfit.fitter.cli.main import main
from bodyfit.fitter.demo.studio_photos import write_subject
from bodyfit.fitter.fit.person_fit import FitSettings
from bodyfit.fitter.model.cache import CACHE_ENV_VAR
from bodyfit.fitter.run.results import RUN_FILES
from bodyfit.kernels import cpu_threads

#: A tiny budget: the tests check the batch, not the fit's accuracy.
BUDGET = ["--method", "thorough", "--projection", "orthographic", "--optimizer", "cmaes", "--population", "8",
          "--generations", "2", "--seed", "3", "--refine-components", "0"]
GOOD = ("s0", "s1", "s2", "s3")
#: The six-row table: four good subjects, a blank front photo, a photo that does not exist.
SIX = ("s0", "blank", "s1", "s2", "missing", "s3")
BATCH_FILES = ("summary.csv", "failures.csv", "batch.json")


@pytest.fixture(scope="module")
def shipped_model_only(tmp_path_factory):
    """The workers (fresh processes) load the shipped model, not a user's build."""
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv(CACHE_ENV_VAR, str(tmp_path_factory.mktemp("cache")))
        patch.delenv(WORKER_EXIT_HOOK, raising=False)
        yield


@pytest.fixture(scope="module")
def studio(body_model, tmp_path_factory, shipped_model_only):
    """A folder of four subjects' photos (each in its own folder), a blank photo, and the
    six-row table (relative paths); returns (folder, statures in cm)."""
    folder = tmp_path_factory.mktemp("studio")
    rng = np.random.default_rng(7)
    heights = {}
    for name in GOOD:
        (folder / name).mkdir()
        truth = write_subject(folder / name, body_model,
                              np.clip(rng.standard_normal(20), -1.5, 1.5), rng.uniform(2, 8, 4))
        heights[name] = round(truth["O"] / 10, 1)
    cv2.imwrite(str(folder / "blank.png"), np.full((800, 600, 3), 180, np.uint8))
    rows = {name: row for name, row in zip(GOOD, subject_rows(heights))}
    rows["blank"] = ["blank", "blank.png", "s0/side.png", 170]
    rows["missing"] = ["missing", "gone/front.png", "s0/side.png", 170]
    write_table(folder / "six.csv", [rows[name] for name in SIX])
    return folder, heights


def subject_rows(heights, names=GOOD):
    return [[name, f"{name}/front.png", f"{name}/side.png", heights[name]] for name in names]


def write_table(path, rows, header=("id", "front", "side", "height_cm")):
    with open(path, "w", newline="") as stream:
        writer = csv.writer(stream)
        writer.writerow(header)
        writer.writerows(rows)
    return path


def batch(*argv):
    """Run `fitter -q batch ARGV`; return (exit status, stdout, stderr)."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(["-q", "batch", *map(str, argv)])
    return code, out.getvalue(), err.getvalue()


def summary(out):
    with open(out / "summary.csv", newline="") as stream:
        return list(csv.DictReader(stream))


def failures(out):
    with open(out / "failures.csv", newline="") as stream:
        return {row["id"]: row["reason"] for row in csv.DictReader(stream)}


def results(out):
    """id -> the summary row without its seconds and status (what the same seed fixes)."""
    return {row["id"]: {k: v for k, v in row.items() if k not in ("seconds", "status")}
            for row in summary(out)}


def statuses(out):
    return {row["id"]: row["status"] for row in summary(out)}


@pytest.fixture(scope="module")
def local_batch(studio, tmp_path_factory):
    """The six-row table on the local engine, two workers, bad rows skipped."""
    folder, _ = studio
    out = tmp_path_factory.mktemp("local") / "out"
    code, stdout, stderr = batch(folder / "six.csv", "-o", out, "--workers", 2,
                                 "--skip-bad-rows", *BUDGET)
    return out, code, stdout, stderr


def test_batch_fits_the_good_subjects_and_records_the_broken_ones(local_batch, studio):
    out, code, stdout, stderr = local_batch
    _, heights = studio
    assert code == 1, stderr  # ran, but not every subject was fitted
    assert sorted(p.name for p in out.iterdir()) == sorted([*GOOD, *BATCH_FILES])
    for name in GOOD:
        assert sorted(p.name for p in (out / name).iterdir()) == sorted(RUN_FILES)
    rows = summary(out)
    assert [row["id"] for row in rows] == list(SIX)  # the table's order
    assert statuses(out) == {"s0": "fitted", "blank": "failed", "s1": "fitted",
                             "s2": "fitted", "missing": "bad row", "s3": "fitted"}
    for row in rows:
        values = [v for k, v in row.items() if k.endswith("_mm")]
        assert len(values) == 32  # 16 measurements with their spreads
        if row["status"] != "fitted":
            assert not any(values) and not row["best_cost"]
            continue
        record = json.loads((out / row["id"] / "run.json").read_text())
        assert float(row["best_cost"]) == record["result"]["best_cost"]
        assert float(row["seconds"]) > 0
        assert all(float(row[k]) >= 0 for k in row if k.endswith("_spread_mm"))
        # every candidate stands as tall as the person: the fitted stature is the table's
        assert float(row["stature_mm"]) == pytest.approx(heights[row["id"]] * 10, abs=0.5)
        table = json.loads((out / row["id"] / "measurements.json").read_text())["measurements"]
        assert float(row["chest_circumference_mm"]) == table["chest_circumference"]["value_mm"]
    assert len({row["best_cost"] for row in rows if row["status"] == "fitted"}) == 4
    reasons = failures(out)
    assert sorted(reasons) == ["blank", "missing"]
    assert "no person" in reasons["blank"]
    assert reasons["missing"].startswith("line 6:") and "no such file" in reasons["missing"]
    assert "skipping" in stderr and "six.csv line 6" in stderr
    assert "4 fitted, 1 failed, 1 bad row" in stdout
    record = json.loads((out / "batch.json").read_text())
    assert record["engine"] == "local" and record["workers"] == 2
    assert record["subjects"]["fitted"] == 4 and record["seconds"]["start_up"] > 0
    for name in GOOD:  # each worker's fits score candidates on its share of the cores
        settings = json.loads((out / name / "run.json").read_text())["settings"]
        assert settings["threads"] == max(1, cpu_threads() // 2)


def test_a_subjects_results_are_those_of_fitter_run(local_batch, studio, tmp_path):
    out, _, _, _ = local_batch
    folder, heights = studio
    alone = tmp_path / "alone"
    code = main(["-q", "run", "--front", str(folder / "s1" / "front.png"), "--side",
                 str(folder / "s1" / "side.png"), "--height-cm", str(heights["s1"]),
                 "-o", str(alone), *BUDGET])
    assert code == 0
    assert sorted(p.name for p in alone.iterdir()) == sorted(p.name for p in (out / "s1").iterdir())
    for name in ("measurements.json", "run.json"):
        ran, batched = (json.loads((path / name).read_text()) for path in (alone, out / "s1"))
        key = "measurements" if name == "measurements.json" else "result"
        assert ran[key] == batched[key]
    batched = json.loads((out / "s1" / "run.json").read_text())
    assert batched["output"] == str(out / "s1")
    assert batched["inputs"]["front"] == str(folder / "s1" / "front.png")  # absolute


def test_same_seed_same_results_with_one_worker_and_a_run_jsons_settings(local_batch, studio,
                                                                         tmp_path):
    out, _, _, _ = local_batch
    folder, _ = studio
    # --config: the settings (BUDGET's) of a subject's run.json, not its person
    code, _, stderr = batch(folder / "six.csv", "-o", tmp_path / "one", "--workers", 1,
                            "--skip-bad-rows", "--config", out / "s0" / "run.json")
    assert code == 1, stderr
    assert results(tmp_path / "one") == results(out)
    assert failures(tmp_path / "one") == failures(out)


def test_a_rerun_keeps_what_is_done_and_retries_failures_only_when_asked(local_batch, studio,
                                                                         tmp_path):
    folder, _ = studio
    out = tmp_path / "out"
    shutil.copytree(local_batch[0], out)
    (out / "s3" / "report.html").unlink()  # not the batch's doing: never overwritten
    code, _, stderr = batch(folder / "six.csv", "-o", out, "--skip-bad-rows", *BUDGET)
    assert code == 1, stderr
    assert statuses(out) == {"s0": "fitted earlier", "blank": "failed earlier",
                             "s1": "fitted earlier", "s2": "fitted earlier",
                             "missing": "bad row", "s3": "failed"}
    assert "no person" in failures(out)["blank"]
    assert "holds files but not all" in failures(out)["s3"]
    before = {row["id"]: row for row in summary(local_batch[0])}
    for row in summary(out):
        if row["status"] == "fitted earlier":
            assert row["seconds"] == before[row["id"]]["seconds"]
    assert json.loads((out / "batch.json").read_text())["seconds"]["start_up"] is None  # no fit
    code, _, stderr = batch(folder / "six.csv", "-o", out, "--skip-bad-rows", "--retry-failed",
                            *BUDGET)
    assert statuses(out)["blank"] == "failed"  # tried again
    assert float({row["id"]: row for row in summary(out)}["blank"]["seconds"]) > 0


def test_killed_batch_resumes_with_every_subject_done_exactly_once(local_batch, studio,
                                                                   tmp_path):
    folder, heights = studio
    table = write_table(tmp_path / "four.csv", [
        [name, str(folder / front), str(folder / side), height]
        for name, front, side, height in subject_rows(heights)])
    out = tmp_path / "out"
    argv = [table, "-o", out, "--workers", 1, "--threads", 5, *BUDGET]
    process = subprocess.Popen(
        [sys.executable, "-m", "bodyfit.fitter.cli.main", "-q", "batch", *map(str, argv)],
        start_new_session=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + 180
    try:
        while not any((out / name).exists() for name in GOOD):
            assert process.poll() is None and time.monotonic() < deadline
            time.sleep(0.02)
    finally:
        os.killpg(process.pid, signal.SIGKILL)  # the batch and its workers, mid-subject
        process.wait()
    done = {name: (out / name / "run.json").stat().st_mtime_ns for name in GOOD
            if (out / name).exists()}
    assert 0 < len(done) < len(GOOD)
    for name in done:  # a subject's folder appears whole or not at all
        assert sorted(p.name for p in (out / name).iterdir()) == sorted(RUN_FILES)
    # what a kill while writing leaves: a staging folder, a table's temporary file
    (out / ".s3.0123abcd.partial").mkdir()
    (out / ".s3.0123abcd.partial" / "mesh.obj").write_text("v 0 0")
    (out / ".summary.csv.999.0123abcd.part").write_text("id,sta")
    code, _, stderr = batch(*argv)
    assert code == 0, stderr
    assert statuses(out) == {name: "fitted earlier" if name in done else "fitted"
                             for name in GOOD}
    for name, written in done.items():  # not fitted again
        assert (out / name / "run.json").stat().st_mtime_ns == written
    assert sorted(p.name for p in out.iterdir()) == sorted([*GOOD, *BATCH_FILES])
    reference = results(local_batch[0])
    assert results(out) == {name: reference[name] for name in GOOD}
    # the user's --threads, not the engine's share; the results do not depend on it
    assert all(json.loads((out / name / "run.json").read_text())["settings"]["threads"] == 5
               for name in GOOD)


def test_a_dying_worker_is_retried_once_then_recorded_and_the_batch_finishes(
        local_batch, studio, tmp_path, monkeypatch):
    folder, heights = studio
    table = write_table(folder / "three.csv", subject_rows(heights, ("s0", "s1", "s2")))
    marker = tmp_path / "s1-died-once"
    monkeypatch.setenv(WORKER_EXIT_HOOK, f"s1:{marker},s2")  # s1 dies once, s2 every time
    out = tmp_path / "out"
    code, _, stderr = batch(table, "-o", out, "--workers", 2, *BUDGET)
    assert code == 1, stderr
    assert marker.exists()  # s1's first worker did die
    assert statuses(out) == {"s0": "fitted", "s1": "fitted", "s2": "failed"}
    assert "worker process died" in failures(out)["s2"] and "2 times" in failures(out)["s2"]
    reference = results(local_batch[0])
    assert {k: v for k, v in results(out).items() if k != "s2"} == \
        {name: reference[name] for name in ("s0", "s1")}
    assert sorted(p.name for p in out.iterdir()) == sorted(["s0", "s1", *BATCH_FILES])


# --- Ray ----------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def ray_instance(shipped_model_only, tmp_path_factory):
    """A local Ray instance whose workers die once on s2 and always on "doomed"; yields
    the file s2's first death leaves."""
    ray = pytest.importorskip("ray", reason="Ray is not installed (pip install -e '.[ray]'; "
                                            "CI installs it)")
    marker = tmp_path_factory.mktemp("ray") / "s2-died-once"
    with pytest.MonkeyPatch.context() as patch:  # Ray's workers inherit it from ray.init
        patch.setenv(WORKER_EXIT_HOOK, f"s2:{marker},doomed")
        ray.init(num_cpus=2, include_dashboard=False, logging_level=logging.ERROR,
                 log_to_driver=False)
    yield marker
    ray.shutdown()


def test_ray_gives_the_local_engines_results(ray_instance, local_batch, studio, tmp_path):
    folder, _ = studio
    out = tmp_path / "ray"
    code, _, stderr = batch(folder / "six.csv", "-o", out, "--ray", "--skip-bad-rows",
                            *BUDGET)
    assert code == 1, stderr
    assert ray_instance.exists()  # s2's first actor died, and s2 was fitted on a fresh one
    assert statuses(out) == statuses(local_batch[0])
    assert results(out) == results(local_batch[0])
    assert failures(out) == failures(local_batch[0])
    record = json.loads((out / "batch.json").read_text())
    assert record["engine"] == "ray" and record["workers"] == 2


def test_ray_records_a_subject_whose_worker_always_dies(ray_instance, studio, tmp_path):
    folder, heights = studio
    table = write_table(tmp_path / "doomed.csv", [
        ["doomed", str(folder / "s0" / "front.png"), str(folder / "s0" / "side.png"),
         heights["s0"]]])
    code, _, stderr = batch(table, "-o", tmp_path / "out", "--ray", *BUDGET)
    assert code == 1, stderr
    assert statuses(tmp_path / "out") == {"doomed": "failed"}
    assert "worker process died" in failures(tmp_path / "out")["doomed"]


def test_ray_missing_is_one_line_exit_2(studio, tmp_path, monkeypatch):
    folder, _ = studio
    monkeypatch.setitem(sys.modules, "ray", None)  # `import ray` fails as if not installed
    code, _, stderr = batch(folder / "six.csv", "-o", tmp_path / "out", "--ray",
                            "--skip-bad-rows")
    assert code == 2 and len(stderr.strip().splitlines()) == 1
    assert "pip install" in stderr and not (tmp_path / "out").exists()


# --- bad input ----------------------------------------------------------------------------

GOOD_ROW = ["s0", "s0/front.png", "s0/side.png", "170"]


@pytest.mark.parametrize("header,rows,options,message", [
    (("id", "front", "side"), [GOOD_ROW[:3]], [], "missing column height_cm"),
    (("id", "front", "side", "heigth_cm"), [GOOD_ROW], [], "unknown column 'heigth_cm'"),
    (None, [GOOD_ROW, ["S0", *GOOD_ROW[1:]]], [], "line 3: id 'S0' is used already on line 2"),
    (None, [GOOD_ROW[:3]], [], "line 2: 3 cells, the header has 4"),
    (None, [[*GOOD_ROW[:3], "tall"]], [], "height_cm 'tall' is not a number"),
    (None, [[*GOOD_ROW[:3], "1.8"]], [], "height_cm must be a stature in centimetres"),
    (("id", "front", "side", "height_cm", "mass_kg"), [[*GOOD_ROW, "heavy"]], [],
     "mass_kg 'heavy' is not a number"),
    (("id", "front", "side", "height_cm", "mass_kg"), [[*GOOD_ROW, "0.08"]], [],
     "mass_kg must be a body mass in kilograms"),
    (None, [["s0", "nowhere.png", *GOOD_ROW[2:]]], [], "line 2: front nowhere.png: no such file"),
    (None, [["../x", *GOOD_ROW[1:]]], [], "id '../x' is not a safe folder name"),
    (None, [["/tmp/x", *GOOD_ROW[1:]]], [], "id '/tmp/x' is not a safe folder name"),
    (None, [["summary.csv", *GOOD_ROW[1:]]], [], "the batch's own files"),
    (None, [["", *GOOD_ROW[1:]]], [], "line 2: no id"),
    (None, [["../x", *GOOD_ROW[1:]], ["s1", "gone.png", *GOOD_ROW[2:]]], [],
     r"line 2: .*\(and 1 more bad row\); .*--skip-bad-rows"),
    (None, [GOOD_ROW], ["--camera", "nowhere.json"], "--camera nowhere.json: no such file"),
    (None, [GOOD_ROW], ["--population", "2"], "--population must be at least 4"),
    (None, [GOOD_ROW], ["--weight", "knee=3"], "unknown"),
    (None, [GOOD_ROW], ["--cpus-per-worker", "2"], "are for --ray"),
    (None, [GOOD_ROW], ["--workers", "0"], "--workers must be at least 1"),
    (None, [GOOD_ROW], ["--threads", "0"], "--threads must be at least 1"),
])
def test_bad_input_is_one_line_exit_2_before_any_work(studio, tmp_path, header, rows,
                                                      options, message):
    import re

    folder, _ = studio
    table = write_table(folder / "bad.csv", rows, header or ("id", "front", "side", "height_cm"))
    out = tmp_path / "out"
    code, stdout, stderr = batch(table, "-o", out, *options)
    assert code == 2
    assert stderr.startswith("fitter: error:") and len(stderr.strip().splitlines()) == 1
    assert re.search(message, stderr), stderr
    assert not out.exists() and not stdout


def test_a_missing_or_non_utf8_table_is_one_line_exit_2(tmp_path):
    for content, message in ((None, "no such file"), (b"id,front\n\xff\xfe\x00", "UTF-8"),
                             (b"id;front;side;height_cm\n", "separated by ';'"),
                             (b"", "is empty"),
                             (b"id,front,side,height_cm\n", "no subject rows")):
        table = tmp_path / "table.csv"
        table.unlink(missing_ok=True)
        if content is not None:
            table.write_bytes(content)
        code, _, stderr = batch(table, "-o", tmp_path / "out")
        assert code == 2 and message in stderr and len(stderr.strip().splitlines()) == 1


def test_table_paths_are_relative_to_its_folder(tmp_path, monkeypatch):
    photos = tmp_path / "photos"
    photos.mkdir()
    for name in ("f.png", "s.png", "cam.json", "w.toml"):
        (photos / name).write_bytes(b"x")
    (tmp_path / "tables").mkdir()
    table = write_table(tmp_path / "tables" / "t.csv", [
        ["a", "../photos/f.png", "../photos/s.png", "170", "../photos/cam.json", "female",
         "../photos/w.toml"],
        ["b", str(photos / "f.png"), "../photos/s.png", "165.5", "", "", "paper"]],
        ("id", "front", "side", "height_cm", "camera", "sex", "weights"))
    monkeypatch.chdir(photos)  # not the table's folder
    read = read_subjects(table)
    assert not read.bad_rows
    a, b = read.rows
    assert (a.inputs.front, a.inputs.camera, a.weights, a.inputs.sex, a.line) == (
        str(photos / "f.png"), str(photos / "cam.json"), str(photos / "w.toml"), "female", 2)
    assert (b.inputs.front, b.inputs.camera, b.weights, b.inputs.sex, b.inputs.height_cm) == (
        str(photos / "f.png"), None, "paper", "unknown", 165.5)


def test_a_rows_background_plates_replace_the_batchs(tmp_path):
    for name in ("f.png", "s.png", "plate_f.png", "plate_s.png"):
        (tmp_path / name).write_bytes(b"x")
    table = write_table(tmp_path / "t.csv", [
        ["a", "f.png", "s.png", "170", "plate_f.png", ""],
        ["b", "f.png", "s.png", "170", "", ""]],
        ("id", "front", "side", "height_cm", "background_front", "background_side"))
    read = read_subjects(table)
    assert not read.bad_rows
    batch_plates = {"background_front": "/studio/front.png", "background_side": "/studio/side.png"}
    a, b = (subject_job(row, FitSettings(), batch_plates, tmp_path / "out").inputs
            for row in read.rows)
    assert (a.background_front, a.background_side) == (str(tmp_path / "plate_f.png"),
                                                       "/studio/side.png")
    assert (b.background_front, b.background_side) == ("/studio/front.png", "/studio/side.png")


def test_summary_rows_carry_each_fits_poor_match_warning(tmp_path):
    """summary.csv's ``warning``: run.json's ``photos.fit_warning``, empty for a sound fit;
    a subject without readable results gets a row without values."""
    from bodyfit.fitter.batch.tables import SUMMARY_COLUMNS, summary_row, write_tables
    from bodyfit.fitter.measure.measurements import MEASUREMENTS

    table = {name: {"value_mm": 100.0 + i, "spread_mm": 2.0}
             for i, (name, _) in enumerate(MEASUREMENTS.values())}
    rows = []
    for subject, photos in (("sound", {}), ("poor", {"fit_warning": "matches poorly"})):
        folder = tmp_path / subject
        folder.mkdir()
        (folder / "measurements.json").write_text(json.dumps({"measurements": table}))
        (folder / "run.json").write_text(json.dumps({"result": {"best_cost": 50.0},
                                                     "photos": photos}))
        rows.append(summary_row(folder, "fitted", 3.0))
    (tmp_path / "broken").mkdir()
    rows.append(summary_row(tmp_path / "broken", "fitted", 3.0))
    write_tables(tmp_path, rows)
    written = summary(tmp_path)
    assert list(written[0]) == SUMMARY_COLUMNS
    assert [row["warning"] for row in written] == ["", "matches poorly", ""]
    assert written[1]["chest_circumference_mm"] == "103.00"
    assert written[2]["chest_circumference_mm"] == ""
