"""Benchmark of `fitter batch`: subjects per minute by engine and workers, Ray's overhead.

    python -m bench.batch_speed --docs docs/batch.md     # the figures of docs/batch.md
    python -m bench.batch_speed --subjects 2 --generations 2 --engines local   # a smoke run

In-space subjects (:func:`bench.subjects.draw_subject`, photographed orthographically by
:mod:`bodyfit.fitter.demo.studio_photos`) are fitted by the `fitter batch` command itself at
the paper's budget (``--method paper``: its GA, 30 x 25 candidates), once per engine
(local processes, a local Ray instance started by the command) and worker count, each
into a fresh OUT. Per run, from the wall clock and OUT/batch.json:

- subjects/min: subjects / wall seconds of the whole command (start-up included);
- start-up: the command's wall seconds until the first subject starts (the command's own
  start and checks, then the engine's: worker processes, or Ray and its actors, starting
  and loading the body model);
- steady subjects/min: subjects / (wall - start-up);
- job s: a subject's job in its worker, mean (photos to written results);
- overhead s/subject: what a worker slot spends per subject beyond its job,
  (wall - start-up) x workers / subjects - job s: scheduling, sending the job and its
  outcome, the driver's bookkeeping. Ray's overhead per subject is its figure minus the
  local engine's at the same worker count.

Every run must give the same results (the same seed); the benchmark checks it. Prints
Markdown; with ``--docs FILE`` it also replaces the block between the markers
``<!-- bench_batch: begin -->`` and ``<!-- bench_batch: end -->`` in FILE.
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import platform
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from bench.subjects import draw_subject
from bodyfit.fitter.demo.studio_photos import write_subject
from bodyfit.fitter.model.cache import load_model

BEGIN, END = "<!-- bench_batch: begin -->", "<!-- bench_batch: end -->"


def write_subjects(folder: Path, count: int, seed: int) -> Path:
    """``count`` subjects' photos in ``folder`` and their table; returns the table."""
    model, rng = load_model(), np.random.default_rng(seed)
    rows = []
    for index in range(count):
        name = f"subject{index:03d}"
        (folder / name).mkdir(parents=True, exist_ok=True)
        truth = write_subject(folder / name, model, *draw_subject(rng))
        rows.append([name, f"{name}/front.png", f"{name}/side.png", f"{truth['O'] / 10:.2f}"])
    table = folder / "subjects.csv"
    with open(table, "w", newline="") as stream:
        writer = csv.writer(stream)
        writer.writerow(["id", "front", "side", "height_cm"])
        writer.writerows(rows)
    return table


def run_batch(table: Path, out: Path, engine: str, workers: int, options: list[str]) -> dict:
    """One `fitter batch` run; its figures (module docstring) and results."""
    command = ["fitter", "-q", "batch", str(table), "-o", str(out), "--workers", str(workers),
               *(["--ray"] if engine == "ray" else []), *options]
    start = time.perf_counter()
    done = subprocess.run(command, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    wall = time.perf_counter() - start
    if done.returncode != 0:
        sys.exit(f"{' '.join(command)} failed ({done.returncode}):\n{done.stderr[-2000:]}")
    record = json.loads((out / "batch.json").read_text())
    with open(out / "summary.csv", newline="") as stream:
        rows = list(csv.DictReader(stream))
    count = len(rows)
    # from the first subject's start to the end; the rest of the wall clock is start-up
    steady = record["seconds"]["total"] - record["seconds"]["start_up"]
    start_up = wall - steady
    job = record["seconds"]["jobs"] / count
    return {"engine": engine, "workers": workers, "wall": wall, "start_up": start_up,
            "rate": 60 * count / wall, "steady_rate": 60 * count / steady, "job": job,
            "overhead": steady * workers / count - job,
            "results": [{k: v for k, v in row.items() if k not in ("seconds", "status")}
                        for row in rows]}


def markdown(runs: list[dict], args, candidates: str) -> list[str]:
    local = {run["workers"]: run for run in runs if run["engine"] == "local"}
    lines = [
        f"`python -m bench.batch_speed {' '.join(args.argv)}` on {platform.machine()}, "
        f"{os.cpu_count()} cores, {platform.python_version()}: {args.subjects} subjects, "
        f"{candidates}; wall seconds of the whole `fitter batch` command.",
        "",
        "| engine | workers | wall s | start-up s | subjects/min | steady subjects/min "
        "| job s | overhead s/subject | Ray's extra overhead s/subject |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for run in runs:
        extra = ""
        if run["engine"] == "ray" and run["workers"] in local:
            extra = f"{run['overhead'] - local[run['workers']]['overhead']:+.2f}"
        lines.append(f"| {run['engine']} | {run['workers']} | {run['wall']:.1f} | "
                     f"{run['start_up']:.1f} | {run['rate']:.1f} | {run['steady_rate']:.1f} | "
                     f"{run['job']:.2f} | {run['overhead']:.2f} | {extra} |")
    same = all(run["results"] == runs[0]["results"] for run in runs)
    lines += ["", f"Same results (best costs, measurements, spreads) in every run: "
                  f"{'yes' if same else 'NO'}."]
    return lines


def main() -> None:
    parser = argparse.ArgumentParser(prog="python -m bench.batch_speed",
                                     description=__doc__.splitlines()[0])
    parser.add_argument("--subjects", type=int, default=8)
    parser.add_argument("--seed", type=int, default=11)
    parser.add_argument("--workers", default="1,2", help="worker counts (default 1,2)")
    parser.add_argument("--engines", default="local,ray", help="default local,ray")
    parser.add_argument("--generations", type=int,
                        help="fewer generations than the paper's 25, for a smoke run")
    parser.add_argument("--docs", type=Path, help="replace the figures' block in this file")
    args = parser.parse_args()
    args.argv = sys.argv[1:]
    options = ["--method", "paper"]
    if args.generations is not None:
        options += ["--generations", str(args.generations)]
    candidates = f"the paper's budget (`--method paper`: GA, 30 x {args.generations or 25} " \
                 "candidates)"
    with tempfile.TemporaryDirectory(prefix="bench_batch.") as scratch:
        scratch = Path(scratch)
        table = write_subjects(scratch / "subjects", args.subjects, args.seed)
        runs = []
        for engine in args.engines.split(","):
            for workers in map(int, args.workers.split(",")):
                runs.append(run_batch(table, scratch / f"{engine}-{workers}", engine, workers,
                                      options))
                print(f"{engine}, {workers} workers: {runs[-1]['wall']:.1f} s",
                      file=sys.stderr)
    lines = markdown(runs, args, candidates)
    print("\n".join(lines))
    if args.docs is not None:
        text = args.docs.read_text()
        block = re.compile(re.escape(BEGIN) + ".*?" + re.escape(END), re.S)
        if not block.search(text):
            sys.exit(f"{args.docs} has no {BEGIN} ... {END} block")
        args.docs.write_text(block.sub(lambda _: "\n".join([BEGIN, *lines, END]), text))
        print(f"wrote the figures into {args.docs}", file=sys.stderr)


if __name__ == "__main__":
    main()
