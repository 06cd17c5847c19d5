"""`fitter`: fit the body model to a person's photos, measure meshes, build the model.

The help says only what exists. User errors, usage errors included, print one line,
``fitter: error: ...``, and exit with status 2. `fitter batch` exits with status 1 when
it ran but some subjects were not fitted (its failures.csv says why).
"""

from __future__ import annotations

import argparse
import logging
import os
import sys
import time
from pathlib import Path

from bodyfit.calib.segmenters import SEGMENTER_HELP, SEGMENTERS
from bodyfit.common.command_line import OneLineArgumentParser, bodyfit_version
from bodyfit.common.errors import UserError
from bodyfit.common.files import check_input_file
from bodyfit.fitter.fit.facing import SIDE_FROM, side_text
from bodyfit.fitter.fit.mass_volume import MASS_SCALINGS
from bodyfit.fitter.fit.pitch import PITCHES, pitch_text

__all__ = ["main"]

logger = logging.getLogger("bodyfit")


def _add_silhouette_options(parser: argparse.ArgumentParser) -> None:
    """How the photos' silhouettes are taken: background plates and the segmenter."""
    parser.add_argument("--background-front", metavar="PHOTO",
                        help="background plate: the front view without the person")
    parser.add_argument("--background-side", metavar="PHOTO",
                        help="background plate, side view")
    parser.add_argument("--segmenter", choices=SEGMENTERS, help=SEGMENTER_HELP)


def _add_fit_options(parser: argparse.ArgumentParser, batch: bool) -> None:
    """`fitter run`'s options; `fitter batch` takes the same fit options for every subject
    (its table gives each subject's photos, stature, masks and optionally camera, sex and
    weights)."""
    if batch:
        parser.add_argument("--config", type=Path, metavar="run.json",
                            help="the settings of a previous run's run.json (not its "
                                 "person; the options given here override them)")
    else:
        parser.add_argument("--config", type=Path, metavar="run.json",
                            help="repeat a previous run: its inputs and settings from its "
                                 "run.json (the options given here override them)")
    parser.add_argument("--method", choices=("bodyfit", "thorough", "paper"),
                        help="bodyfit (default: the local solver from the mean body, "
                             "stature-conditioned, bodyfit weights, the camera solved with "
                             "the body), thorough (the population search that was the "
                             "default before: CMA-ES, 99,000 candidates, minutes a person) "
                             "or paper (the paper's method exactly: its GA 30 x 25, Table 2 "
                             "weights, person-to-model matching); the options below override "
                             "single settings")
    if not batch:
        parser.add_argument("--front", metavar="PHOTO", help="front photo, A-pose (required "
                            "without --config)")
        parser.add_argument("--side", metavar="PHOTO",
                            help="side photo from the person's left or right, arms hanging down")
        parser.add_argument("--height-cm", type=float, metavar="CM",
                            help="the person's stature, centimetres")
        parser.add_argument("--mass-kg", type=float, metavar="KG",
                            help="the person's body mass, kilograms (optional): the girths "
                                 "are scaled to it (--mass-scaling), and the measurements' "
                                 "prior reads it with the stature and sex")
        parser.add_argument("-o", "--output", type=Path, metavar="OUT",
                            help="output folder (created; must be empty unless --overwrite)")
    parser.add_argument("--camera", metavar="camera.json",
                        help="the calibrated camera (calib capture): the photos are "
                             "undistorted and fitted through it"
                             + ("; for the rows without a camera" if batch else ""))
    parser.add_argument("--projection", choices=("orthographic", "pinhole"),
                        help="pinhole: the camera of --camera, or without it a typical phone "
                             "camera (70 degrees across the long side); "
                             "orthographic: the paper's, each view scaled from the stature "
                             "(default pinhole; --method paper: orthographic)")
    parser.add_argument("--placement-rounds", type=int, metavar="N",
                        help="pinhole: place the camera anew from the search's best body so "
                             "far N times, evenly spaced (default 2; 0: from the mean body "
                             "only)")
    if not batch:
        parser.add_argument("--mask-front", metavar="PNG", help="your own front silhouette "
                            "(white person on black, of the undistorted upright photo)")
        parser.add_argument("--mask-side", metavar="PNG", help="your own side silhouette")
    _add_silhouette_options(parser)
    parser.add_argument("--no-check", dest="check", action="store_const", const=False,
                        help="skip the photography check (fitter check) before the fit")
    parser.add_argument("--sex", choices=("female", "male", "unknown"),
                        help="the person's sex, read by the learned start (default "
                             "unknown)"
                             + ("; for the rows without a sex" if batch else ""))
    parser.add_argument("--side-from", choices=SIDE_FROM,
                        help="which side of the person the side photo shows (left: the "
                             "person faces the image's left); auto (default): told by the "
                             "feet, and where they do not tell, both fitted and the lower "
                             "cost kept" + ("; for every row" if batch else ""))
    parser.add_argument("--weights", metavar="PRESET|FILE.toml",
                        help="cost weights: bodyfit (Table 2 without the top and bottom "
                             "terms, the head and neck 4; the default), paper (Table 2; "
                             "the paper method's), "
                             "uniform, lower-body, or a .toml file"
                             + ("; for the rows without weights" if batch else ""))
    parser.add_argument("--weight", action="append", metavar="NAME=VALUE",
                        help="override one weight, e.g. waist=8 or view.side=3 (repeatable)")
    parser.add_argument("--matching",
                        help="boundary matching direction: model_to_person (default), "
                             "person_to_model (the paper's) or symmetric (both)")
    parser.add_argument("--vertical-anchor", choices=("centroid", "extremes"),
                        help="how candidates are shifted vertically onto the person: "
                             "centroid (the paper's moments) or extremes (the middle of the "
                             "top and bottom rows; the default)")
    parser.add_argument("--side-arms", choices=("down", "hidden"),
                        help="the side view's candidates: down (default) with their arms "
                             "hanging down, as the side photo shows them; hidden: without "
                             "arms (for a side photo whose arms hide within the torso)")
    parser.add_argument("--optimizer", choices=("ga", "cmaes"),
                        help="the population search's optimiser: cmaes, CMA-ES (default); "
                             "ga, the paper's genetic algorithm")
    parser.add_argument("--population", type=int, help="the population search's candidates "
                        "per generation (default 30)")
    parser.add_argument("--generations", type=int,
                        help="the population search's generations (default 150; --method "
                             "paper: 25)")
    parser.add_argument("--components", type=int,
                        help="shape components of the population search (default 20, as "
                             "the paper; up to 60; the local solver solves for 40)")
    parser.add_argument("--seed", type=int, help="random seed (default 0)"
                        + ("; every subject uses it" if batch else ""))
    parser.add_argument("--searches", type=int,
                        help="independent population searches (seeds SEED, SEED+1, ...) whose "
                             "answers are averaged (default 0: none, the local solver starts "
                             "from the mean body; --method thorough: 2, paper: 1)")
    parser.add_argument("--iterations", type=int,
                        help="the local solver's iterations at most, after the searches "
                             "(default 40, fewer where the cost stops falling; 10: the default "
                             "before; 0: none; --method thorough and paper: 0)")
    parser.add_argument("--placements-within", type=int, metavar="N",
                        help="the local solver places the cameras anew from its body 3 "
                             "times, evenly within its first N iterations (default 10; 0: "
                             "through all of them, the default before)")
    parser.add_argument("--start", choices=("mean", "learned"),  # local_solver.SOLVER_STARTS
                        help="where the local solver starts without a search: learned (the "
                             "default: the body a regression reads off the silhouettes; with "
                             "--iterations 0, the answer) or mean (the mean body)")
    parser.add_argument("--arms-lower-deg", type=float, metavar="DEG",
                        help="the arms' lowest abduction from the rest A-pose (default -25: "
                             "17 degrees from hanging; -10: the default before, and "
                             "--method thorough's and paper's)")
    parser.add_argument("--elbows", choices=("fitted", "rest"),  # local_solver.ELBOWS
                        help="the local solver's elbows: fitted (the default: one flexion "
                             "for both arms and photos, solved with the body) or rest (the "
                             "model's rest pose's, about 43 degrees)")
    parser.add_argument("--hands", choices=("fitted", "rest"),  # local_solver.HANDS
                        help="the front photo's hands: fitted (the default: each hand's "
                             "twist about its forearm, from palm in to palm forward, solved "
                             "with the body) or rest (the model's rest pose's, palms in; "
                             "the default before)")
    parser.add_argument("--pitch", choices=PITCHES,
                        help="the cameras' pitch: searched (the default: the local solver "
                             "run again with each camera pitched 4 degrees down and up, the "
                             "best-scored answer kept; about twice the time) or level (both "
                             "cameras level, the default before)")
    parser.add_argument("--shape-prior", type=float, metavar="SHARE",
                        help="the local solver's Gaussian prior on the shape grows by this "
                             "share of the silhouettes' misfit (mm^2 of cost per sigma^2 "
                             "of each shape component per mm^2 of misfit; default "
                             "0.00125; 0: a fixed weak prior, the default before)")
    parser.add_argument("--beta-limit", type=float, metavar="SIGMA",
                        help="the shape components span +-SIGMA standard deviations (the "
                             "search's and the local solver's bounds, and the canvases' "
                             "room; default 3, the paper's)")
    parser.add_argument("--measurement-prior", choices=("ansur", "none"),  # PRIORS
                        help="ansur (the default): each measurement weighed against what "
                             "ANSUR II's adults of the stature, sex (and --mass-kg) measure, "
                             "by its ±, so a fit that matched the silhouettes poorly leans "
                             "on them; none: the fit's own (the default before; --method "
                             "thorough's and paper's)")
    parser.add_argument("--mass-scaling", choices=MASS_SCALINGS,
                        help="with --mass-kg: girths (the default) scales the "
                             "circumferences so that the fitted body's volume at 1.0 kg/L "
                             "is the mass, before the prior; none: the prior alone reads "
                             "the mass (the default before; --method thorough's and paper's)")
    parser.add_argument("--refine-components", type=int, metavar="K",
                        help="after the searches, refine their answer with CMA-ES over the "
                             "first K components, --refinements of them, averaged (more "
                             "than --components; default 40, none when --components is 40 "
                             "or more; 0: none; --method paper: 0)")
    parser.add_argument("--refine-generations", type=int,
                        help="each refinement's generations (default 500)")
    parser.add_argument("--refinements", type=int,
                        help="refinements (seeds SEED, SEED+1, ...) whose answers are averaged "
                             "(default 6)")
    parser.add_argument("--free-stature", action="store_true", default=None,
                        help="search the first shape component like the others (the paper) "
                             "instead of solving it so every candidate stands as tall as the "
                             "person")
    parser.add_argument("--device", help="cpu (default) or cuda:0"
                        + ("; cuda: one worker per GPU" if batch else ""))
    parser.add_argument("--threads", type=int,
                        help="CPU threads scoring each generation (default: one per core"
                             + ("; fitter batch: the cores shared among the local workers"
                                if batch else "") + "; the result does not depend on it)")
    if not batch:
        parser.add_argument("--overwrite", action="store_true",
                            help="write into a non-empty OUT")


def _build_parser() -> argparse.ArgumentParser:
    parser = OneLineArgumentParser(
        prog="fitter",
        description="bodyfit: a 3D body and 16 tape measurements from a front and a side "
                    "photo (fitter run); draw and measure bodies of the model. Lengths in "
                    "files are metres (meshes) and millimetres (measurements).")
    parser.add_argument("--version", action="version", version=f"bodyfit {bodyfit_version()}")
    parser.add_argument("-q", "--quiet", action="store_true", help="print only errors")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    model = sub.add_parser("model", help="build or inspect the body model")
    model_sub = model.add_subparsers(dest="model_command", required=True, metavar="ACTION")
    build = model_sub.add_parser(
        "build", help="build the body model from Anny into the cache (about 4 minutes; "
                      "bodyfit ships a default model, so this is for other settings)")
    build.add_argument("--components", type=int, default=60,
                       help="PCA shape components to store (default 60; fitting uses 40, "
                            "a population search 20)")
    build.add_argument("--samples", type=int, default=3000,
                       help="bodies in the sample, half men, half women (default 3000)")
    build.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    build.add_argument("--girth-spread", type=float, default=1.0, metavar="FACTOR",
                       help="draw the sample's circumferences FACTOR times as widely as "
                            "ANSUR II's soldiers' (default 1)")
    build.add_argument("-o", "--output", type=Path,
                       help="write the model here instead of the cache (.npz); "
                            "fitter/data/body_model.npz is the model bodyfit ships")
    model_sub.add_parser("info", help="print which model is used and how it was built")
    train = model_sub.add_parser(
        "train-start", help="train the learned start (--start learned) for the model in use "
                            "on bodies it draws and photographs (about 10 minutes) into the "
                            "cache; bodyfit ships one for its default model")
    train.add_argument("--bodies", type=int, default=6000,
                       help="bodies photographed front and side (default 6000; a tenth "
                            "held out to measure it)")
    train.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    train.add_argument("-o", "--output", type=Path,
                       help="write the weights here instead of the cache (.npz); "
                            "fitter/data/learned_start.npz is the start bodyfit ships")

    demo = sub.add_parser(
        "demo", help="the main job on a synthetic person: photos and board photos through "
                     "one phone camera, calibration, fitter run --camera, measured vs true (mm)",
        description="Photograph a synthetic person (front, A-pose; side, arms down) and a "
                    "chessboard through one synthetic phone camera with lens distortion, "
                    "calibrate it as calib capture does, fit the person as fitter run "
                    "--camera does, and print the 16 fitted measurements against the true "
                    "ones (mm). Writes the photos, camera.json, truth.json and the fit "
                    "(DIR/fit) into DIR (docs/fitter.md, The demo).")
    demo.add_argument("-o", "--output", type=Path, default=Path("out/demo"), metavar="DIR",
                      help="output folder (default out/demo; the demo's earlier files there "
                           "are replaced)")
    demo.add_argument("--seed", type=int, default=0,
                      help="which body, camera place and board poses are drawn (default 0)")
    demo.add_argument("--method", choices=("bodyfit", "thorough", "paper"),
                      help="fitter run's --method (default bodyfit)")

    check = sub.add_parser(
        "check", help="the photography check: is each photo one the fit can measure? "
                      "(fitter run runs it first)",
        description="Check a front and a side photo before fitting them: one person, the "
                    "whole body in the frame with a margin, large enough, upright, the "
                    "camera level at a sensible height; the front facing the camera, arms "
                    "and feet apart (an A-pose); the side turned 90 degrees, arms hanging "
                    "down. Prints what it read of each photo; each problem is one line that "
                    "says what to do, and the exit status is 2. Loose clothing is a warning "
                    "(docs/fitter.md, The photography check).")
    check.add_argument("front", metavar="FRONT", help="front photo, A-pose")
    check.add_argument("side", metavar="SIDE", help="side photo, arms hanging down")
    check.add_argument("--camera", metavar="camera.json",
                       help="the calibrated camera: the photos are undistorted first")
    _add_silhouette_options(check)
    check.set_defaults(segmenter="auto")

    run = sub.add_parser(
        "run", help="fit the body model to a person's front and side photos: mesh (m), "
                    "16 measurements (mm), convergence plot, run record",
        description="Fit bodyfit's body model to a front photo (A-pose) and a side photo "
                    "(arms hanging down) on a plain backdrop or in a room (--segmenter), "
                    "after the photography check (fitter check; --no-check skips it). "
                    "Cameras: with --camera, "
                    "the calibrated pinhole camera, the person's distance solved from the "
                    "stature; without, see --projection (docs/fitter.md, Cameras).")
    _add_fit_options(run, batch=False)

    batch = sub.add_parser(
        "batch", help="fit every subject of a table (SUBJECTS.csv) as fitter run does, on "
                      "local worker processes or a Ray cluster; resumable",
        description="Fit every row of SUBJECTS.csv (columns id, front, side, height_cm; "
                    "optional camera, mask_front, mask_side, background_front, "
                    "background_side, sex, weights; relative paths "
                    "are relative to the CSV's folder) as fitter run does, into OUT/<id>/, "
                    "with OUT/summary.csv, OUT/failures.csv and OUT/batch.json. Subjects "
                    "already fitted in OUT are kept; a subject that fails is recorded and "
                    "the batch goes on. Exit status 0: every subject fitted; 1: some "
                    "failed; 2: bad input (docs/batch.md).")
    batch.add_argument("subjects", type=Path, metavar="SUBJECTS.csv",
                       help="the subjects table, one row per subject")
    batch.add_argument("-o", "--output", type=Path, metavar="OUT", required=True,
                       help="output folder (created; a rerun into it resumes the batch)")
    batch.add_argument("--workers", type=int, metavar="N",
                       help="subjects fitted at once (default: one per CPU core, or per "
                            "GPU with --device cuda; with --ray, as many as the cluster's "
                            "resources hold)")
    batch.add_argument("--ray", action="store_true",
                       help="run the subjects as Ray tasks (pip install 'bodyfit[ray]'): "
                            "on a local Ray instance, or on --ray-address's cluster")
    batch.add_argument("--ray-address", metavar="ADDR",
                       help="join this Ray cluster (e.g. ray://head:10001 or auto; implies "
                            "--ray); inputs and OUT must lie on a file system every node "
                            "sees at the same path")
    batch.add_argument("--cpus-per-worker", type=float, metavar="C",
                       help="with --ray: CPUs Ray reserves per worker (default 1)")
    batch.add_argument("--gpus-per-worker", type=float, metavar="G",
                       help="with --ray and --device cuda: GPUs per worker, a fraction when "
                            "several fit on one GPU (default 1)")
    batch.add_argument("--retry-failed", action="store_true",
                       help="fit again the subjects OUT/failures.csv lists (a rerun skips "
                            "them otherwise)")
    batch.add_argument("--skip-bad-rows", action="store_true",
                       help="skip the table's bad rows, each reported, instead of stopping")
    _add_fit_options(batch, batch=True)

    serve = sub.add_parser(
        "serve", help="the studio page: photograph, check and measure people from a phone "
                      "or this computer's browser",
        description="A web page to measure people: their photos taken on a phone, checked "
                    "at once, fitted on this computer; the people and their fits kept in "
                    "DATA (docs/serve.md).")
    serve.add_argument("--host", default="127.0.0.1",
                       help="the address to listen on (default 127.0.0.1: this computer "
                            "only; 0.0.0.0: the studio's network, with an access token)")
    serve.add_argument("--port", type=int, default=8000, help="the port (default 8000)")
    serve.add_argument("--data", type=Path, default=Path("bodyfit-studio"), metavar="DIR",
                       help="the folder of the people, fits and photos (default "
                            "./bodyfit-studio; created)")
    serve.add_argument("--workers", type=int, metavar="N",
                       help="fits at once (default: one per CPU core)")

    measure = sub.add_parser("measure", help="the 16 measurements (mm) of a mesh in the "
                                             "model's topology (.obj/.ply)")
    measure.add_argument("mesh", type=Path, help="mesh file, .obj or .ply")
    measure.add_argument("--units", choices=("m", "cm", "mm"), default="m",
                         help="length unit of the mesh file (default m)")
    measure.add_argument("-o", "--output", type=Path,
                         help="write JSON here (and CSV beside it); default: print only")
    return parser


def _cmd_model_build(args) -> None:
    from tqdm.contrib.logging import logging_redirect_tqdm

    from bodyfit.common.files import check_writable_dir
    from bodyfit.fitter.model.cache import model_path
    from bodyfit.fitter.model_build.body_sample import SamplingSettings
    from bodyfit.fitter.model_build.builder import ModelBuildSettings, build_and_save

    settings = ModelBuildSettings(components=args.components, samples=args.samples,
                                  seed=args.seed,
                                  sampling=SamplingSettings(girth_spread=args.girth_spread))
    settings.validate()
    path = args.output or model_path()
    if path.suffix != ".npz":
        raise UserError(f"-o takes a .npz path, got {path}")
    check_writable_dir(path.parent)
    with logging_redirect_tqdm():
        model = build_and_save(settings, path, progress=None if not args.quiet else False)
    t = model.metadata["timings_s"]
    print(f"built the body model in {t['total']:.0f} s: {model.num_vertices} vertices, "
          f"{model.num_components} components, {len(model.sample_sex)} bodies")
    print(f"wrote {path}")


def _cmd_model_train_start(args) -> None:
    from tqdm import tqdm

    from bodyfit.common.files import check_writable_dir
    from bodyfit.fitter.fit.learned_start import trained_start_path
    from bodyfit.fitter.model.cache import load_model
    from bodyfit.fitter.training.start_training import TrainingSettings, train_start

    model = load_model()
    settings = TrainingSettings(bodies=args.bodies, seed=args.seed)
    settings.validate(model)
    path = args.output or trained_start_path()
    if path.suffix != ".npz":
        raise UserError(f"-o takes a .npz path, got {path}")
    check_writable_dir(path.parent)
    t0 = time.perf_counter()
    with tqdm(total=settings.bodies, unit="body", disable=args.quiet or None) as progress:
        start = train_start(model, settings, progress)
    start.save(path)
    held = start.metadata["held_out"]
    print(f"trained the learned start on {settings.bodies} bodies in "
          f"{time.perf_counter() - t0:.0f} s; on the {held['bodies']} held out: the 7 "
          f"important measurements {held['important_mean_abs_mm']:.1f} mm, components "
          f"{held['components_rms_sigma']:.2f} sigma, angles {held['angles_rms_deg']:.1f} "
          f"degrees (rms)")
    print(f"wrote {path}")


def _cmd_model_info(args) -> None:
    from bodyfit.fitter.fit.learned_start import (active_start, active_start_path,
                                                  trained_start_path)
    from bodyfit.fitter.model.cache import active_model_path, load_model, model_path

    t0 = time.perf_counter()
    model = load_model()
    load_s = time.perf_counter() - t0
    meta = model.metadata
    path = active_model_path()
    origin = "built by you" if path == model_path() else "shipped with bodyfit"
    print(f"body model ({origin}): {path} ({path.stat().st_size / 1e6:.1f} MB, "
          f"loaded in {load_s * 1000:.0f} ms)")
    print(f"  {model.num_vertices} vertices, {len(model.faces)} faces, "
          f"{model.num_components} components ({meta['explained_variance']:.6f} of the "
          f"sample's variance)")
    print(f"  built from anny {meta['anny_version']} with {meta['settings']} "
          f"in {meta['timings_s']['total']:.0f} s")
    start_path = active_start_path()
    held = active_start(model).metadata["held_out"]
    origin = "trained by you" if start_path == trained_start_path() else "shipped with bodyfit"
    print(f"learned start ({origin}): {start_path}; on its {held['bodies']} held-out bodies "
          f"the 7 important measurements {held['important_mean_abs_mm']:.1f} mm")


def _cmd_demo(args) -> None:
    import shlex

    from bodyfit.fitter.demo.example import (DemoSettings, calibrate_scene, measurement_table,
                                             write_scene)
    from bodyfit.fitter.fit.person_fit import METHODS, check_learned_start, fit_work
    from bodyfit.fitter.fit.spreads import SPREAD_NOTES
    from bodyfit.fitter.model.cache import load_model
    from bodyfit.fitter.run.results import run_person

    model = load_model()
    check_learned_start(model, METHODS[args.method or "bodyfit"])
    scene = write_scene(model, args.output, DemoSettings(seed=args.seed))
    calibration, camera_path, coverage_path = calibrate_scene(scene)
    fx_true, fx = scene.camera.K[0, 0], calibration.camera.K[0, 0]
    print(f"calibrated the phone camera from {len(scene.board_photos)} board photos "
          f"({len(calibration.used_views)} used): fx {fx:.1f} px (true {fx_true:.1f}), "
          f"k1 {calibration.camera.dist[0]:+.3f} (true {scene.camera.dist[0]:+.3f}), "
          f"RMS {calibration.rms_px:.3f} px")
    # the fit is `fitter run` on the demo's files, with its defaults and its settings logic
    run_argv = ["run", "--front", str(scene.front), "--side", str(scene.side),
                "--height-cm", f"{scene.truth['O'] / 10:.1f}", "--camera", str(camera_path),
                "-o", str(args.output / "fit"), "--overwrite"]
    if args.method is not None:
        run_argv += ["--method", args.method]
    run_args = _build_parser().parse_args(run_argv)
    inputs, settings, output = _run_settings(run_args)
    fit, written = run_person(model, inputs, settings, output, run_args.overwrite,
                              progress=None if not args.quiet else False)
    result = fit.search
    print(f"fitted in {sum(fit.seconds.values()):.1f} s: {fit_work(settings, result)}, "
          f"{settings.projection}")
    print(_photos_line(fit))
    print("\n".join(measurement_table(fit.measurements, fit.spreads, scene.truth)))
    print(f"  ({SPREAD_NOTES[fit.spread_basis]})")
    print("wrote:")
    for path in (scene.front, scene.side, scene.board_photos[0].parent, camera_path,
                 coverage_path, scene.truth_file, *written):
        print(f"  {path}")
    print(f"fit the photos again by hand: fitter {shlex.join(run_argv)}")


def _photos_line(fit) -> str:
    """What was read of the photos besides the silhouettes, for the summary."""
    pitch = fit.photos.get("pitch_deg")
    return (f"  camera: {fit.photos['camera']}; the side photo shows "
            f"{side_text(fit.photos)}"
            + (f"; the cameras' pitch: {pitch_text(pitch)}" if pitch else ""))


def _run_settings(args):
    """(PersonInputs, FitSettings, output folder) of `fitter run`'s options: the defaults,
    or with --config the run.json's values, overridden by every option given."""
    import dataclasses

    from bodyfit.fitter.fit.person import PersonInputs
    from bodyfit.fitter.run.options import INPUT_OPTIONS, base_settings, fit_settings

    given = {k: v for k, v in vars(args).items() if v is not None}
    if args.config is None:
        missing = [f"--{k.replace('_', '-')}" for k in ("front", "side", "height_cm")
                   if k not in given] + ([] if args.output else ["-o"])
        if missing:
            raise UserError(f"fitter run needs {', '.join(missing)} (or --config run.json)")
    settings, config = base_settings(args.method, args.config)
    if config is None:
        inputs, output = PersonInputs(args.front, args.side, args.height_cm), args.output
    else:
        inputs, output = config.inputs, args.output or config.output
        if output is None:
            raise UserError(f"{args.config} records no output folder; give -o OUT")
    inputs = dataclasses.replace(inputs, **{k: given[k] for k in INPUT_OPTIONS if k in given})
    return inputs, fit_settings(settings, given), output


def _cmd_run(args) -> None:
    from bodyfit.fitter.fit.person_fit import fit_work
    from bodyfit.fitter.fit.spreads import SPREAD_NOTES
    from bodyfit.fitter.measure.measurements import MEASUREMENTS
    from bodyfit.fitter.model.cache import load_model
    from bodyfit.fitter.run.results import run_person

    try:
        inputs, settings, output = _run_settings(args)
        model = load_model()
        fit, written = run_person(model, inputs, settings, output, args.overwrite,
                                  progress=None if not args.quiet else False)
    except ValueError as exc:  # the kernels' argument and device errors, --matching
        raise UserError(str(exc)) from None
    for line in [*fit.photos.get("check_warnings", ()), fit.photos.get("fit_warning")]:
        if line:
            print(f"fitter: warning: {line}", file=sys.stderr)
    result = fit.search
    print(f"fitted in {sum(fit.seconds.values()):.1f} s: {fit_work(settings, result)}, "
          f"cost {result.cost:.1f} weighted mm")
    print(_photos_line(fit))
    for key, (_, label) in MEASUREMENTS.items():
        print(f"  {key} {label:<28} {fit.measurements[key]:8.1f} ± "
              f"{fit.spreads[key]:5.1f} mm")
    print(f"  ({SPREAD_NOTES[fit.spread_basis]})")
    print("wrote:")
    for path in written:
        print(f"  {path}")


def _cmd_check(args) -> int:
    from bodyfit.fitter.check.photos import failed_lines
    from bodyfit.fitter.fit.person import PersonInputs, checked_photos

    inputs = PersonInputs(args.front, args.side, float("nan"),  # the check reads no stature
                          camera=args.camera,
                          background_front=args.background_front,
                          background_side=args.background_side, segmenter=args.segmenter)
    verdicts = checked_photos(inputs)
    for verdict in verdicts:
        print(verdict.summary())
        for line in verdict.warnings:
            print(f"fitter: warning: {line}", file=sys.stderr)
    problems = failed_lines(verdicts)
    for line in problems:
        print(f"fitter: error: {line}", file=sys.stderr)
    if problems:
        return 2
    print("the photos pass the check")
    return 0


def _batch_engine(args, model_sha256: str):
    """The engine of `fitter batch`'s options: local processes, or Ray."""
    import dataclasses

    from bodyfit.fitter.batch.engines import LocalEngine, WorkerSetup
    from bodyfit.kernels import cpu_threads

    device = args.device or "cpu"
    setup = WorkerSetup(model_sha256,
                        log_level=logging.ERROR if args.quiet else logging.WARNING)
    if args.ray or args.ray_address:
        from bodyfit.fitter.batch.ray_engine import RayEngine

        cpus = args.cpus_per_worker or 1.0
        gpus = args.gpus_per_worker if args.gpus_per_worker is not None else (
            1.0 if device.startswith("cuda") else 0.0)
        setup = dataclasses.replace(setup, threads=max(1, int(cpus)))
        return RayEngine(args.ray_address, args.workers, setup, cpus, gpus)
    if args.cpus_per_worker is not None or args.gpus_per_worker is not None:
        raise UserError("--cpus-per-worker and --gpus-per-worker are for --ray")
    if device.startswith("cuda"):
        import warp

        warp.init()
        count = warp.get_cuda_device_count()
        devices = tuple(f"cuda:{i}" for i in range(count)) if device == "cuda" else (device,)
        if count == 0 or not set(devices) <= {f"cuda:{i}" for i in range(count)}:
            raise UserError(f"--device {device}: this machine has {count} CUDA devices")
        setup = dataclasses.replace(setup, devices=devices)
        workers = len(devices) if args.workers is None else args.workers  # one per GPU
    else:
        workers = cpu_threads() if args.workers is None else args.workers  # one per core
    threads = max(1, cpu_threads() // max(1, workers))  # each worker's share of the cores
    return LocalEngine(workers, dataclasses.replace(setup, threads=threads))


def _batch_jobs(args):
    """(the subjects table, id -> job) of `fitter batch`'s options; every problem of the
    options or the table is a UserError here, before any work."""
    import dataclasses

    from bodyfit.calib.camera import load_camera
    from bodyfit.fitter.batch.job import subject_job
    from bodyfit.fitter.batch.subjects import BadRow, read_subjects
    from bodyfit.fitter.fit.person_fit import check_learned_start
    from bodyfit.fitter.model.cache import load_model
    from bodyfit.fitter.run.options import base_settings, fit_settings

    options = dict(vars(args))
    for name in ("camera", "background_front", "background_side", "weights"):
        value = options[name]
        if value is None or (name == "weights" and not value.endswith(".toml")):
            continue
        check_input_file(value, f"--{name.replace('_', '-')} {value}")
        options[name] = str(Path(value).absolute())
    if options["camera"]:
        load_camera(options["camera"])
    table = read_subjects(args.subjects)
    base, _ = base_settings(args.method, args.config)
    try:
        model = load_model()
        settings = fit_settings(base, options)
        settings.validate(model.num_components)
        check_learned_start(model, settings)
    except ValueError as exc:  # --matching
        raise UserError(str(exc)) from None
    jobs, bad_rows = {}, list(table.bad_rows)
    for row in table.rows:
        try:
            jobs[row.subject_id] = subject_job(row, base, options, args.output.absolute())
        except UserError as exc:  # the row's weights file
            bad_rows.append(BadRow(row.line, row.subject_id, str(exc)))
    table = dataclasses.replace(table, rows=[row for row in table.rows
                                             if row.subject_id in jobs],
                                bad_rows=sorted(bad_rows, key=lambda bad: bad.line))
    if table.bad_rows and not args.skip_bad_rows:
        more = len(table.bad_rows) - 1
        raise UserError(table.bad_rows[0].message(args.subjects)
                        + (f" (and {more} more bad row{'s' * (more > 1)})" if more else "")
                        + "; fix the table, or pass --skip-bad-rows to skip bad rows")
    return table, jobs


def _cmd_batch(args) -> int:
    import signal

    from tqdm.contrib.logging import logging_redirect_tqdm

    from bodyfit.common.files import check_writable_dir, file_sha256
    from bodyfit.fitter.batch.orchestration import run_batch
    from bodyfit.fitter.batch.tables import STATUSES
    from bodyfit.fitter.model.cache import active_model_path

    check_writable_dir(args.output)
    if args.output.exists() and not args.output.is_dir():
        raise UserError(f"output folder {args.output} is a file")
    table, jobs = _batch_jobs(args)
    engine = _batch_engine(args, file_sha256(active_model_path()))
    for bad in table.bad_rows:  # every check passed: the work starts
        print(f"fitter batch: skipping {bad.message(args.subjects)}", file=sys.stderr)

    def stop(signum, frame):  # `kill` (a scheduler's time limit) stops as Ctrl-C does
        raise KeyboardInterrupt

    previous_handler = signal.signal(signal.SIGTERM, stop)
    try:
        with logging_redirect_tqdm():
            result = run_batch(table, jobs, args.output, engine, args.retry_failed,
                               progress=None if not args.quiet else False,
                               command=["fitter", *args.argv])
    finally:
        signal.signal(signal.SIGTERM, previous_handler)
    counts = {status: result.count(status) for status in STATUSES}
    workers = f", {engine.workers} workers" if engine.workers else ""
    print(f"fitter batch: {len(result.rows)} subjects in {result.seconds:.1f} s "
          f"({engine.name}{workers}): "
          + ", ".join(f"{n} {status}" for status, n in counts.items() if n))
    print("wrote:")
    for path in result.written:
        print(f"  {path}")
    # 0 when every subject of the table is fitted; failures are in failures.csv
    return 0 if counts["fitted"] + counts["fitted earlier"] == len(result.rows) else 1


def _cmd_measure(args) -> None:
    from bodyfit.fitter.measure.measurements import MEASUREMENTS, Measurer
    from bodyfit.fitter.model.cache import load_model
    from bodyfit.fitter.output.mesh_io import read_mesh
    from bodyfit.fitter.output.result_files import write_measurements

    model = load_model()
    vertices = read_mesh(args.mesh, model.faces, args.units)
    values = Measurer.from_model(model).measure(vertices)
    for key, value in values.items():
        print(f"  {key} {MEASUREMENTS[key][1]:<28} {value:8.1f} mm")
    if args.output:
        if args.output.suffix.lower() != ".json":
            raise UserError(f"-o takes a .json path, got {args.output}")
        csv_path = write_measurements(args.output, {args.mesh.stem: values},
                                      {"command": "fitter measure", "mesh": str(args.mesh),
                                       "units": args.units})
        print(f"wrote {args.output} and {csv_path}")


def _lan_address() -> str:
    """This computer's address on its network (where a phone reaches it), or 127.0.0.1."""
    import socket

    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
        try:
            probe.connect(("10.255.255.255", 1))  # sends nothing: picks the route's address
            return probe.getsockname()[0]
        except OSError:
            return "127.0.0.1"


def _cmd_serve(args) -> int:
    import secrets
    import socket

    import uvicorn

    from bodyfit.common.files import check_writable_dir, file_sha256
    from bodyfit.fitter.batch.engines import WorkerSetup
    from bodyfit.fitter.model.cache import active_model_path
    from bodyfit.fitter.serve.app import create_app

    workers = args.workers or os.cpu_count() or 1
    if workers < 1:
        raise UserError(f"--workers must be at least 1, got {workers}")
    if not 1 <= args.port <= 65535:
        raise UserError(f"--port must be 1-65535, got {args.port}")
    check_writable_dir(args.data)
    try:
        args.data.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        raise UserError(f"--data {args.data}: cannot create it ({error.strerror}); choose "
                        "another folder") from None
    with socket.socket(socket.AF_INET6 if ":" in args.host else socket.AF_INET) as probe:
        try:
            probe.bind((args.host, args.port))
        except OSError as error:
            raise UserError(f"cannot listen on {args.host} port {args.port} ({error.strerror}):"
                            " is another fitter serve running? Choose another --port") from None
    local = args.host in ("127.0.0.1", "localhost", "::1")
    token = None if local else secrets.token_urlsafe(16)
    shown = args.host if local or args.host not in ("0.0.0.0", "::") else _lan_address()
    url = f"http://{shown}:{args.port}/" + ("" if token is None else f"?token={token}")
    app = create_app(args.data.resolve(), WorkerSetup(file_sha256(active_model_path())),
                     workers, token, None if token is None else url)
    print(f"bodyfit studio: {url}" + ("" if token is None else
                                      "  (the access link: give it only to the studio)"))
    print(f"  data: {args.data.resolve()}; {workers} fit(s) at once; Ctrl+C stops")
    uvicorn.run(app, host=args.host, port=args.port, log_level="warning")
    return 0


def main(argv: list[str] | None = None) -> int:
    try:
        args = _build_parser().parse_args(argv)
    except SystemExit as stop:  # --help, --version, usage errors: argparse has printed
        return int(stop.code or 0)
    args.argv = list(sys.argv[1:] if argv is None else argv)  # recorded by fitter batch
    logging.basicConfig(level=logging.ERROR if args.quiet else logging.INFO,
                        format="%(message)s")
    for chatty in ("anny", "bodyfit.calib"):  # their steps are logged for `calib -v`
        logging.getLogger(chatty).setLevel(logging.WARNING)
    from bodyfit.kernels.device import init_warp

    init_warp()  # Warp's banner, module loads and no-driver warning: the CLI keeps to errors
    command = {"batch": _cmd_batch, "check": _cmd_check, "demo": _cmd_demo,
               "measure": _cmd_measure, "run": _cmd_run, "serve": _cmd_serve}.get(args.command)
    if args.command == "model":
        command = {"build": _cmd_model_build, "info": _cmd_model_info,
                   "train-start": _cmd_model_train_start}[args.model_command]
    try:
        code = command(args)
    except UserError as exc:  # the photography check's: one line per problem
        for line in str(exc).splitlines():
            print(f"fitter: error: {line}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("fitter: interrupted", file=sys.stderr)
        return 130
    return code or 0


if __name__ == "__main__":
    sys.exit(main())
