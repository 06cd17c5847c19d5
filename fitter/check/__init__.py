"""The photography check that `fitter check` runs, and `fitter run` before each fit.

- :mod:`~bodyfit.fitter.check.shape`: what a silhouette shows of the pose and framing;
- :mod:`~bodyfit.fitter.check.photos`: the rules, from the silhouette and the pose
  model's landmarks, each failure one line that says what to do.
"""
