"""The accuracy benchmark (issue 10, docs/accuracy.md): synthetic adults photographed
through a calibrated phone camera, fitted by the user's own commands, scored against
their truth.

- :mod:`.bodies`: the subjects' bodies, in-space and out-of-space, and their poses;
- :mod:`.photos`: their photos, by a renderer independent of the kernels, with a lens,
  uneven light, sensor noise and JPEG;
- :mod:`.subject_set`: a set of subjects on disk (photos, truth, board photos, the
  subjects table of ``fitter batch``);
- :mod:`.fit_photos`: a subject's fit as `fitter run` saw it, to measure its bodies again;
- :mod:`.scores`: errors against the truth and their statistics;
- :mod:`.report`: the Markdown tables (the paper's Tables 3 and 4 and more).

``python -m bench.accuracy`` runs it.
"""
