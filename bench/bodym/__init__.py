"""The real-people benchmark (issue 72, docs/accuracy.md "Real people (BodyM)"): BodyM's
adults' silhouettes fitted through ``fitter batch``, scored against their 3D scans.

- :mod:`.dataset`: the split on disk, its subjects, their fixed order and parts;
- :mod:`.scores`: errors, offsets, statistics and the baselines;
- :mod:`.cli`: ``python -m bench.bodym fit|report``.

BodyM is CC BY-NC 4.0 (Amazon; Ruiz et al., WACV 2023): evaluation only. Nothing of it,
nor per-person results, enters the repository.
"""
