"""The ``combine`` probe: other ways to combine the answers a run's fits averaged, and
where the fits' neck circumference goes wrong (``python -m bench.probes.accuracy
combine``, :mod:`bench.probes.accuracy`)."""

from __future__ import annotations

import dataclasses
import json
import sys
from pathlib import Path

import numpy as np

from bench.accuracy.fit_photos import FitPhotos
from bench.accuracy.report import mean_of_important
from bench.accuracy.runs import record_holders, run_folder
from bench.accuracy.scores import IMPORTANT_COLUMNS, KEYS, error_stats
from bench.accuracy.subject_set import read_bodies, read_truth, subject_ids
from bodyfit.fitter.fit.canvas import extreme_bodies
from bodyfit.fitter.fit.person_fit import stature_conditioner
from bodyfit.fitter.fit.photo_extents import section_scales
from bodyfit.fitter.measure.measurements import MEASUREMENTS, Measurer
from bodyfit.fitter.measure.sections import hull_perimeter
from bodyfit.fitter.model.body_model import POSE_NAMES
from bodyfit.fitter.model.cache import load_model
from bodyfit.fitter.run.config import run_config

__all__ = ["combine", "FIT_RULE", "COMBINATIONS"]


def _combinations(count: int) -> dict:
    """combine's rules for ``count`` answers: name -> (the answers' genes (N, K + 4), their
    costs (N,)) -> genes; the first is the fit's own (the mean of all), then the mean of
    the first n (seeds S to S + n - 1: what ``--refinements n`` gives) for every n <
    ``count``, then the rules of ``COMBINATIONS``."""
    firsts = {f"the mean of the first {n}" if n > 1 else "the first alone":
              (lambda genes, costs, n=n: genes[:n].mean(axis=0)) for n in range(1, count)}
    return {FIT_RULE: lambda genes, costs: genes.mean(axis=0),
            **firsts, **COMBINATIONS}



#: combine's first rule, the fit's own: the mean of all the answers.
FIT_RULE = "the mean of all (the fit's)"
#: combine's rules besides the means of the first n (:func:`_combinations`).
COMBINATIONS = {
    "the lowest-cost one": lambda genes, costs: genes[np.argmin(costs)],
    "the mean of all but the highest-cost one":
        lambda genes, costs: genes[np.argsort(costs)[:-1]].mean(axis=0),
    "the median, gene by gene": lambda genes, costs: np.median(genes, axis=0),
}


def combine(args) -> None:
    """Other ways to combine the answers a run's fits averaged (run.json's
    ``result.averaged``: the refinements' betas, angles and costs), among them the mean of
    the first n (fewer refinements, from the same run), each body formed as
    the fit forms its average (the first beta solved anew from the stature, the rest
    body rescaled to it) and measured: the 7 important measurements' mean |error| per
    rule and its difference from the fit's own, paired. Also how often the truth lies
    within the single answers' scatter (their standard deviation, each measurement).
    The first rule rebuilds each fit's own measurements (printed: the largest
    difference from measurements.json, a round trip). A run is a name or a folder of
    `keep`; several runs are joined, each subject from the first run holding it;
    ``--answers N`` takes each fit's first N answers only (what ``--refinements N``
    gives: the refinements do not depend on their count), so runs of more refinements
    join runs of N as N's fits. Last, where the fits' neck circumference goes wrong
    (:func:`_neck_line`)."""
    folder = Path(args.set)
    model = load_model()
    measurer = Measurer.from_model(model)
    errors, counts = {}, set()
    scatter, round_trip, rebuilt = [], 0.0, 0
    truths = read_bodies(model, folder)
    ids = subject_ids(len(truths.sex), truths.sex)
    necks = []  # per subject, what _neck_line reads
    subjects = [row.split(",")[0] for row in
                (folder / "subjects.csv").read_text().splitlines()[1:][:args.first]]
    holder = record_holders([run_folder(folder, name) for name in args.names], subjects)
    for subject in (s for s in subjects if s in holder):
        run = holder[subject]
        record = json.loads((run / subject / "run.json").read_text())
        answers = record["result"].get("averaged", [])
        if len(answers) < (args.answers or 0):
            sys.exit(f"{run / subject}: its fit averaged {len(answers)} answers, fewer "
                     f"than --answers {args.answers}")
        truncated = len(answers) > (args.answers or len(answers))
        answers = answers[:args.answers]
        if len(answers) < 2:
            continue
        settings = run_config(record).settings
        stature_m = record["inputs"]["height_cm"] / 100.0
        search = settings.search.refinement() if settings.search.refine_components \
            else settings.search
        bodies = extreme_bodies(model, search.components, search.pose_lower_deg,
                                search.pose_upper_deg, search.beta_limit)
        conditioner = stature_conditioner(model, dataclasses.replace(settings, search=search),
                                          stature_m, bodies)
        genes = np.array([a["betas"] + [a["pose_deg"][n] for n in POSE_NAMES]
                          for a in answers])
        costs = np.array([a["cost"] for a in answers])
        truth = read_truth(folder / subject)
        counts.add(len(answers))
        if len(counts) > 1:
            sys.exit(f"{'+'.join(args.names)}: their fits averaged different numbers of "
                     f"answers ({sorted(counts)}; --answers N takes the first N)")
        rules = _combinations(len(answers))
        # every rule's body, then each answer's own, formed as the fit forms its average
        combined = np.array([rule(genes, costs) for rule in rules.values()] + list(genes))
        betas, pose = combined[:, :-len(POSE_NAMES)], combined[:, -len(POSE_NAMES):]
        if conditioner is not None:
            betas = conditioner.complete(betas[:, 1:], pose)
        photos = FitPhotos.of(model, folder, subject, record)
        bodies_measured = [photos.measure(model, measurer, b, g) for b, g in zip(betas, pose)]
        rest = [body for body, _, _ in bodies_measured]
        measured = np.array([[values[key] - truth[key] for key in KEYS]
                             for _, values, _ in bodies_measured])
        for name, values in zip(rules, measured):
            errors.setdefault(name, []).append(values)
        if not truncated:
            written = json.loads((run / subject / "measurements.json").read_text())
            own = np.array([written["measurements"][name]["value_mm"] - truth[key]
                            for key, (name, _) in zip(KEYS, MEASUREMENTS.values())])
            round_trip = max(round_trip, float(np.abs(own - measured[0]).max()))
            rebuilt += 1
        scatter.append(measured[len(rules):].std(axis=0, ddof=1))  # the single answers'
        true_body = truths.vertices[ids.index(subject)]
        true_neck = measurer.girth_section(true_body, "B")
        scale = (section_scales(model, measurer, bodies_measured[0][2])["B"]
                 if bodies_measured[0][2] is not None else 1.0)
        necks.append((true_neck, measurer.girth_section(rest[0], "B") * scale,
                      1000 * stature_m / settings.canvas.body_height_px,
                      _beyond_the_neck(measurer, true_body, true_neck)))
    fit = np.array(errors.get(FIT_RULE, []))
    count = len(fit)
    if count < 2:
        sys.exit(f"{'+'.join(args.names)}: fewer than 2 fits record the answers they averaged")
    print(f"{folder}: {'+'.join(args.names)}, {count} subjects whose fits averaged "
          f"{len(answers)} answers" + (f"; the fit's measurements rebuilt to within "
                                       f"{round_trip:.3f} mm ({rebuilt} fits)" if rebuilt else "")
          + "\n\n| combination | 7 important, mean abs. error (95 % CI) | paired with the "
          "fit's |\n|---|---|---|")
    for name, values in errors.items():
        values = np.array(values)
        mean, _, ci = mean_of_important(values)
        per_subject = (np.abs(values[:, IMPORTANT_COLUMNS]).mean(axis=1)
                       - np.abs(fit[:, IMPORTANT_COLUMNS]).mean(axis=1))
        difference = error_stats(per_subject[:, None])
        print(f"| {name} | {mean:.2f} (±{ci:.2f}) | {difference.bias[0]:+.2f} ± "
              f"{difference.bias_ci[0]:.2f} |")
    within = np.mean(np.abs(fit) <= np.array(scatter), axis=0)
    print("\nThe truth within the single answers' scatter (1 sd), per measurement: "
          + ", ".join(f"{key} {share:.0%}" for key, share in zip(KEYS, within)))
    print("\n" + _neck_line(necks))



def _beyond_the_neck(measurer: Measurer, vertices: np.ndarray,
                     section: np.ndarray) -> np.ndarray:
    """(2,) mm: how much wider (x) and deeper (y) than its neck's ``section``
    (``Measurer.girth_section``) the body ``vertices`` (V, 3, rest) is at the height of the
    neck tape's centre, within 12 cm of it across (no arm): what of the front and side
    outlines there is another part (the jaw, the chin) than the neck."""
    v = np.asarray(vertices, np.float64)
    centre = measurer.girth_plane(v, "B")[0]
    near = (np.abs(v[:, 2] - centre[2]) < 0.003) & (np.abs(v[:, 0] - centre[0]) < 0.12)
    return 1000 * (np.ptp(v[near, :2], axis=0) - np.ptp(section, axis=0))



def _neck_line(necks: list[tuple[np.ndarray, np.ndarray, float, np.ndarray]]) -> str:
    """Where the fit's neck circumference goes wrong: its section's width (across, what a
    front photo shows) and depth (front to back, a side photo's) against the truth's, and
    the circumference's error left when one section is scaled to the other's width and
    depth (what the section's shape alone gives) or the truth's to the fit's (what the
    extents alone give); and on how many the truth's outlines show the neck at the tape's
    centre height (:func:`_beyond_the_neck` under 1 mm). ``necks``: (truth's section,
    fit's section, canvas mm per pixel, :func:`_beyond_the_neck` of the truth) per
    subject, sections (n, 2) metres (``Measurer.girth_section``)."""
    rows = []
    for truth, fitted, pixel_mm, _ in necks:
        true_size, fit_size = np.ptp(truth, axis=0), np.ptp(fitted, axis=0)
        tape = hull_perimeter(truth)
        rows.append([hull_perimeter(fitted) - tape, *(1000 * (fit_size - true_size)),
                     hull_perimeter(fitted * true_size / fit_size) - tape,
                     hull_perimeter(truth * fit_size / true_size) - tape, pixel_mm])
    e = np.array(rows)
    e[:, [0, 3, 4]] *= 1000
    mean = np.abs(e[:, :5]).mean(axis=0)
    r = [np.corrcoef(e[:, 0], e[:, j])[0, 1] for j in (1, 2)]
    beyond = np.array([neck[3] for neck in necks])
    return (f"The neck (B), the fit's section against the truth's, {len(e)} subjects, mean "
            f"|error|: circumference {mean[0]:.2f} mm; width {mean[1]:.2f} mm "
            f"({np.mean(np.abs(e[:, 1]) / e[:, 5]):.2f} canvas px), depth {mean[2]:.2f} mm "
            f"({np.mean(np.abs(e[:, 2]) / e[:, 5]):.2f} px); the circumference's error "
            f"correlates {r[0]:.2f} with the width's, {r[1]:.2f} with the depth's; the fit's "
            f"section at the truth's width and depth (its shape's part) {mean[3]:.2f} mm, the "
            f"truth's at the fit's width and depth (the extents' part) {mean[4]:.2f} mm. At "
            f"the tape's centre height the truth's outline is the neck's across on "
            f"{np.sum(beyond[:, 0] < 1)} of {len(e)} (median {np.median(beyond[:, 0]):.1f} mm "
            f"wider), front to back on {np.sum(beyond[:, 1] < 1)} (median "
            f"{np.median(beyond[:, 1]):.1f} mm deeper: the chin, the jaw)")
