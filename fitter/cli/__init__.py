"""The `fitter` command line (:func:`bodyfit.fitter.cli.main.main`): run, batch, demo,
measure and model."""
