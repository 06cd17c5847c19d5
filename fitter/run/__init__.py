"""One `fitter run`: its settings, from the options or an earlier run.json, and the fit
written to a folder (also what `fitter batch` runs for each subject).

- :mod:`~bodyfit.fitter.run.options`: how the command's options become a fit's settings;
- :mod:`~bodyfit.fitter.run.config`: the inputs and settings of an earlier run.json
  (``--config``);
- :mod:`~bodyfit.fitter.run.results`: :func:`~bodyfit.fitter.run.results.run_person`,
  a person's photos to a folder of results, and run.json's record.
"""
