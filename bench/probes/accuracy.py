"""One-off investigations of the accuracy benchmark's runs (not supported commands).

Each answered a question behind a past choice (docs/history.md) and is kept runnable, so
that its answer can be checked again. They read runs of ``python -m bench.accuracy fit``
(SET/runs/NAME, with every subject's run.json) on a set made by ``make``::

    # how far calib's extracted outlines lie from the exact silhouettes, per refinement passes
    python -m bench.probes.accuracy outlines SETS/in --first 10 --passes 1 2 4
    # the space's floor: the error of each true body's closest body of K components
    python -m bench.probes.accuracy floor SETS/out --first 100 --components 20 40 60
    # does the cost tell the truth's closest body from the fit's answer (search or photos?)
    python -m bench.probes.accuracy costs SETS/out default --first 30
    # the error had each refinement run G generations only (0: the searches' answer)
    python -m bench.probes.accuracy budgets SETS/out long long-b --generations 0 250 500
    # other ways to combine the refinements' answers the fits averaged; the neck's error
    python -m bench.probes.accuracy combine SETS/in default
    # each measurement's signed error against the front photo's limb bends (out-of-space)
    python -m bench.probes.accuracy bends SETS/out default
    # the photo readings with the front body bent by the truth's angles or the estimate
    python -m bench.probes.accuracy bend-readings SETS/out default --first 72
    # a run's fits measured again by today's code, into a new run (a change of the
    # measuring alone needs no fit again)
    python -m bench.probes.accuracy remeasure SETS/in default default-remeasured
"""

from __future__ import annotations

import argparse
import json
import shutil
import sys
from pathlib import Path

import numpy as np
import warp
from scipy import stats

from bench.accuracy.bodies import pose_bodies
from bench.accuracy.figures import errors_per_generation
from bench.accuracy.outlines import outline_errors
from bench.accuracy.fit_photos import FitPhotos, answer_pose
from bench.accuracy.report import mean_of_important
from bench.accuracy.runs import (concatenated, joined_scores, read_source, record_holders,
                                 run_folder)
from bench.accuracy.scores import IMPORTANT_COLUMNS, KEYS, error_stats
from bench.accuracy.subject_set import read_bodies, read_settings, read_truth, subject_ids
from bench.probes import bend_readings as bend_probes
from bench.probes.combine import combine
from bench.probes.truth_costs import compare_costs
from bodyfit.calib.silhouette import SilhouetteSettings, photo_silhouette
from bodyfit.fitter.batch.orchestration import BATCH_FILE
from bodyfit.fitter.batch.tables import (SUMMARY_COLUMNS, SUMMARY_FILE, SummaryRow, read_table,
                                         summary_row, write_tables)
from bodyfit.fitter.demo.studio_photos import pinhole_silhouette
from bodyfit.fitter.fit.person_fit import METHODS, reported_measurements
from bodyfit.fitter.fit.photo_extents import SCALED
from bodyfit.fitter.fit.spreads import (bodyfit_calibration, calibration_applies,
                                        recorded_answer_cost)
from bodyfit.fitter.fit.stature import scaled_to_stature
from bodyfit.fitter.measure.measurements import MEASUREMENTS, Measurer
from bodyfit.fitter.model.body_model import PART_NAMES, POSE_NAMES, project_shape, rest_shape
from bodyfit.fitter.model.cache import load_model
from bodyfit.fitter.output.result_files import write_fitted_measurements
from bodyfit.fitter.run.config import read_run_config

__all__ = ["main"]


def remeasure(args) -> None:
    """Each fit of a run (a name or a folder, :func:`~bench.accuracy.runs.run_folder`)
    measured again by today's code, as `fitter run` measures its answer now
    (:func:`bodyfit.fitter.fit.person_fit.fitted_measurements`: the answer's body and the subject's
    photos in the set, then :func:`~bodyfit.fitter.fit.person_fit.reported_measurements`),
    into the new run SET/runs/TO/: each record kept, measurements.json and summary.csv
    written anew with the ± of today's calibration where it applies (the run's own ±
    otherwise). A change of the measuring alone needs no fit again: the search's answer
    does not depend on it."""
    folder = Path(args.set)
    source, out = run_folder(folder, args.name), folder / "runs" / args.to
    model = load_model()
    measurer = Measurer.from_model(model)
    previous = {row["id"]: row for row in read_table(source / SUMMARY_FILE, SUMMARY_COLUMNS)}
    out.mkdir(parents=True, exist_ok=True)
    for name in (BATCH_FILE, "bench.json"):
        if (source / name).exists():
            shutil.copyfile(source / name, out / name)
    scores = read_source(source)
    rows = [SummaryRow(subject, "failed earlier", reason=reason)
            for subject, reason in scores.failures]
    for subject in scores.ids:
        record = json.loads((source / subject / "run.json").read_text())
        photos = FitPhotos.of(model, folder, subject, record)
        _, values, _ = photos.measure(model, measurer, np.array(record["result"]["betas"]),
                                      answer_pose(record))
        written = json.loads((source / subject / "measurements.json").read_text())
        basis = written.get("spread_basis", "population")
        if calibration_applies(photos.settings, METHODS["bodyfit"]):
            basis = "calibrated"
        if basis in ("calibrated", "solver"):  # the default's factors, as fit_person gives
            spreads = bodyfit_calibration().spreads(recorded_answer_cost(record))
        else:
            spreads = {key: written["measurements"][name]["spread_mm"]
                       for key, (name, _) in MEASUREMENTS.items()}
        person = record["inputs"]
        values, spreads = reported_measurements(photos.settings, values, spreads,
                                                person.get("sex", "unknown"),
                                                person["height_cm"] / 100.0,
                                                person.get("mass_kg"))
        (out / subject).mkdir(exist_ok=True)
        (out / subject / "run.json").write_text(json.dumps(record, indent=1))
        write_fitted_measurements(out / subject / "measurements.json", values, spreads, basis,
                                  written["provenance"] | {"remeasured_from": str(source)})
        seconds = previous[subject]["seconds"]
        rows.append(summary_row(out / subject, previous[subject]["status"],
                                float(seconds) if seconds else None))
        others = max(abs(values[key] - _old(written, key)) for key in MEASUREMENTS
                     if key not in SCALED)
        print(f"{subject}: " + ", ".join(f"{key} {values[key] - _old(written, key):+.1f} mm"
                                         for key in SCALED)
              + f"; the others as written to within {others:.2f} mm", flush=True)
    write_tables(out, rows)
    print(f"{source} -> {out}: {len(rows)} subjects")



def outlines(args) -> None:
    """calib's silhouettes of a set's photos against the exact ones, per outline passes.

    The exact silhouette of a photo is the pixels its body covers by more than half
    (:func:`pinhole_silhouette`, in the undistorted frame); the extracted one is
    ``photo_silhouette``'s, undistorted through the set's true camera, so that only the
    extraction is measured. Prints, per number of passes, the mean over photos of the
    outline's outward offset (extra minus missed pixels per outline pixel of the exact
    silhouette, pixels) and of the pixels wrong per outline pixel.
    """
    folder = Path(args.set)
    model = load_model()
    bodies, camera = read_bodies(model, folder), read_settings(folder).camera
    ids = subject_ids(len(bodies.sex), bodies.sex)
    offsets: dict[int, list[tuple[float, float]]] = {passes: [] for passes in args.passes}
    for index in range(args.first):
        truth = json.loads((folder / ids[index] / "truth.json").read_text())
        for view, posed in zip(("front", "side"), pose_bodies(model, bodies, index)):
            exact = pinhole_silhouette(posed, model, view, PART_NAMES, camera.K,
                                       camera.image_size_px, truth["camera_distance_m"],
                                       truth["camera_height_m"])
            for passes in args.passes:
                mask = photo_silhouette(folder / ids[index] / f"{view}.jpg", camera,
                                        settings=SilhouetteSettings(outline_passes=passes))
                offsets[passes].append(outline_errors(mask, exact))
    print(f"{folder}, the first {args.first} subjects ({2 * args.first} photos), against "
          "the exact silhouettes:\n\n| outline passes | outward offset (px) | pixels wrong "
          "per outline pixel |\n|---|---|---|")
    for passes, values in offsets.items():
        outward, wrong = np.mean(values, axis=0)
        print(f"| {passes} | {outward:+.3f} | {wrong:.3f} |")



def floor(args) -> None:
    """The error no search over K components can go below: each true body's closest body
    of the first K components (:func:`project_shape`: least squares over its vertices
    and joints), rescaled to its stature as a fit is, measured against its truth. Prints
    a Markdown row per K: the 7 important measurements' mean |error| with its 95 % CI,
    over the hard share and the others (out-of-space), and each measurement's mean."""
    folder = Path(args.set)
    model = load_model()
    bodies = read_bodies(model, folder)
    ids = subject_ids(len(bodies.sex), bodies.sex)[:args.first]
    truth = np.array([[read_truth(folder / i)[key] for key in KEYS] for i in ids])
    stature_m = truth[:, KEYS.index("O")] / 1000.0
    hard = bodies.hard[:len(ids)]
    measurer = Measurer.from_model(model)
    print(f"{folder}, the first {len(ids)} subjects: each true body's closest body of the "
          "first K components, against its truth (mm)\n\n| K | 7 important (95 % CI) | "
          "hard share | others | " + " | ".join(KEYS) + " |\n|" + "---|" * (len(KEYS) + 4))
    for k in args.components:
        rest, _ = rest_shape(model, project_shape(model, bodies.vertices[:len(ids)],
                                                  bodies.joints[:len(ids)], k))
        errors = measurer.measure_many(scaled_to_stature(rest, stature_m)) - truth
        mean, _, ci = mean_of_important(errors)
        shares = [f"{mean_of_important(errors[rows])[0]:.2f}" if rows.any() else "-"
                  for rows in (hard, ~hard)]
        print(f"| {k} | {mean:.2f} (±{ci:.2f}) | {' | '.join(shares)} | "
              + " | ".join(f"{v:.1f}" for v in np.abs(errors).mean(axis=0)) + " |")



def costs(args) -> None:
    """The fit's answers against each truth's closest body of the fit's space, scored on
    the fit's own views (:mod:`bench.probes.truth_costs`): Markdown rows of the
    paired cost differences (truth minus answer: negative, the search stopped short of a
    cheaper body nearer the truth) with their 95 % CI, and per part against the fit's
    answer."""
    folder, run = Path(args.set), Path(args.set) / "runs" / args.name
    model = load_model()
    bodies = read_bodies(model, folder)
    found = []
    for index, subject in enumerate(subject_ids(len(bodies.sex), bodies.sex)[:args.first]):
        if (run / subject / "run.json").exists():
            found.append(compare_costs(model, run / subject / "run.json",
                                       bodies.vertices[index], bodies.joints[index]))
    if len(found) < 2:
        sys.exit(f"{run}: fewer than 2 fitted subjects")
    averaged = [c for c in found if len(c.answers)]  # fits that record their answers
    against = [("the fit's answer", found, lambda c: c.fit),
               ("the cheapest answer it averaged", averaged, lambda c: c.answers.min()),
               ("the answers it averaged, on average", averaged, lambda c: c.answers.mean())]
    print(f"{run}: the truth's closest body of the fit's space (its angles searched) against "
          "the fit, on the fit's views; cost, weighted mm\n\n| against | subjects | its mean "
          "cost | the truth's | truth minus it (95 % CI) | the truth cheaper |\n"
          "|---|---|---|---|---|---|")
    for name, comparisons, cost in against:
        if len(comparisons) < 2:
            continue
        values = np.array([cost(c) for c in comparisons])
        truth = np.array([c.truth for c in comparisons])
        difference = error_stats((truth - values)[:, None])
        print(f"| {name} | {len(comparisons)} | {values.mean():.2f} | {truth.mean():.2f} | "
              f"{difference.bias[0]:+.2f} ± {difference.bias_ci[0]:.2f} | "
              f"{np.sum(truth < values)} |")
    parts = error_stats(np.array([c.truth_parts - c.fit_parts for c in found]))
    cheaper = np.sum([c.truth_parts < c.fit_parts for c in found], axis=0)
    print("\n| part | truth minus the fit's answer (95 % CI) | the truth cheaper |\n|---|---|---|")
    for j, name in enumerate(PART_NAMES):
        print(f"| {name} | {parts.bias[j]:+.2f} ± {parts.bias_ci[j]:.2f} | {cheaper[j]} |")



def _budget_errors(model, bodies, folder: Path, run: Path, subjects: list[str],
                   budgets: list[int]) -> np.ndarray:
    """(S, len(budgets), 7) |error| (mm) of the 7 important measurements of ``run``'s fits
    of ``subjects`` had each refinement run ``budgets`` generations (see :func:`budgets`)."""
    searches = {(c.search.generations, c.search.refine_generations
                 if c.search.refine_components else 0)  # 0: no refinement
                for c in (read_run_config(run / s / "run.json").settings for s in subjects)}
    if len(searches) > 1:
        sys.exit(f"{run}: its fits ran different budgets {sorted(searches)}")
    (generations, longest), = searches
    if max(budgets) > longest:
        sys.exit(f"{run}: its refinements ran {longest} generations, fewer than {max(budgets)}")
    return errors_per_generation(model, bodies, folder, run, [generations + g for g in budgets],
                                 set(subjects))



def budgets(args) -> None:
    """Runs' fits as shorter refinements would have answered them: Markdown rows of the 7
    important measurements' error for each refinement budget, paired with the first.

    A refinement's first G generations do not depend on its budget (CMA-ES's state does not
    know it; the same seeds draw the same candidates), and run.json records the
    refinements' mean answer after every generation, so one run at the longest budget holds
    every shorter one's answer on the same subjects (each measured as the fit measures its
    answer, as ``figures`` measures it: the run's own error for the last generation). 0:
    the searches' answer, before any refinement. Several runs are joined, each subject
    from the first run holding it."""
    folder = Path(args.set)
    model = load_model()
    bodies = read_bodies(model, folder)
    ids = subject_ids(len(bodies.sex), bodies.sex)[:args.first]
    holders = record_holders([run_folder(folder, name) for name in args.names], ids)
    parts = [(run, {s for s, held in holders.items() if held == run})
             for run in dict.fromkeys(holders.values())]
    if len(holders) < 2:
        sys.exit(f"{folder}: fewer than 2 subjects fitted by {', '.join(args.names)}")
    errors = [_budget_errors(model, bodies, folder, run, [s for s in ids if s in own],
                             args.generations) for run, own in parts if own]
    errors = np.concatenate(errors)  # (S, G, 7)
    means = errors.mean(axis=2)
    print(f"{folder}: {'+'.join(args.names)}, {len(errors)} subjects, as each refinement's "
          "first G generations answered (mm)\n\n| G | "
          + " | ".join(KEYS[j] for j in IMPORTANT_COLUMNS)
          + f" | 7 important (95 % CI) | paired with G = {args.generations[0]} (95 % CI) | "
          "better for |\n" + "|---" * (len(IMPORTANT_COLUMNS) + 4) + "|")
    for column, budget in enumerate(args.generations):
        mean = error_stats(means[:, [column]])
        paired = error_stats((means[:, column] - means[:, 0])[:, None])
        print(f"| {budget} | " + " | ".join(f"{e:.1f}" for e in errors[:, column].mean(axis=0))
              + f" | {mean.mae[0]:.2f} (±{mean.mae_ci[0]:.2f}) | {paired.bias[0]:+.2f} ± "
              f"{paired.bias_ci[0]:.2f} | {np.sum(means[:, column] < means[:, 0])} |")



def _old(written: dict, key: str) -> float:
    """A measurement's value (mm) in a measurements.json's payload ``written``."""
    return written["measurements"][MEASUREMENTS[key][0]]["value_mm"]



def _rows_of(bodies) -> dict[str, int]:
    """subject id -> its row of the set's ``bodies``, in the set's order."""
    return {subject: row for row, subject in enumerate(subject_ids(len(bodies.sex), bodies.sex))}



def bends(args) -> None:
    """How each measurement's signed error follows the front photo's limb bends, which
    the fit's rig cannot make (out-of-space sets: each chain swung forward or back by up
    to ``flexion_deg``, :mod:`bench.accuracy.bodies`). Per measurement and per
    pair of chains (the arms, the legs: their mean bend, degrees): Spearman's rank
    correlation with the signed error, the least-squares slope (mm per degree), and the
    mean |error| with that linear share taken out, fitted on the same subjects (so an upper
    bound of what modelling the bend could gain)."""
    folder = Path(args.set)
    scores = concatenated(joined_scores([run_folder(folder, name) for name in args.names],
                                        args.first, args.skip))
    bodies = read_bodies(load_model(), folder)
    if not bodies.flexion_deg.any():
        sys.exit(f"bends: {folder}'s photos bend no limb (an in-space set)")
    row_of = _rows_of(bodies)
    rows = [row_of[subject] for subject in scores.ids]
    chains = {limbs: [POSE_NAMES.index(f"{joint}_abduction_{side}") for side in ("left", "right")]
              for limbs, joint in (("arms", "shoulder"), ("legs", "hip"))}
    bend = {name: bodies.flexion_deg[rows][:, columns].mean(axis=1)
            for name, columns in chains.items()}
    print(f"{folder}: {'+'.join(args.names)}, {len(rows)} subjects; the front photo's bend "
          "(degrees, + forward): arms' mean |bend| "
          f"{np.abs(bend['arms']).mean():.2f}, legs' {np.abs(bend['legs']).mean():.2f}\n\n"
          "| measurement | mean abs. error (mm) | "
          + " | ".join(f"{name}: rho, mm per degree, abs. error without" for name in chains)
          + " |\n|" + "---|" * (2 + len(chains)))
    for column, key in enumerate(KEYS):
        error = scores.errors[:, column]
        cells = []
        for angle in bend.values():
            slope = np.polyfit(angle, error, 1)[0]
            cells.append(f"{stats.spearmanr(angle, error).statistic:+.2f}, {slope:+.2f}, "
                         f"{np.abs(error - slope * (angle - angle.mean())).mean():.2f}")
        print(f"| {key} {MEASUREMENTS[key][1]} | {np.abs(error).mean():.2f} | "
              + " | ".join(cells) + " |")



def bend_readings(args) -> None:
    """What the front photo's limb bends do to the photo readings, fit by fit (out-of-space
    sets; :mod:`bench.probes.bend_readings`): the bicep's front width per degree
    of the benchmark's swing against a pure tilt (the truth's section); how well the front
    photo tells each arm's swing; each photo-read measurement's mean |error| as the fit
    reads it and with its front body bent by the truth's angles or by the estimate,
    paired differences with their 95 % intervals (Student t)."""
    folder = Path(args.set)
    model = load_model()
    measurer = Measurer.from_model(model)
    bodies = read_bodies(model, folder)
    if not bodies.flexion_deg.any():
        sys.exit(f"bend-readings: {folder}'s photos bend no limb (an in-space set)")
    row_of = _rows_of(bodies)
    wanted = list(row_of)[args.skip:args.first]
    holders = record_holders([run_folder(folder, name) for name in args.names], wanted)
    subjects = [s for s in wanted if s in holders]
    if len(subjects) < 2:
        sys.exit(f"{folder}: fewer than 2 subjects fitted by {', '.join(args.names)}")
    twists, errors, estimates = [], [], []
    for subject in subjects:
        row = row_of[subject]
        twists.append(bend_probes.twist_width_change(model, measurer, bodies, row))
        error, estimate = bend_probes.bend_readings(model, measurer, bodies, row, folder,
                                                    holders[subject], subject)
        errors.append(error)
        estimates.append(estimate[:2])
    twists, errors, estimates = np.array(twists), np.array(errors), np.array(estimates)
    truth = bodies.flexion_deg[[row_of[s] for s in subjects]][:, :2]
    print(f"{folder}: {'+'.join(args.names)}, {len(subjects)} subjects\n\n"
          f"- the left bicep's front width (the truth's section, orthographic): "
          f"{twists[:, 0].mean():+.3f} % per degree swung about the model's x axis (range "
          f"{twists[:, 0].min():+.3f} to {twists[:, 0].max():+.3f}), {twists[:, 1].mean():+.3f} "
          "tilted towards the camera\n- the arms' swing estimated from the front photo: "
          f"r {np.corrcoef(truth.ravel(), estimates.ravel())[0, 1]:.2f} with the truth's, "
          f"mean |estimate - truth| {np.abs(estimates - truth).mean():.2f} degrees (the "
          f"truth's mean |swing| {np.abs(truth).mean():.2f})\n")
    absolute = np.abs(errors)  # (S, variants, measurements)
    variants = bend_probes.VARIANTS
    print("| measurement | " + " | ".join(
        f"{v} (mm)" if i == 0 else f"{v}: mm, paired (95 % CI)" for i, v in enumerate(variants))
        + " |\n|" + "---|" * (1 + len(variants)))
    for column, key in enumerate(SCALED):
        cells = [f"{absolute[:, 0, column].mean():.2f}"]
        for variant in range(1, len(variants)):
            s = error_stats(absolute[:, variant, column:column + 1]
                            - absolute[:, 0, column:column + 1])
            cells.append(f"{absolute[:, variant, column].mean():.2f}, {s.bias[0]:+.2f} "
                         f"(±{s.bias_ci[0]:.2f})")
        print(f"| {key} {MEASUREMENTS[key][1]} | " + " | ".join(cells) + " |")



def _joined_runs_parser(sub, command: str, description: str,
                        skip_example: str | None = None) -> argparse.ArgumentParser:
    """A subcommand over a set and runs of it joined, with ``--first``, and with ``--skip``
    where ``skip_example`` says what rows it leaves out for."""
    p = sub.add_parser(command, help=description)
    p.add_argument("set")
    p.add_argument("names", nargs="+", metavar="name",
                   help="runs (SET/runs/NAME, or a folder of `keep`), joined: each "
                   "subject from the first")
    p.add_argument("--first", type=int, help="the set's first N subjects only")
    if skip_example is not None:
        p.add_argument("--skip", type=int, default=0, metavar="I",
                       help=f"with --first N: rows I to N - 1 only (e.g. {skip_example})")
    return p




def main(argv: list[str] | None = None) -> None:
    warp.config.log_level = warp.LOG_WARNING  # no initialisation banner in the Markdown
    parser = argparse.ArgumentParser(prog="python -m bench.probes.accuracy",
                                     description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)
    p = sub.add_parser("remeasure", help="a run's fits measured again by today's code, "
                       "into a new run")
    p.add_argument("set")
    p.add_argument("name", help="the run's name (SET/runs/NAME) or folder")
    p.add_argument("to", help="the new run's name (SET/runs/TO)")
    p = sub.add_parser("outlines", help="extracted silhouettes against the exact ones")
    p.add_argument("set")
    p.add_argument("--first", type=int, default=10, help="the set's first N subjects")
    p.add_argument("--passes", type=int, nargs="+", default=[1, 2, 4],
                   help="outline refinement passes to compare (SilhouetteSettings.outline_passes)")
    p = sub.add_parser("floor", help="the error of the truth's closest bodies of K components")
    p.add_argument("set")
    p.add_argument("--first", type=int, default=100, help="the set's first N subjects")
    p.add_argument("--components", type=int, nargs="+", default=[20, 40, 60], metavar="K")
    p = sub.add_parser("costs", help="the fit's answers against the truth's closest body, "
                       "scored on the fit's views")
    p.add_argument("set")
    p.add_argument("name", help="the run's name (SET/runs/NAME)")
    p.add_argument("--first", type=int, default=30, help="the set's first N subjects")
    p = sub.add_parser("budgets", help="the error had the refinements run fewer generations")
    p.add_argument("set")
    p.add_argument("names", nargs="+", metavar="name",
                   help="runs' names (SET/runs/NAME), joined: each subject from the first")
    p.add_argument("--first", type=int, help="the set's first N subjects only")
    p.add_argument("--generations", type=int, nargs="+", default=[0, 250, 500], metavar="G",
                   help="each refinement's generations (0: the searches' answer)")
    p = _joined_runs_parser(sub, "combine", "other ways to combine the answers a run's fits "
                            "averaged")
    p.add_argument("--answers", type=int, metavar="N",
                   help="each fit's first N answers only (as --refinements N would give)")
    _joined_runs_parser(sub, "bends", "each measurement's signed error against the front "
                        "photo's limb bends (out-of-space)",
                        skip_example="subjects held out from every choice")
    _joined_runs_parser(sub, "bend-readings", "the photo readings with the front body bent by "
                        "the truth's angles or the photo's estimate (out-of-space)",
                        skip_example="subjects held out from every choice")
    args = parser.parse_args(argv)
    {"remeasure": remeasure, "outlines": outlines, "floor": floor, "costs": costs,
     "budgets": budgets, "combine": combine, "bends": bends,
     "bend-readings": bend_readings}[args.command](args)


if __name__ == "__main__":
    main()
