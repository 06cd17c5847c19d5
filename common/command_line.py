"""What the `calib` and `fitter` command lines share: one-line usage errors, the version."""

from __future__ import annotations

import argparse
import importlib.metadata

__all__ = ["OneLineArgumentParser", "bodyfit_version"]


class OneLineArgumentParser(argparse.ArgumentParser):
    """argparse that reports usage errors in one line, like every other user error:
    ``PROG: error: MESSAGE (see `PROG [COMMAND] --help`)``, exit status 2."""

    def error(self, message: str) -> None:  # noqa: D102 - argparse's hook
        self.exit(2, f"{self.prog.split()[0]}: error: {message} (see `{self.prog} --help`)\n")


def bodyfit_version() -> str:
    """The installed bodyfit's version, or "unknown" when it runs uninstalled."""
    try:
        return importlib.metadata.version("bodyfit")
    except importlib.metadata.PackageNotFoundError:
        return "unknown"
