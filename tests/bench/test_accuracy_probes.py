"""The accuracy benchmark's one-off probes (``python -m bench.probes.accuracy``), each over
the shared small run (conftest.py): each answers with a value that a round trip or an
analytic case fixes."""

from __future__ import annotations

import json
import re

import numpy as np
import pytest
from accuracy_runs import probe

from bench.accuracy.report import mean_of_important
from bench.accuracy.runs import read_source
from bodyfit.fitter.batch.tables import SUMMARY_COLUMNS, SUMMARY_FILE, csv_text, read_table
from bodyfit.fitter.measure.measurements import MEASUREMENTS


@pytest.fixture(scope="module")
def mean7(small_thorough_run) -> float:
    """The small thorough run's 7 important measurements' mean |error|, as its report
    prints it."""
    return round(mean_of_important(read_source(small_thorough_run.run).errors)[0], 2)


def test_remeasure_gives_a_fit_its_own_measurements_back(small_run, capsys):
    """A fit made on a GPU, measured again on a machine without one (its views prepared on
    the CPU whatever its record's device): the same measuring code gives the fit's own
    measurements back (a round trip)."""
    record = small_run.run / "s0000-female" / "run.json"
    payload = json.loads(record.read_text())
    gpu = small_run.set_folder / "runs" / "on-gpu"
    gpu.mkdir()
    for name in (SUMMARY_FILE, "failures.csv"):
        (gpu / name).write_bytes((small_run.run / name).read_bytes())
    for subject in small_run.set_folder.glob("s0*"):
        (gpu / subject.name).mkdir()
        for name in ("run.json", "measurements.json"):
            (gpu / subject.name / name).write_bytes((small_run.run / subject.name / name)
                                                    .read_bytes())
    (gpu / "s0000-female" / "run.json").write_text(json.dumps(
        payload | {"settings": payload["settings"] | {"device": "cuda:0"}}))
    probe(capsys, "remeasure", str(small_run.set_folder), "on-gpu", "again")
    fitted, again = (read_table(folder / SUMMARY_FILE, SUMMARY_COLUMNS)
                     for folder in (small_run.run, small_run.set_folder / "runs" / "again"))
    values = [f"{name}_mm" for name, _ in MEASUREMENTS.values()]
    assert len(fitted) == 4 and [row["id"] for row in again] == [row["id"] for row in fitted]
    np.testing.assert_allclose([[float(row[name]) for name in values] for row in again],
                               [[float(row[name]) for name in values] for row in fitted],
                               atol=0.05)


def test_budgets_own_budget_is_the_runs_own_error(small_thorough_run, capsys, mean7):
    """Shorter refinements read from the same run: its own budget gives its own error (a
    round trip); a budget longer than the run's is refused."""
    printed = probe(capsys, "budgets", str(small_thorough_run.set_folder), small_thorough_run.name,
                    "--generations", "0", "10", "20")
    longest = re.search(r"\| 20 \|(?: [.\d]+ \|){7} ([.\d]+) \(", printed)
    assert float(longest[1]) == pytest.approx(mean7, abs=0.06)
    with pytest.raises(SystemExit, match="fewer than 30"):
        probe(capsys, "budgets", str(small_thorough_run.set_folder), small_thorough_run.name, "--generations", "30")


def test_outlines_default_passes_sit_on_the_exact_edge(small_run, capsys):
    """calib's silhouettes of the JPEGs against the geometry's exact coverage: with the
    default passes on the edge within a tenth of a pixel, one pass clearly outside."""
    printed = probe(capsys, "outlines", str(small_run.set_folder), "--first", "2",
                    "--passes", "1", "4")
    outward = {int(m[1]): float(m[2]) for m in re.finditer(r"\| (\d) \| ([-+.\d]+) \|", printed)}
    assert abs(outward[4]) < 0.1 and outward[1] > 0.15


def test_floor_of_in_space_bodies_is_zero_at_their_own_components(small_run, capsys):
    """In-space bodies are drawn from the first 20 components, so their closest bodies of
    20 are themselves (up to the stored offsets' rounding); with 5, millimetres are lost."""
    printed = probe(capsys, "floor", str(small_run.set_folder), "--first", "4",
                    "--components", "5", "20")
    floor = {int(m[1]): float(m[2]) for m in re.finditer(r"\| (\d+) \| ([.\d]+) \(", printed)}
    assert floor[20] < 0.05 and floor[5] > 1.0


def test_combine_rebuilds_each_fits_own_measurements(small_thorough_run, capsys, mean7):
    """The first rule, the answers' mean, rebuilds each fit's own measurements from run.json
    (a few hundredths of a millimetre apart); its neck section's circumference is the
    report's neck error; the first three answers only are the mean of the first three."""
    printed = probe(capsys, "combine", str(small_thorough_run.set_folder), small_thorough_run.name)
    assert float(re.search(r"rebuilt to within ([.\d]+) mm", printed)[1]) < 0.05
    assert re.search(r"\| the mean of all \(the fit's\) \| ([.\d]+) .* \| \+0\.00 ± 0\.00 \|",
                     printed)[1] == f"{mean7:.2f}"
    neck = re.search(r"mean \|error\|: circumference ([.\d]+) mm; width ([.\d]+) mm", printed)
    assert float(neck[2]) > 0
    first3 = re.search(r"\| the mean of the first 3 \| ([.\d]+) ", printed)[1]
    printed = probe(capsys, "combine", str(small_thorough_run.set_folder), small_thorough_run.name,
                    "--answers", "3")
    assert "averaged 3 answers" in printed and "rebuilt" not in printed
    assert re.search(r"\| the mean of all \(the fit's\) \| ([.\d]+) ", printed)[1] == first3


def test_costs_the_truth_is_cheaper_than_a_short_search(small_thorough_run, capsys):
    """Drawn from the space the fit searches, the truth's closest body scores cheaper on the
    fit's views than a 60-generation search's answer."""
    printed = probe(capsys, "costs", str(small_thorough_run.set_folder), small_thorough_run.name, "--first", "2")
    row = re.search(r"\| the fit's answer \| 2 \| ([.\d]+) \| ([.\d]+) \| \S+ ± [.\d]+ \| (\d) \|",
                    printed)
    assert float(row[2]) < float(row[1]) and row[3] == "2"


def test_bends_refuses_a_set_whose_photos_bend_no_limb(small_run, capsys):
    with pytest.raises(SystemExit, match="bend no limb"):
        probe(capsys, "bends", str(small_run.set_folder), small_run.name)
    with pytest.raises(SystemExit, match="bend no limb"):
        probe(capsys, "bend-readings", str(small_run.set_folder), small_run.name)


def test_the_prior_probe_scores_kept_fits_with_and_without_the_prior(tmp_path):
    """bench.probes.measurement_prior on a made-up kept setting: a fit with a ± of 1 µm
    keeps its values; one with a ± of a kilometre takes the prior's."""
    from bench.accuracy.runs import KEPT_COLUMNS, TRUTH_COLUMNS
    from bench.probes.measurement_prior import prior_effect
    from bodyfit.fitter.fit.measurement_prior import MeasurementPrior
    from bodyfit.fitter.measure.measurements import IMPORTANT

    names = [name for name, _ in MEASUREMENTS.values()]
    truth = {k: 500.0 + 10 * i for i, k in enumerate(MEASUREMENTS)} | {"O": 1700.0}
    truths, kept = [], []
    for i, spread in enumerate((1e-3, 1e6)):
        subject = f"s{i:04d}-female"
        truths.append([subject, "female", "False", *[truth[k] for k in MEASUREMENTS]])
        cells = {"id": subject, "status": "fitted"} | {
            f"{n}_mm": truth[k] + 10.0 for k, n in zip(MEASUREMENTS, names)} | {
            f"{n}_spread_mm": spread for n in names}
        kept.append([cells.get(c, "") for c in KEPT_COLUMNS])
    (tmp_path / "truths.csv").write_text(csv_text(TRUTH_COLUMNS, truths))
    (tmp_path / "kept.csv").write_text(csv_text(KEPT_COLUMNS, kept))
    without, with_prior = prior_effect(tmp_path / "kept.csv", tmp_path / "truths.csv")
    np.testing.assert_allclose(without, [10.0, 10.0])
    mean, _ = MeasurementPrior.load().predict("female", 1700.0)
    expected = np.mean([abs(mean[k] - truth[k]) for k in IMPORTANT])
    np.testing.assert_allclose(with_prior, [10.0, expected], rtol=1e-6)
