"""The accuracy benchmark's commands: synthetic subjects through the user's pipeline.

Run from the repository root (docs/accuracy.md holds what they measured)::

    # a subject set: bodies, photos through a phone camera, chessboard photos, the table
    python -m bench.accuracy make SETS/in --kind in-space --count 200 --seed 0
    python -m bench.accuracy make SETS/out --kind out-of-space --count 200 --seed 0
    python -m bench.accuracy make SETS/standing --kind standing --count 200 --seed 0
    # fit it as a user would: calib capture on the board photos, then fitter batch with
    # the calibrated camera (fitter batch options after --; resumable: rerun to continue)
    python -m bench.accuracy fit SETS/in bodyfit
    python -m bench.accuracy fit SETS/in thorough --first 54 -- --method thorough
    python -m bench.accuracy fit SETS/in uniform-weights --first 100 -- --weights uniform
    python -m bench.accuracy fit SETS/in no-camera --first 100 --camera none
    # a run's results merged into the setting kept in git (docs/accuracy-runs/in-space/
    # bodyfit.csv and the set's truths.csv), e.g. rows 100-199 fitted in a later session
    python -m bench.accuracy keep SETS/in bodyfit
    python -m bench.accuracy fit SETS/in bodyfit-b --first 200 --skip 100
    python -m bench.accuracy keep SETS/in bodyfit-b --setting bodyfit
    # Markdown tables of kept settings or runs (SOURCE+SOURCE: joined, each subject from
    # the first that holds it); --first/--skip: the set's rows skip to first - 1 only
    python -m bench.accuracy report --first 200 \
        --main "in-space=docs/accuracy-runs/in-space/bodyfit.csv" \
        --ablation "uniform weights=SETS/in/runs/uniform-weights"
    # the calibrated ± (fitter/fit/spreads.py) on a setting's fits; --write makes a
    # calibration of them (bodyfit's: fitter/data/spread_calibration.json)
    python -m bench.accuracy spread docs/accuracy-runs/out-of-space/bodyfit.csv --first 72
    # a room set (the same subjects dressed, in rooms; --first N: only its first N) and
    # each segmenter's silhouettes of it against the truth masks
    python -m bench.accuracy make SETS/room-out --kind out-of-space --count 200 --seed 0 \
        --rooms --first 24
    python -m bench.accuracy silhouettes SETS/room-out --first 24
    # the same with each photo's background plate (the empty room from a tripod)
    python -m bench.accuracy fit SETS/room-out plates --first 24 --plates
    python -m bench.accuracy silhouettes SETS/room-out --first 24 --plates --segmenter auto
    # error per generation (the paper's Fig. 12), bodies coloured by distance (Figs. 16-17)
    python -m bench.accuracy figures SETS/in --curve "bodyfit=bodyfit" \
        --curve "uniform weights=uniform-weights" --meshes bodyfit "uniform weights"

``make --bodies-only`` stops after drawing the bodies (bodies.npz, set.json: the
out-of-space draw needs Anny, the photos do not), ``make`` again photographs them; a set
or a run interrupted is continued by the same command. A run lies in SET/runs/NAME/
(fitter batch's output) with bench.json: its command, wall time, peak memory, machine.
One-off investigations of runs live apart: ``python -m bench.probes.accuracy``.
"""

from __future__ import annotations

import argparse
import concurrent.futures
import csv
import json
import multiprocessing
import os
import platform
import resource
import subprocess
import sys
import time
from pathlib import Path

import cv2
import numpy as np
import warp
from scipy import stats

from bench.accuracy.bodies import KINDS
from bench.accuracy.figures import (colour_bar, distance_panel, errors_per_generation,
                                    fitted_rest_body)
from bench.accuracy.report import (failure_lines, important_table, measurement_table,
                                   paired_measurement_table)
from bench.accuracy.runs import concatenated, joined_scores, keep_run, source_timing, subset
from bench.accuracy.outlines import HEIGHT_OFF_SHARE, height_error, outline_errors
from bench.accuracy.scores import KEYS, RunScores
from bench.accuracy.subject_set import (BOARD, CAMERA_FILE, SQUARE_MM, SetSettings, read_bodies,
                                        read_settings, subject_ids, write_bodies,
                                        write_photos_of_set)
from bench.subjects import bodyfit_command
from bodyfit.calib.images import write_image
from bodyfit.calib.segmenters import SEGMENTERS
from bodyfit.calib.silhouette import photo_silhouette
from bodyfit.common.errors import UserError
from bodyfit.fitter.batch.tables import (FAILURES_COLUMNS, FAILURES_FILE, SUMMARY_COLUMNS,
                                         SUMMARY_FILE, csv_text, read_table)
from bodyfit.fitter.fit.spreads import SpreadCalibration, bodyfit_calibration, read_calibration
from bodyfit.fitter.measure.measurements import MEASUREMENTS, Measurer
from bodyfit.fitter.model.cache import load_model
from bodyfit.fitter.output.plots import line_chart
from bodyfit.fitter.output.result_files import write_text

__all__ = ["main", "parse"]

#: Where ``keep`` writes kept settings: KEPT_DIR/<set kind>/<setting>.csv.
KEPT_DIR = Path("docs/accuracy-runs")


def _photograph(folder: str, subjects: list[int]) -> None:
    write_photos_of_set(load_model(), Path(folder), subjects)



def make(args) -> None:
    folder = Path(args.set)
    model = load_model()
    if not (folder / "bodies.npz").exists():
        settings = (SetSettings.standing(args.count, args.seed, pool_per_sex=args.pool_per_sex,
                                         rooms=args.rooms)
                    if args.kind == "standing" else
                    SetSettings(kind=args.kind, count=args.count, seed=args.seed,
                                pool_per_sex=args.pool_per_sex, rooms=args.rooms))
        folder.mkdir(parents=True, exist_ok=True)
        write_bodies(model, folder, settings)
        print(f"{folder}: {args.count} {args.kind} bodies drawn")
    if args.bodies_only:
        return
    count = json.loads((folder / "set.json").read_text())["settings"]["count"]
    count = min(count, args.first or count)
    write_photos_of_set(model, folder, [])  # the board photos, once
    workers = args.workers or os.cpu_count()
    chunks = [list(range(i, count, workers)) for i in range(workers)]
    context = multiprocessing.get_context("spawn")
    with concurrent.futures.ProcessPoolExecutor(workers, mp_context=context) as pool:
        for future in [pool.submit(_photograph, str(folder), chunk) for chunk in chunks]:
            future.result()
    table = write_photos_of_set(model, folder, [])
    print(f"{folder}: photographed; {table}")



def _table_rows(folder: Path, first: int | None, skip: int = 0) -> list[str]:
    """subjects.csv's header and its rows ``skip`` to ``first`` - 1 (to the last without
    ``first``): as many women as men when both are even (subject_set's order)."""
    lines = (folder / "subjects.csv").read_text().splitlines()
    return lines[:1] + lines[1 + skip:None if first is None else first + 1]



def _keep_earlier_rows(out: Path, earlier: dict[str, list[dict[str, str]]]) -> None:
    """Put back into the run's summary.csv and failures.csv the rows ``earlier`` (file name
    -> its rows before this batch) held of subjects outside this batch's table: fitter
    batch writes its tables for its own table's rows, so a run fitted in parts (``fit
    --skip``) would otherwise describe its last part alone. Rows in the set's order (ids
    sort as rows)."""
    now = {row["id"] for row in read_table(out / SUMMARY_FILE, ("id",))}
    # failures first, as fitter batch writes them
    for name, header in ((FAILURES_FILE, FAILURES_COLUMNS), (SUMMARY_FILE, SUMMARY_COLUMNS)):
        others = [row for row in earlier[name] if row["id"] not in now]
        if not others:
            continue
        rows = sorted(read_table(out / name, ("id",)) + others, key=lambda row: row["id"])
        write_text(out / name, csv_text(header, [[row.get(c, "") for c in header]
                                                 for row in rows]))



def fit(args, batch_options: list[str]) -> None:
    folder = Path(args.set)
    if not (folder / "subjects.csv").exists():
        sys.exit(f"{folder}: not a subject set (no subjects.csv); make it with `make` first")
    camera = folder / CAMERA_FILE
    if args.camera == "calibrated" and not camera.exists():
        photos = sorted(str(p) for p in (folder / "board").glob("*.png"))
        subprocess.run([bodyfit_command("calib"), "capture", *photos, "--board", BOARD, "--square-mm",
                        f"{SQUARE_MM:g}", "-o", str(camera)], check=True,
                       stdout=subprocess.DEVNULL)
    out = folder / "runs" / args.name
    table = folder / "subjects.csv"
    if args.first or args.plates:
        rows = _table_rows(folder, args.first, args.skip)
        if args.plates:
            ids = [row.split(",", 1)[0] for row in rows]
            rows = [rows[0] + ",background_front,background_side"] + [
                f"{row},{subject}/plate_front.jpg,{subject}/plate_side.jpg"
                for row, subject in zip(rows[1:], ids[1:])]
        window = (f"-rows{args.skip}-{args.first - 1}" if args.skip
                  else f"-first{args.first}") if args.first else ""
        table = folder / f"subjects{window}{'-plates' if args.plates else ''}.csv"
        table.write_text("".join(row + "\n" for row in rows))
    # a set with uncalibrated subjects names each subject's camera in its table
    per_row = read_settings(folder).per_row_camera
    command = [bodyfit_command("fitter"), "-q", "batch", str(table), "-o", str(out),
               *(["--camera", str(camera)] if args.camera == "calibrated" and not per_row
                 else []),
               *batch_options]
    earlier = {name: read_table(out / name, ("id",)) for name in (SUMMARY_FILE, FAILURES_FILE)}
    start = time.perf_counter()
    code = subprocess.run(command).returncode
    wall = time.perf_counter() - start
    _keep_earlier_rows(out, earlier)
    if code not in (0, 1):  # 1: some subjects failed (recorded in failures.csv)
        sys.exit(f"fitter batch stopped with exit status {code}")
    record = {"command": command, "wall_s": round(wall, 1),
              "peak_rss_mb": round(resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
                                   / 1024),
              "machine": f"{platform.machine()}, {os.cpu_count()} logical CPUs",
              "date": time.strftime("%Y-%m-%d %H:%M")}
    previous = out / "bench.json"
    runs = json.loads(previous.read_text())["runs"] if previous.exists() else []
    previous.write_text(json.dumps({"runs": [*runs, record]}, indent=1))
    print(f"{out}: fitter batch exit {code} in {wall:.0f} s")



def keep(args) -> None:
    """Merge a run's subjects into a setting kept in git (KEPT_DIR/<kind>/<setting>.csv,
    :func:`bench.accuracy.runs.keep_run`), with their truths (the set's truths.csv)."""
    folder = Path(args.set)
    run = folder / "runs" / args.name
    if not (run / SUMMARY_FILE).exists():
        sys.exit(f"{run}: no {SUMMARY_FILE} (not a run of fitter batch)")
    kept = Path(args.to) / read_settings(folder).kind / f"{args.setting or args.name}.csv"
    try:
        count = keep_run(run, kept)
    except ValueError as error:
        sys.exit(f"keep: {error}")
    print(f"{run} -> {kept}: {count} subjects")


def _source_spec(spec: str) -> tuple[str, list[Path]]:
    """LABEL=SOURCE[+SOURCE...] -> (label, the sources: kept .csv files or run folders)."""
    label, _, sources = spec.partition("=")
    if not label or not sources:
        sys.exit(f"report: {spec!r} is not LABEL=SOURCE[+SOURCE...]")
    return label, [Path(source) for source in sources.split("+")]


def _joined(sources: list[Path], first: int | None, skip: int) -> tuple[RunScores, str]:
    """The joined scores of ``sources`` (:func:`bench.accuracy.runs.joined_scores`) and
    where and how fast each part went."""
    for source in sources:
        if not source.exists():
            sys.exit(f"{source}: no such kept setting or run")
    parts = joined_scores(sources, first, skip)
    timing = "; ".join((f"{source.stem if source.suffix else source.name}: "
                        if len(parts) > 1 else "") + source_timing(source, scores)
                       for source, scores in parts)
    return concatenated(parts), timing


def _set_kind(source: Path) -> str:
    """The kind of set a source was fitted on: a kept setting's folder, a run's set.json."""
    return source.parent.name if source.suffix == ".csv" else read_settings(source.parents[1]).kind


def report(args) -> None:
    """Markdown tables: each ``--main`` source in the paper's Table 3 form (and split into
    the hard share and the others when it holds both), then every source in its Table 4
    form, each ``--ablation`` paired with the first ablation of the same set."""
    table4, baselines, first_of_set = {}, {}, {}
    for label, sources in map(_source_spec, args.main):
        scores, timing = _joined(sources, args.first, args.skip)
        table4[label] = scores
        print(f"### {label}\n\n{timing}.\n")
        print("\n".join(measurement_table(scores)) + "\n")
        if 2 <= scores.hard.sum() <= len(scores.hard) - 2:
            hard = {i for i, h in zip(scores.ids, scores.hard) if h}
            split = important_table({"the hard share (wider start)": subset(scores, hard),
                                     "the others": subset(scores, set(scores.ids) - hard)})
            print("\n".join(split[:-1]) + "\n")  # without the paper's row
        if scores.failures:
            print("Failures:\n\n" + "\n".join(failure_lines(scores)) + "\n")
    for label, sources in map(_source_spec, args.ablation):
        baseline = first_of_set.setdefault(_set_kind(sources[0]), label)
        if baseline != label:
            baselines[label] = baseline
        scores, timing = _joined(sources, args.first, args.skip)
        table4[label] = scores
        print(f"- {label}: {timing}")
    print("\n### The 7 important measurements (Table 4 form)\n")
    print("\n".join(important_table(table4, baselines)))
    if args.per_measurement:
        for label, baseline in baselines.items():
            print(f"\n### {label} against {baseline}, measurement by measurement\n")
            print("\n".join(paired_measurement_table(table4[label], table4[baseline])))


def spread(args) -> None:
    """The calibrated ± (:mod:`bodyfit.fitter.fit.spreads`) on fits: the factors their
    subjects give (each measurement's quantile of |error| / answer cost), and how often the
    truth lies within the ± of bodyfit's own calibration (``fitter/data``) or of
    ``--calibration FILE``'s (a test of it on subjects it was not made from), and within
    the fits' own reported spreads. ``--write FILE`` writes the run's factors as a
    calibration. (On the subjects it is made from, a calibration holds the truth for its
    coverage by construction, and so would each subject left out of it: the quantile's
    rank does not depend on the errors.) Last, how well a fit's answer cost and its
    reported spread rank the subjects by their errors."""
    own, tested = _tested_calibration(args.calibration)
    scores, _ = _joined([Path(source) for source in args.sources], args.first, args.skip)
    costs = scores.answer_costs
    if len(costs) < 2 or np.isnan(costs).any():
        sys.exit("spread: needs at least 2 fits, each with its answer cost recorded")
    made = SpreadCalibration.made_from(scores.errors, costs,
                                       "python -m bench.accuracy " + " ".join(args.argv))
    absolute = np.abs(scores.errors)
    columns = {f"{tested} calibration ({own.subjects} subjects)": np.mean(
                   absolute <= np.array([list(own.spreads(c).values()) for c in costs]), axis=0),
               "the same, unscaled (its ± at its median cost)": np.mean(
                   absolute <= np.array(list(own.spreads(own.median_cost).values())), axis=0),
               "the fits' reported spreads": np.mean(absolute <= scores.spreads, axis=0)}
    print(f"{'+'.join(args.sources)}, {len(costs)} subjects; answer cost (weighted mm) "
          f"median {np.median(costs):.1f}, {costs.min():.1f}-{costs.max():.1f} ({tested} "
          f"calibration's median {own.median_cost:.1f})\n\n"
          f"| measurement | these fits' factor (mm per weighted mm) | {tested} | truth within: "
          + " | ".join(columns) + " |\n|---|---|---|" + "---|" * len(columns))
    for j, (key, (_, label)) in enumerate(MEASUREMENTS.items()):
        print(f"| {key} {label} | {made.per_cost[key]:.3f} | {own.per_cost[key]:.3f} | "
              + " | ".join(f"{share[j]:.0%}" for share in columns.values()) + " |")
    shown = [KEYS.index(key) for key in KEYS if key != "O"]  # the given stature: always ~0
    print("| all but O (the given stature) | | | "
          + " | ".join(f"{share[shown].mean():.1%}" for share in columns.values()) + " |")
    if len(costs) >= 3:  # does a fit's answer cost, or its spread, rank subjects by error?
        scaled = (absolute / np.sqrt(np.mean(absolute ** 2, axis=0)))[:, shown].ravel()
        ranks = {"its answer cost": np.repeat(costs, len(shown)),
                 "its reported spread": (scores.spreads[:, shown]
                                         / np.median(scores.spreads[:, shown], axis=0)).ravel()}
        print("\nSpearman's rank correlation of a subject's |error| (each measurement's divided "
              "by its RMS, all but O pooled) with "
              + "; with ".join(f"{name}: {stats.spearmanr(scaled, values)[0]:+.2f}"
                               for name, values in ranks.items()))
    if args.write:
        write_text(Path(args.write), json.dumps(made.as_json(), indent=2) + "\n")
        print(f"\nwrote {args.write}")



def _tested_calibration(path: str | None) -> tuple[SpreadCalibration, str]:
    """The calibration ``spread`` tests, with its name for the table: bodyfit's own, or
    the one in the file ``path`` (exits with one line if it is not a readable one)."""
    if path is None:
        return bodyfit_calibration(), "bodyfit's"
    try:
        return read_calibration(Path(path).read_text()), f"{path}'s"
    except (OSError, ValueError, KeyError) as error:
        sys.exit(f"{path}: not a readable spread calibration ({error})")



def figures(args) -> None:
    """Fig. 12 (error per generation) and Figs. 16-17 (bodies coloured by distance)."""
    model = load_model()
    folder = Path(args.set)
    runs = {label: folder / "runs" / name for label, name in
            (spec.split("=", 1) for spec in args.curve)}
    generations = [g for g in (1, 2, 3, 5, 8, 12, 18, 25, 35, 50, 70, 100, 125, 150, 200)
                   if g < args.generations] + [args.generations]
    bodies = read_bodies(model, folder)
    ids = subject_ids(len(bodies.sex), bodies.sex)
    common = {s for s in ids if all((run / s / "run.json").exists() for run in runs.values())}
    curves = {}
    for label, run in runs.items():
        curves[label] = errors_per_generation(model, bodies, folder, run, generations,
                                              common).mean(axis=(0, 2))
        print(f"{label}: " + ", ".join(f"g{g} {e:.1f}" for g, e in zip(generations,
                                                                      curves[label])))
    chart = line_chart(curves, f"{args.title}, {len(common)} subjects: the answer so far",
                       "generation",
                       "7 important, mean abs. error (mm)",
                       x_values={label: generations for label in curves})
    write_image(Path(args.docs) / "accuracy_error_per_generation.png", chart)
    shown = [runs[label] for label in args.meshes]
    candidates = [i for i, s in enumerate(ids) if s in common]
    measurer = Measurer.from_model(model)
    waist = np.array([measurer.measure(bodies.vertices[i])["E"] for i in candidates])
    rows = []
    for name, q in (("thin", 0.03), ("normal", 0.5), ("heavy", 0.97)):
        index = candidates[int(np.argsort(waist)[int(q * (len(waist) - 1))])]
        panel = distance_panel(model, bodies.vertices[index],
                               [fitted_rest_body(model, run, ids[index]) for run in shown])
        caption = np.full((28, panel.shape[1], 3), 255, np.uint8)
        label = (f"{name}: {ids[index]}, waist {waist[candidates.index(index)]:.0f} mm - "
                 "truth | " + " | ".join(args.meshes))
        cv2.putText(caption, label, (8, 20),
                    cv2.FONT_HERSHEY_SIMPLEX, 0.5, (0, 0, 0), 1, cv2.LINE_AA)
        rows.append(np.vstack([caption, panel]))
    width = max(r.shape[1] for r in rows)
    rows = [np.hstack([r, np.full((r.shape[0], width - r.shape[1], 3), 255, np.uint8)])
            for r in rows]
    write_image(Path(args.docs) / "accuracy_meshes.png",
                np.vstack([*rows, colour_bar(width)]))
    print(f"wrote {args.docs}/accuracy_error_per_generation.png, {args.docs}/accuracy_meshes.png")


def silhouettes(args) -> None:
    """Markdown: each segmenter's silhouettes of a room set's photos against their truth
    masks (:func:`.outlines.outline_errors`), those whose height is off
    (:func:`.outlines.height_error`), and the photos it refused."""
    folder = Path(args.set)
    with open(folder / "subjects.csv", newline="") as table:
        subjects = [row["id"] for row in csv.DictReader(table)][:args.first]
    print(f"{folder}, {len(subjects)} subjects: wrong pixels per outline pixel, mean "
          f"(median); the silhouettes whose height is off by over {HEIGHT_OFF_SHARE:.0%}\n")
    print("| segmenter | view | photos | refused | wrong pixels per outline pixel | height off |")
    print("|---|---|---|---|---|---|")
    for segmenter in args.segmenter:
        for view in ("front", "side"):
            wrong, off, refused = [], [], 0
            for subject in subjects:
                truth = cv2.imread(str(folder / subject / f"truth_{view}.png"),
                                   cv2.IMREAD_GRAYSCALE) > 127
                plate = folder / subject / f"plate_{view}.jpg" if args.plates else None
                try:
                    mask = photo_silhouette(folder / subject / f"{view}.jpg",
                                            background_path=plate, segmenter=segmenter)
                except UserError:
                    refused += 1
                    continue
                wrong.append(outline_errors(mask, truth)[1])
                error = height_error(mask, truth)
                if abs(error) > HEIGHT_OFF_SHARE:
                    off.append(f"{subject} {error:+.1%}")
            shown = f"{np.mean(wrong):.3f} ({np.median(wrong):.3f})" if wrong else "-"
            print(f"| {segmenter} | {view} | {len(subjects)} | {refused} | {shown} | "
                  f"{len(off)}{': ' + ', '.join(off) if off else ''} |")


def parse(argv: list[str]) -> tuple[argparse.Namespace, list[str]]:
    """The command's arguments, and the fitter batch options after ``--`` (``fit``)."""
    parser = argparse.ArgumentParser(prog="python -m bench.accuracy",
                                     description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)
    p = sub.add_parser("make", help="draw and photograph a subject set")
    p.add_argument("set", help="the set's folder")
    p.add_argument("--kind", choices=KINDS, default="in-space")
    p.add_argument("--count", type=int, default=200)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--pool-per-sex", type=int, default=400,
                   help="out-of-space: bodies the population sampler's linear map is fitted on")
    p.add_argument("--bodies-only", action="store_true")
    p.add_argument("--first", type=int, metavar="N",
                   help="photograph only the first N subjects (the others later, by make again)")
    p.add_argument("--rooms", action="store_true",
                   help="dress the subjects and photograph them in the rooms of bench/data/rooms "
                   "(the same bodies and camera places as the plain set of this kind, count and "
                   "seed)")
    p.add_argument("--workers", type=int, help="processes photographing (default: the cores)")
    p = sub.add_parser("fit", help="calib capture, then fitter batch on a set")
    p.add_argument("set")
    p.add_argument("name", help="the run's name (SET/runs/NAME)")
    p.add_argument("--camera", choices=("calibrated", "none"), default="calibrated",
                   help="none: fitter batch without --camera (a typical phone assumed)")
    p.add_argument("--first", type=int, help="fit only the set's first N subjects (N even: "
                   "half women, half men)")
    p.add_argument("--skip", type=int, default=0, metavar="I",
                   help="with --first N: leave out the first I subjects (fitted by another "
                   "run, e.g. in an earlier session), fit rows I to N - 1; the run's summary.csv "
                   "keeps the rows it had of other subjects")
    p.add_argument("--plates", action="store_true",
                   help="a room set's photos with their background plates (plate_front.jpg, "
                   "plate_side.jpg: the empty room from a tripod)")
    p = sub.add_parser("keep", help="merge a run into a setting kept in git")
    p.add_argument("set")
    p.add_argument("name", help="the run's name (SET/runs/NAME)")
    p.add_argument("--setting", help="the kept setting (default: the run's name)")
    p.add_argument("--to", default=str(KEPT_DIR),
                   help="folder of kept settings: TO/<set kind>/SETTING.csv (default: %(default)s)")
    window = argparse.ArgumentParser(add_help=False)
    window.add_argument("--first", type=int, help="the set's first N subjects only")
    window.add_argument("--skip", type=int, default=0, metavar="I",
                        help="with --first N: rows I to N - 1 only (e.g. the subjects held "
                        "out from a choice made on the others)")
    sources = "kept settings (docs/accuracy-runs/KIND/SETTING.csv) or run folders (SET/runs/NAME)"
    p = sub.add_parser("report", parents=[window], help="Markdown tables of settings")
    p.add_argument("--main", action="append", default=[], metavar="LABEL=SOURCE[+SOURCE]",
                   help=f"a setting in the full Table 3 form; sources: {sources}, joined")
    p.add_argument("--ablation", action="append", default=[], metavar="LABEL=SOURCE[+SOURCE]",
                   help="a setting in the Table 4 form only, paired with its set's first")
    p.add_argument("--per-measurement", action="store_true",
                   help="also each ablation against its set's first, measurement by "
                   "measurement, over the subjects both fitted")
    p = sub.add_parser("spread", parents=[window], help="the calibrated ± on a setting's fits: "
                       "their factors, how often the truth lies within")
    p.add_argument("sources", nargs="+", metavar="SOURCE", help=f"{sources}, joined")
    p.add_argument("--write", metavar="FILE",
                   help="write the fits' factors as a calibration (bodyfit's own: "
                   "fitter/data/spread_calibration.json)")
    p.add_argument("--calibration", metavar="FILE",
                   help="test this calibration (one `--write` made, e.g. from other rows) "
                   "instead of bodyfit's own")
    p = sub.add_parser("silhouettes", help="a room set's silhouettes against their truth masks")
    p.add_argument("set", help="a set made with make --rooms")
    p.add_argument("--first", type=int, help="its first N subjects only")
    p.add_argument("--segmenter", nargs="+", choices=SEGMENTERS, default=list(SEGMENTERS))
    p.add_argument("--plates", action="store_true",
                   help="each photo with its background plate (plate_front.jpg, "
                   "plate_side.jpg)")
    p = sub.add_parser("figures", help="error per generation; bodies coloured by distance")
    p.add_argument("set")
    p.add_argument("--curve", action="append", default=[], metavar="LABEL=RUN",
                   help="a run of SET drawn in the error-per-generation chart")
    p.add_argument("--meshes", nargs="+", default=[], metavar="LABEL",
                   help="the curves' runs whose fitted bodies are drawn")
    p.add_argument("--generations", type=int, default=150)
    p.add_argument("--title", default="in-space")
    p.add_argument("--docs", default="docs")
    batch_options = argv[argv.index("--") + 1:] if "--" in argv else []
    args = parser.parse_args(argv[:argv.index("--")] if "--" in argv else argv)
    if args.command != "fit" and batch_options:
        parser.error("only fit takes fitter batch options after --")
    if getattr(args, "skip", 0) and not getattr(args, "first", None):
        parser.error("--skip needs --first (rows --skip to --first - 1)")
    args.argv = argv  # recorded by what it writes (spread --write)
    return args, batch_options


def main(argv: list[str] | None = None) -> None:
    warp.config.log_level = warp.LOG_WARNING  # no initialisation banner in the Markdown
    args, batch_options = parse(sys.argv[1:] if argv is None else argv)
    if args.command == "fit":
        fit(args, batch_options)
    else:
        {"make": make, "keep": keep, "report": report, "spread": spread,
         "silhouettes": silhouettes, "figures": figures}[args.command](args)
