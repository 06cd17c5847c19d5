"""What the `calib` and `fitter` packages share: the user-error type, atomic file writes
and the command lines' common parts.

- :mod:`~bodyfit.common.errors`: :class:`~bodyfit.common.errors.UserError`, a problem
  the user can fix (the CLIs print it as one line and exit 2);
- :mod:`~bodyfit.common.files`: atomic writes, created folders removed on failure, input
  checks and fingerprints;
- :mod:`~bodyfit.common.command_line`: one-line usage errors, the installed version.

It imports no other bodyfit package (docs/architecture.md, "Layers").
"""
