"""The real-people benchmark's commands: BodyM's silhouettes through ``fitter batch``.

Run from the repository root (what they measured: docs/accuracy.md, "Real people
(BodyM)")::

    # the choice part's first 100 subjects (their first photo pair), the default method;
    # fitter batch options after -- (resumable: rerun to continue, or to fit more rows)
    python -m bench.bodym fit bodyfit --first 100
    python -m bench.bodym fit mass --first 100 --mass
    # of the first 400, those whose side masks' feet do not tell the side, fitted as left
    python -m bench.bodym fit untold-left --first 400 --side-untold -- --side-from left
    # every photo pair of those subjects (repeat photos: the precision)
    python -m bench.bodym fit bodyfit-all --first 100 --photos all
    # the tables: per measurement, baselines beside, paired against another run
    python -m bench.bodym report bodyfit --first 100
    python -m bench.bodym report mass --first 100 --against bodyfit
    # the held-out part, once per change that lands (offsets from the choice part's run)
    python -m bench.bodym fit held-out --part held-out --first 200
    python -m bench.bodym report held-out --part held-out --first 200 --offsets-from bodyfit

Each photo pair is fitted as the issue measured it: ``fitter batch --projection
orthographic --no-check``, the masks padded with 48 px of black (the crops touch their
frame), the stated height as the stature (``--height scan``: the scan's), the sex and, with
``--mass``, the stated weight.
Runs, masks and tables lie in ``out/bodym/`` (git ignores it): per-person fits and errors
never enter the repository (BodyM is CC BY-NC; evaluation only), only the aggregate
tables that ``report`` prints.
"""

from __future__ import annotations

import argparse
import re
import subprocess
import sys
from pathlib import Path

import cv2
import numpy as np
from scipy import stats

from bench.accuracy.runs import FITTED
from bench.accuracy.scores import error_stats
from bench.bodym.dataset import (DEFAULT_SPLIT, PARTS, SHARED_KEYS, Subject, part,
                                 read_split)
from bench.bodym.scores import (PAPER_TABLE2, PhotoFits, bmi_band_errors,
                                height_weight_predictions, measurement_stats, offsets,
                                precision_sd)
from bench.subjects import bodyfit_command
from bodyfit.calib.silhouette import load_mask
from bodyfit.fitter.batch.tables import FAILURES_FILE, SUMMARY_FILE, csv_text, read_table
from bodyfit.fitter.fit.facing import side_seen
from bodyfit.fitter.measure.measurements import MEASUREMENTS

__all__ = ["main"]

#: Black added around each BodyM mask, px: its crops touch the frame, which the fit's
#: silhouette reading refuses as a person cut off.
PAD_PX = 48
RUNS = Path("out/bodym")
_CHEST_WAIST_HIP = ("D", "E", "F")
#: Fewest choice subjects the height-and-weight regression is fitted on (else not shown).
_MIN_TRAIN = 20


def _window(args) -> list[Subject]:
    return part(read_split(Path(args.split)), args.part)[:args.first]


def _padded_masks(photo_id: str, split: Path, folder: Path) -> tuple[Path, Path]:
    """The front and side masks of ``photo_id`` padded by ``PAD_PX`` (written once)."""
    paths = []
    for view, source in (("front", "mask"), ("side", "mask_left")):
        path = folder / f"{photo_id}_{view}.png"
        if not path.exists():
            mask = cv2.imread(str(split / source / f"{photo_id}.png"), cv2.IMREAD_GRAYSCALE)
            cv2.imwrite(str(path), cv2.copyMakeBorder(mask, *[PAD_PX] * 4,
                                                      cv2.BORDER_CONSTANT, value=0))
        paths.append(path)
    return paths[0], paths[1]


def fit(args, batch_options: list[str]) -> None:
    split = Path(args.split)
    subjects = _window(args)
    masks = RUNS / "masks"
    masks.mkdir(parents=True, exist_ok=True)
    if args.side_untold:
        subjects = [s for s in subjects if side_seen(load_mask(
            str(_padded_masks(s.photo_ids[0], split, masks)[1]))) is None]
    header = ["id", "front", "side", "mask_front", "mask_side", "height_cm", "sex", "mass_kg"]
    rows = []
    for s in subjects:
        height = s.stated_height_cm if args.height == "stated" else s.scan_height_cm
        for photo_id in (s.photo_ids if args.photos == "all" else s.photo_ids[:1]):
            front, side = (str(p.resolve()) for p in _padded_masks(photo_id, split, masks))
            rows.append([photo_id, front, side, front, side, f"{height:g}", s.sex,
                         f"{s.weight_kg:g}" if args.mass else ""])
    out = RUNS / args.name
    out.mkdir(parents=True, exist_ok=True)
    table = out / "subjects.csv"
    table.write_text(csv_text(header, rows))
    command = [bodyfit_command("fitter"), "-q", "batch", str(table), "-o", str(out), "--projection",
               "orthographic", "--no-check", *batch_options]
    code = subprocess.run(command).returncode
    if code not in (0, 1):  # 1: some subjects failed (recorded in failures.csv)
        sys.exit(f"fitter batch stopped with exit status {code}")
    print(f"{out}: {len(rows)} photo pairs of {len(subjects)} subjects; fitter batch exit "
          f"{code}")


def read_fits(name: str, subjects: list[Subject]) -> PhotoFits:
    """The fits of run ``name`` of ``subjects``' photo pairs (those in its summary.csv)."""
    out = RUNS / name if "/" not in name else Path(name)
    if not (out / SUMMARY_FILE).exists():
        sys.exit(f"{out}: no {SUMMARY_FILE}; run `python -m bench.bodym fit` first")
    by_photo = {p: s for s in subjects for p in s.photo_ids}
    names = [MEASUREMENTS[k][0] for k in SHARED_KEYS]
    fitted, estimates, spreads, costs = [], [], [], []
    for row in read_table(out / SUMMARY_FILE, ("id",)):
        if row["id"] in by_photo and row["status"] in FITTED:
            fitted.append(row["id"])
            estimates.append([float(row[f"{n}_mm"]) for n in names])
            spreads.append([float(row[f"{n}_spread_mm"]) for n in names])
            costs.append(float(row["best_cost"]))
    failures = [(row["id"], row["reason"]) for row in read_table(out / FAILURES_FILE, ("id",))
                if row["id"] in by_photo] if (out / FAILURES_FILE).exists() else []
    shape = (len(fitted), len(SHARED_KEYS))
    return PhotoFits([by_photo[p] for p in fitted], fitted,
                     np.array(estimates).reshape(shape), np.array(spreads).reshape(shape),
                     np.array(costs), failures)


def _mm(value: float) -> str:
    return "—" if np.isnan(value) else f"{value:.1f}"


def _row(cells) -> str:
    return "| " + " | ".join(cells) + " |"


def _main_table(fits: PhotoFits, removed: np.ndarray, baseline: np.ndarray) -> list[str]:
    st = measurement_stats(fits.errors, fits.spreads, removed)
    base_mae = np.abs(baseline - fits.truths).mean(0)
    paper = PAPER_TABLE2["front + side + height"]
    lines = [_row(["measurement", "mean abs.", "median", "offset (95 %)", "> 50 mm",
                   "> 100 mm", "± holds", "after offsets", "± holds after offsets",
                   "height-weight regression", "BodyM paper, + height"]),
             _row(["---"] + ["---:"] * 10)]
    for i, key in enumerate(SHARED_KEYS):
        lines.append(_row([
            f"{key} {MEASUREMENTS[key][1]}", f"{st.mae[i]:.1f}", f"{st.median[i]:.1f}",
            f"{st.offset[i]:+.1f} (±{st.offset_ci[i]:.1f})", f"{100 * st.over_50[i]:.0f} %",
            f"{100 * st.over_100[i]:.0f} %", f"{100 * st.covered[i]:.0f} %",
            f"**{st.mae_after[i]:.1f}**", f"{100 * st.covered_after[i]:.0f} %",
            _mm(base_mae[i]),
            f"{paper[key]:.1f}" if key in paper else "—"]))
    for label, keys in (("chest, waist, hip", _CHEST_WAIST_HIP), ("all 13", SHARED_KEYS)):
        cols = [SHARED_KEYS.index(k) for k in keys]
        lines.append(_row([
            f"*mean of {label}*", f"{st.mae[cols].mean():.1f}", f"{st.median[cols].mean():.1f}",
            "", f"{100 * st.over_50[cols].mean():.0f} %",
            f"{100 * st.over_100[cols].mean():.0f} %", f"{100 * st.covered[cols].mean():.0f} %",
            f"**{st.mae_after[cols].mean():.1f}**",
            f"{100 * st.covered_after[cols].mean():.0f} %", _mm(base_mae[cols].mean()),
            f"{np.mean([paper[k] for k in keys]):.1f}" if set(keys) <= set(paper) else "—"]))
    return lines


def _paired(fits: PhotoFits, other: PhotoFits, removed: np.ndarray,
            removed_other: np.ndarray) -> list[str]:
    """The change of mean |error after offsets| against ``other`` on the people both
    fitted: per group, mean (95 %)."""
    shared = sorted(set(fits.photo_ids) & set(other.photo_ids))
    a = {p: i for i, p in enumerate(fits.photo_ids)}
    b = {p: i for i, p in enumerate(other.photo_ids)}
    err_a = np.abs(fits.errors[[a[p] for p in shared]] - removed)
    err_b = np.abs(other.errors[[b[p] for p in shared]] - removed_other)
    lines = [f"Paired on the {len(shared)} photo pairs both fitted, mean |error after "
             "offsets| (mm; each run's own offsets, or both --offsets-from's), this run "
             "against the other, and the difference (95 %):", ""]
    groups = [(f"{k} {MEASUREMENTS[k][1]}", (k,)) for k in SHARED_KEYS] + [
        ("chest, waist, hip", _CHEST_WAIST_HIP), ("all 13", SHARED_KEYS)]
    lines += [_row(["measurement", "this run", "the other", "difference"]),
              _row(["---", "---:", "---:", "---:"])]
    columns = [[SHARED_KEYS.index(k) for k in keys] for _, keys in groups]
    change = error_stats(np.stack([err_a[:, c].mean(1) - err_b[:, c].mean(1)
                                   for c in columns], axis=1))
    for (label, _), cols, mean, half in zip(groups, columns, change.bias, change.bias_ci):
        lines.append(_row([label, f"{err_a[:, cols].mean():.1f}", f"{err_b[:, cols].mean():.1f}",
                           f"{mean:+.1f} (±{half:.1f})"]))
    return lines


def report(args) -> None:
    split = read_split(Path(args.split))
    people = part(split, args.part)[:args.first]
    everyone = read_fits(args.name, people)
    fits = everyone.first_photos()
    if len(fits.subjects) < 2:
        sys.exit(f"{args.name}: fewer than 2 of the {len(people)} subjects are fitted")
    offset_source = (fits if args.offsets_from is None else
                     read_fits(args.offsets_from, part(split, "choice")))
    removed = offsets(offset_source)
    evaluated = {s.subject_id for s in people}
    train = [s for s in part(split, "choice") if s.subject_id not in evaluated]
    baseline = (height_weight_predictions(train, fits.subjects) if len(train) >= _MIN_TRAIN
                else np.full(fits.estimates.shape, np.nan))
    refused = {p for p, _ in everyone.failures if p in {s.photo_ids[0] for s in people}}
    lines = [f"BodyM {args.part} part, subjects 0-{len(people) - 1} in the benchmark's order "
             f"(their first photo pair): {len(fits.subjects)} fitted, {len(refused)} refused "
             f"or failed; run `{args.name}`; offsets from "
             f"{'itself' if args.offsets_from is None else '`' + args.offsets_from + '`'}; "
             f"the regression on height, weight and sex fitted on {len(train)} other choice "
             "subjects. Errors in mm.", ""]
    lines += _main_table(fits, removed, baseline)
    for photo_id, reason in everyone.failures:
        if photo_id in refused:
            # its numbers are the person's (a stated weight): aggregate tables only
            lines += ["", f"- refused: {re.sub(r'[0-9]+([.][0-9]+)?', '#', reason)}"]
    lines += ["", "By body mass index (stated height and weight): people, then chest, waist, "
              "hip mean signed error / mean |error|, mm:", "",
              _row(["BMI", "people", "chest", "waist", "hip"]), _row(["---"] + ["---:"] * 4)]
    for label, count, signed, absolute in bmi_band_errors(fits):
        lines.append(_row([label, str(count)] + [f"{s:+.0f} / {a:.0f}"
                                                 for s, a in zip(signed, absolute)]))
    worst = np.abs(fits.errors[:, [SHARED_KEYS.index(k) for k in _CHEST_WAIST_HIP]]).max(1)
    rho = stats.spearmanr(fits.costs, worst).statistic
    lines += ["", f"The fit's best cost against its worst error of chest, waist and hip: "
              f"Spearman {rho:.2f}; {int((worst > 100).sum())} of {len(worst)} people over "
              "100 mm."]
    spread, repeated = precision_sd(everyone)
    if repeated:
        lines += ["", f"Repeat photos ({repeated} subjects with two or more fitted pairs, "
                  f"{len(everyone.photo_ids)} pairs): the spread (SD) of one body's "
                  "measurement over its photos, mm: " + ", ".join(
                      f"{k} {v:.1f}" for k, v in zip(SHARED_KEYS, spread))]
    if args.against:
        other = read_fits(args.against, people).first_photos()
        removed_other = offsets(other if args.offsets_from is None else offset_source)
        lines += ["", *_paired(fits, other, removed, removed_other)]
    print("\n".join(lines))


def parse(argv: list[str]) -> tuple[argparse.Namespace, list[str]]:
    """The command's arguments, and the fitter batch options after ``--`` (``fit``)."""
    parser = argparse.ArgumentParser(prog="python -m bench.bodym", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="command", required=True)
    for name, text in (("fit", "fit a part's subjects through fitter batch"),
                       ("report", "per-measurement tables of a run")):
        p = sub.add_parser(name, help=text)
        p.add_argument("name", help=f"the run: {RUNS}/NAME (or a path with a /)")
        p.add_argument("--split", default=str(DEFAULT_SPLIT), help="the BodyM split folder "
                       "(default: the shared train split)")
        p.add_argument("--part", choices=PARTS, default="choice",
                       help="the split's part, in the benchmark's fixed order")
        p.add_argument("--first", type=int, required=True, metavar="N",
                       help="the part's first N subjects")
    fit_parser = sub.choices["fit"]
    fit_parser.add_argument("--photos", choices=("first", "all"), default="first",
                            help="each subject's first photo pair, or all of them")
    fit_parser.add_argument("--height", choices=("stated", "scan"), default="stated",
                            help="the stature given: the stated height, or the scan's")
    fit_parser.add_argument("--mass", action="store_true",
                            help="give each person's stated weight as the mass (mass_kg)")
    fit_parser.add_argument("--side-untold", action="store_true",
                            help="only the subjects whose first side mask's feet do not "
                                 "tell which side it shows (whom --side-from auto fits "
                                 "both ways)")
    rep = sub.choices["report"]
    rep.add_argument("--offsets-from", metavar="RUN",
                     help="a choice-part run whose mean signed errors are the offsets "
                          "removed (default: this run's own)")
    rep.add_argument("--against", metavar="RUN", help="pair against another run")
    batch_options = argv[argv.index("--") + 1:] if "--" in argv else []
    args = parser.parse_args(argv[:argv.index("--")] if "--" in argv else argv)
    if args.command != "fit" and batch_options:
        parser.error("only fit takes fitter batch options after --")
    return args, batch_options


def main(argv: list[str] | None = None) -> None:
    args, batch_options = parse(sys.argv[1:] if argv is None else argv)
    if args.command == "fit":
        fit(args, batch_options)
    else:
        report(args)
