"""The 16 tape measurements of a body mesh (the paper's Fig. 10).

- :mod:`~bodyfit.fitter.measure.sections`: plane sections of a mesh and their tape
  length (the convex hull's perimeter);
- :mod:`~bodyfit.fitter.measure.measurements`: the 16 measurements, their landmarks
  and ISO 8559-1 definitions (:class:`~bodyfit.fitter.measure.measurements.Measurer`).
"""
