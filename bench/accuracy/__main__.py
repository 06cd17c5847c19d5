"""``python -m bench.accuracy``: the accuracy benchmark's commands (:mod:`.cli`)."""

from bench.accuracy.cli import main

main()
