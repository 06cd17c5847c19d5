"""``python -m bench.bodym``: the real-people benchmark's commands (:mod:`.cli`)."""

from bench.bodym.cli import main

main()
