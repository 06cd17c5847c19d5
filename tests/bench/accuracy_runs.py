"""The accuracy benchmark's tests' helpers: the shared small run and the commands run in
this process."""

from __future__ import annotations

import dataclasses
from pathlib import Path


@dataclasses.dataclass(frozen=True)
class SmallRun:
    """The fixture's set and run: ``set_folder``/runs/``name``."""

    set_folder: Path
    name: str

    @property
    def run(self) -> Path:
        return self.set_folder / "runs" / self.name


def bench(capsys, *argv: str) -> str:
    """``python -m bench.accuracy ARGV`` in this process; what it printed."""
    from bench.accuracy.cli import main

    capsys.readouterr()
    main(list(argv))
    return capsys.readouterr().out


def probe(capsys, *argv: str) -> str:
    """``python -m bench.probes.accuracy ARGV`` in this process; what it printed."""
    from bench.probes.accuracy import main

    capsys.readouterr()
    main(list(argv))
    return capsys.readouterr().out
