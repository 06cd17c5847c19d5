"""bodyfit's benchmarks: the accuracy benchmark and the speed and choice benchmarks.

Not installed with bodyfit: run from the repository root, with bodyfit installed
(``pip install -e .``), as ``python -m bench.<module>``:

- :mod:`bench.accuracy`: synthetic subjects through the user's pipeline, scored against
  their truth (``python -m bench.accuracy make|fit|keep|report|spread|figures``;
  docs/accuracy.md);
- :mod:`bench.fitter_speed`, :mod:`bench.choices`, :mod:`bench.cameras`,
  :mod:`bench.side_arms`: `fitter run`'s error against time, its choices, its cameras,
  the side photo's arms (docs/fitter.md), over subjects drawn by :mod:`bench.subjects`;
- :mod:`bench.batch_speed`: `fitter batch`'s throughput (docs/batch.md);
- :mod:`bench.kernel_speed`: the Warp kernels' throughput (docs/kernels.md);
- :mod:`bench.probes`: one-off investigations behind past choices, kept runnable but not
  supported.
"""
