"""`fitter batch`: many subjects fitted as `fitter run` fits one, resumable.

- :mod:`~bodyfit.fitter.batch.subjects`: the subjects table (SUBJECTS.csv), read and
  checked before any work;
- :mod:`~bodyfit.fitter.batch.job`: what one subject's job is and the one function that
  runs it (every engine calls it);
- :mod:`~bodyfit.fitter.batch.engines`: where jobs run: local worker processes;
  :mod:`~bodyfit.fitter.batch.ray_engine`: Ray actors, on one machine or a cluster;
- :mod:`~bodyfit.fitter.batch.tables`: summary.csv and failures.csv;
- :mod:`~bodyfit.fitter.batch.orchestration`: a batch from plan to tables (which subjects
  are done, which to fit, the progress bar, batch.json).

Design, figures and how to run on a cluster: docs/batch.md.
"""
