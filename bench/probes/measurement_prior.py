"""Probe: the measurements' prior (fitter/fit/measurement_prior.py) applied to fits kept
before it, paired against them on the same subjects.

The prior changes only what a fit reports (its measurements and ±, from the fitted body,
the stature, the sex and the mass), not the fit, so a kept setting fitted without it
(``--measurement-prior none``, or before the prior) is scored with and without it
exactly, with the true stature the benchmark gave the fitter::

    python -m bench.probes.measurement_prior docs/accuracy-runs/in-space/bodyfit.csv \\
        docs/accuracy-runs/in-space/truths.csv
    python -m bench.probes.measurement_prior docs/accuracy-runs/standing/bodyfit.csv \\
        docs/accuracy-runs/standing/truths.csv --first 72
"""

from __future__ import annotations

import argparse

import numpy as np

from bench.accuracy.runs import FITTED, read_truths, subject_row
from bench.accuracy.scores import error_stats
from bodyfit.fitter.batch.tables import read_table
from bodyfit.fitter.fit.measurement_prior import MeasurementPrior, combined
from bodyfit.fitter.measure.measurements import IMPORTANT, MEASUREMENTS

__all__ = ["prior_effect", "main"]


def prior_effect(kept: str, truths: str, first: int | None = None
                 ) -> tuple[np.ndarray, np.ndarray]:
    """(N,) each fitted subject's mean |error| of the 7 important measurements, mm,
    (without the prior, with it), of the kept setting ``kept`` against ``truths``
    (its rows before ``first`` only, if given)."""
    prior = MeasurementPrior.load()
    truth = read_truths(truths)
    without, with_prior = [], []
    for row in read_table(kept, ("id",)):
        if row["status"] not in FITTED or (first is not None and subject_row(row["id"]) >= first):
            continue
        fitted = {k: float(row[f"{name}_mm"]) for k, (name, _) in MEASUREMENTS.items()}
        spreads = {k: float(row[f"{name}_spread_mm"]) for k, (name, _) in MEASUREMENTS.items()}
        person = truth[row["id"]]
        combined_values, _ = combined(fitted, spreads, *prior.predict(
            person["sex"], person["measurements"]["O"]))
        true = person["measurements"]
        without.append(np.mean([abs(fitted[k] - true[k]) for k in IMPORTANT]))
        with_prior.append(np.mean([abs(combined_values[k] - true[k]) for k in IMPORTANT]))
    return np.array(without), np.array(with_prior)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m bench.probes.measurement_prior",
                                     description=__doc__.splitlines()[0])
    parser.add_argument("kept", help="a kept setting's CSV (docs/accuracy-runs/...)")
    parser.add_argument("truths", help="its set's truths.csv")
    parser.add_argument("--first", type=int, help="only the set's rows before this")
    args = parser.parse_args(argv)
    without, with_prior = prior_effect(args.kept, args.truths, args.first)
    change = error_stats((with_prior - without)[:, None])
    print(f"{args.kept}: {change.count} subjects, the 7 important measurements "
          f"{without.mean():.2f} -> {with_prior.mean():.2f} mm with the prior, "
          f"{change.bias[0]:+.3f} ± {change.bias_ci[0]:.3f} paired")


if __name__ == "__main__":
    main()
