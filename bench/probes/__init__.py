"""One-off investigations of the accuracy benchmark's fits (not supported commands).

``python -m bench.probes.accuracy COMMAND`` (outlines, floor, costs, budgets, combine,
bends, bend-readings, remeasure): each answered a question behind a past choice
(docs/history.md); they read runs of ``python -m bench.accuracy fit`` and are kept
runnable so that a result can be checked.

- :mod:`~bench.probes.combine`: other ways to combine a fit's averaged answers; the neck;
- :mod:`~bench.probes.truth_costs`: the truth's closest body scored on a fit's views;
- :mod:`~bench.probes.bend_readings`: the front photo's limb bends against the readings.
"""
