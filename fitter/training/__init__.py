"""Training what the fit learns from bodies the project photographs itself.

- :mod:`~bodyfit.fitter.training.start_training`: the learned start's regression
  (:mod:`bodyfit.fitter.fit.learned_start`), ``fitter model train-start``.
"""
