"""`fitter demo`: a synthetic person photographed, calibrated for and fitted.

- :mod:`~bodyfit.fitter.demo.studio_photos`: synthetic photos of model bodies with their
  truth (also used by the tests and the benchmarks in ``bench/``);
- :mod:`~bodyfit.fitter.demo.example`: the demo's scene, its camera's calibration and
  the measured-against-true table.
"""
