"""`fitter`: fit the body model to a person's photos, measure meshes, build the model.

The help says only what exists. User errors, usage errors included, print one line,
``fitter: error: ...``, and exit with status 2.
"""

from __future__ import annotations

import argparse
import logging
import sys
import time
from pathlib import Path

from bodyfit.calib.command_line import OneLineArgumentParser, bodyfit_version
from bodyfit.calib.errors import UserError

__all__ = ["main"]

logger = logging.getLogger("bodyfit")


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
                       help="PCA shape components to store (default 60; fitting uses 20)")
    build.add_argument("--samples", type=int, default=3000,
                       help="bodies in the population, half men, half women (default 3000)")
    build.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    build.add_argument("-o", "--output", type=Path,
                       help="write the model here instead of the cache (.npz); "
                            "fitter/data/body_model.npz is the model bodyfit ships")
    model_sub.add_parser("info", help="print which model is used and how it was built")

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
    demo.add_argument("--generations", type=int, metavar="G",
                      help="the search's generations (default: fitter run's)")

    run = sub.add_parser(
        "run", help="fit the body model to a person's front and side photos: mesh (m), "
                    "16 measurements (mm), convergence plot, run record",
        description="Fit bodyfit's body model to a front photo (A-pose) and a side photo "
                    "(arms hanging down) on a plain backdrop. Cameras: with --camera, "
                    "the calibrated pinhole camera, the person's distance solved from the "
                    "stature; without, see --projection (docs/fitter.md, Cameras).")
    run.add_argument("--config", type=Path, metavar="run.json",
                     help="repeat a previous run: its inputs and settings from its run.json "
                          "(the options given here override them)")
    run.add_argument("--method", choices=("bodyfit", "paper"),
                     help="bodyfit (default: CMA-ES 30 x 200, stature-conditioned candidates, "
                          "symmetric matching, bodyfit weights) or paper (the paper's method "
                          "exactly: its GA 30 x 25, Table 2 weights, person-to-model "
                          "matching); the options below override single settings")
    run.add_argument("--front", metavar="PHOTO", help="front photo, A-pose (required "
                     "without --config)")
    run.add_argument("--side", metavar="PHOTO",
                     help="side photo (the person's left side), arms hanging down")
    run.add_argument("--height-cm", type=float, metavar="CM",
                     help="the person's stature, centimetres")
    run.add_argument("-o", "--output", type=Path, metavar="OUT",
                     help="output folder (created; must be empty unless --overwrite)")
    run.add_argument("--camera", metavar="camera.json",
                     help="the calibrated camera (calib capture): the photos are undistorted "
                          "and fitted through it")
    run.add_argument("--projection", choices=("orthographic", "pinhole"),
                     help="pinhole: the camera of --camera, or without it a typical phone "
                          "camera (70 degrees across the long side); "
                          "orthographic: the paper's, each view scaled from the stature "
                          "(default pinhole; --method paper: orthographic)")
    run.add_argument("--mask-front", metavar="PNG", help="your own front silhouette "
                     "(white person on black, of the undistorted upright photo)")
    run.add_argument("--mask-side", metavar="PNG", help="your own side silhouette")
    run.add_argument("--background-front", metavar="PHOTO",
                     help="background plate: the front view without the person")
    run.add_argument("--background-side", metavar="PHOTO", help="background plate, side view")
    run.add_argument("--sex", choices=("female", "male", "unknown"),
                     help="recorded with the run (default unknown)")
    run.add_argument("--weights", metavar="PRESET|FILE.toml",
                     help="cost weights: bodyfit (Table 2 without the top and bottom "
                          "terms; the default), paper (Table 2; the paper method's), "
                          "uniform, lower-body, or a .toml file")
    run.add_argument("--weight", action="append", metavar="NAME=VALUE",
                     help="override one weight, e.g. waist=8 or view.side=3 (repeatable)")
    run.add_argument("--matching",
                     help="boundary matching direction: symmetric (default), "
                          "person_to_model (the paper's) or model_to_person")
    run.add_argument("--vertical-anchor", choices=("centroid", "extremes"),
                     help="how candidates are shifted vertically onto the person: centroid "
                          "(the paper's moments) or extremes (the middle of the top and "
                          "bottom rows; the default)")
    run.add_argument("--side-arms", choices=("down", "hidden"),
                     help="the side view's candidates: down (default) with their arms "
                          "hanging down, as the side photo shows them; hidden: without arms "
                          "(for a side photo whose arms hide within the torso)")
    run.add_argument("--optimizer", choices=("ga", "cmaes"),
                     help="cmaes: CMA-ES (default); ga: the paper's genetic algorithm")
    run.add_argument("--population", type=int, help="candidates per generation "
                     "(default 30)")
    run.add_argument("--generations", type=int,
                     help="generations (default 200; --method paper: 25)")
    run.add_argument("--components", type=int,
                     help="shape components searched (default 20, as the paper; up to 60)")
    run.add_argument("--seed", type=int, help="random seed (default 0)")
    run.add_argument("--free-stature", action="store_true", default=None,
                     help="search the first shape component like the others (the paper) "
                          "instead of solving it so every candidate stands as tall as the "
                          "person")
    run.add_argument("--device", help="cpu (default) or cuda:0")
    run.add_argument("--threads", type=int, help="CPU threads scoring each generation "
                     "(default: one per core; the result does not depend on it)")
    run.add_argument("--overwrite", action="store_true", help="write into a non-empty OUT")

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

    from bodyfit.calib.files import check_writable_dir
    from bodyfit.fitter.model_build import ModelBuildSettings
    from bodyfit.fitter.model_cache import build_and_save, model_path

    settings = ModelBuildSettings(components=args.components, samples=args.samples,
                                  seed=args.seed)
    settings.validate()
    path = args.output or model_path()
    if path.suffix != ".npz":
        raise UserError(f"-o takes a .npz path, got {path}")
    check_writable_dir(path.parent)
    with logging_redirect_tqdm():
        model = build_and_save(settings, path, progress=None if not args.quiet else False)
    t = model.metadata["timings_s"]
    print(f"built the body model in {t['total']:.0f} s: {model.num_vertices} vertices, "
          f"{model.num_components} components, {len(model.population_sex)} bodies")
    print(f"wrote {path}")


def _cmd_model_info(args) -> None:
    from bodyfit.fitter.model_cache import active_model_path, load_model, model_path

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
          f"population's variance)")
    print(f"  built from anny {meta['anny_version']} with {meta['settings']} "
          f"in {meta['timings_s']['total']:.0f} s")


def _cmd_demo(args) -> None:
    import shlex

    from bodyfit.fitter.demo import (DemoSettings, calibrate_scene, measurement_table,
                                     write_scene)
    from bodyfit.fitter.model_cache import load_model
    from bodyfit.fitter.run import run_person

    if args.generations is not None and args.generations < 1:
        raise UserError(f"--generations must be at least 1, got {args.generations}")
    model = load_model()
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
    if args.generations is not None:
        run_argv += ["--generations", str(args.generations)]
    run_args = _build_parser().parse_args(run_argv)
    inputs, settings, output = _run_settings(run_args)
    fit, written = run_person(model, inputs, settings, output, run_args.overwrite,
                              progress=None if not args.quiet else False)
    result = fit.search
    print(f"fitted in {sum(fit.seconds.values()):.1f} s: {result.evaluations} candidates, "
          f"{result.generations} generations ({settings.search.optimizer}, "
          f"{settings.projection})")
    print("\n".join(measurement_table(fit.measurements, scene.truth)))
    print("wrote:")
    for path in (scene.front, scene.side, scene.board_photos[0].parent, camera_path,
                 coverage_path, scene.truth_file, *written):
        print(f"  {path}")
    print(f"fit the photos again by hand: fitter {shlex.join(run_argv)}")


#: `fitter run`'s options that are fields of PersonInputs, and of SearchSettings.
_INPUT_OPTIONS = ("front", "side", "height_cm", "camera", "mask_front", "mask_side",
                  "background_front", "background_side", "sex")
_SEARCH_OPTIONS = ("optimizer", "population", "generations", "components", "seed")


def _run_settings(args):
    """(PersonInputs, FitSettings, output folder) of `fitter run`'s options: the defaults,
    or with --config the run.json's values, overridden by every option given."""
    import dataclasses

    from bodyfit.fitter.fit import METHODS
    from bodyfit.fitter.person import PersonInputs
    from bodyfit.fitter.run_config import read_run_config
    from bodyfit.fitter.weights import (cost_settings, parse_override, settings_from_record,
                                        weights_record)

    given = {k: v for k, v in vars(args).items() if v is not None}
    if args.config is None:
        missing = [f"--{k.replace('_', '-')}" for k in ("front", "side", "height_cm")
                   if k not in given] + ([] if args.output else ["-o"])
        if missing:
            raise UserError(f"fitter run needs {', '.join(missing)} (or --config run.json)")
        inputs = PersonInputs(args.front, args.side, args.height_cm)
        settings, output = METHODS[args.method or "bodyfit"], args.output
    elif args.method is not None:
        raise UserError("--method and --config cannot go together: the run.json holds the "
                        "method's settings")
    else:
        config = read_run_config(args.config)
        inputs, settings, output = config.inputs, config.settings, args.output or config.output
        if output is None:
            raise UserError(f"{args.config} records no output folder; give -o OUT")
    inputs = dataclasses.replace(inputs, **{k: given[k] for k in _INPUT_OPTIONS if k in given})
    search = dataclasses.replace(settings.search, **{k: given[k] for k in _SEARCH_OPTIONS
                                                     if k in given})
    if given.get("free_stature"):
        search = dataclasses.replace(search, condition_stature=False)
    cost = settings.cost
    cost = dataclasses.replace(cost, **{k: given[k] for k in ("matching", "vertical_anchor")
                                        if k in given})
    if "weights" in given:
        cost = cost_settings(given["weights"], given.get("weight", []), cost)
    elif "weight" in given:  # on top of the method's or the recorded weights
        record = weights_record(cost) | dict(map(parse_override, args.weight))
        cost = settings_from_record(record, cost)
    settings = dataclasses.replace(settings, search=search, cost=cost,
                                   device=given.get("device", settings.device),
                                   threads=given.get("threads", settings.threads),
                                   side_arms=given.get("side_arms", settings.side_arms),
                                   projection=given.get("projection", settings.projection))
    return inputs, settings, output


def _cmd_run(args) -> None:
    from bodyfit.fitter.measurements import MEASUREMENTS
    from bodyfit.fitter.model_cache import load_model
    from bodyfit.fitter.run import run_person

    try:
        inputs, settings, output = _run_settings(args)
        model = load_model()
        fit, written = run_person(model, inputs, settings, output, args.overwrite,
                                  progress=None if not args.quiet else False)
    except ValueError as exc:  # the kernels' argument and device errors, --matching
        raise UserError(str(exc)) from None
    result = fit.search
    print(f"fitted in {sum(fit.seconds.values()):.1f} s: {result.evaluations} candidates, "
          f"{result.generations} generations, best cost {result.cost:.1f} weighted mm")
    for key, (_, label) in MEASUREMENTS.items():
        print(f"  {key} {label:<28} {fit.measurements[key]:8.1f} ± "
              f"{fit.spreads[key]:5.1f} mm")
    print("wrote:")
    for path in written:
        print(f"  {path}")


def _cmd_measure(args) -> None:
    from bodyfit.fitter.measurements import MEASUREMENTS, Measurer
    from bodyfit.fitter.mesh_io import read_mesh
    from bodyfit.fitter.model_cache import load_model
    from bodyfit.fitter.outputs import write_measurements

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


def main(argv: list[str] | None = None) -> int:
    try:
        args = _build_parser().parse_args(argv)
    except SystemExit as stop:  # --help, --version, usage errors: argparse has printed
        return int(stop.code or 0)
    logging.basicConfig(level=logging.ERROR if args.quiet else logging.INFO,
                        format="%(message)s")
    for chatty in ("anny", "bodyfit.calib"):  # their steps are logged for `calib -v`
        logging.getLogger(chatty).setLevel(logging.WARNING)
    import warp  # Warp prints its banner and module loads at INFO; the CLI keeps to errors

    warp.config.log_level = warp.LOG_ERROR
    command = {"demo": _cmd_demo, "measure": _cmd_measure, "run": _cmd_run}.get(args.command)
    if args.command == "model":
        command = {"build": _cmd_model_build, "info": _cmd_model_info}[args.model_command]
    try:
        command(args)
    except UserError as exc:
        print(f"fitter: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("fitter: interrupted", file=sys.stderr)
        return 130
    return 0


if __name__ == "__main__":
    sys.exit(main())
