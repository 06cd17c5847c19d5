"""The ways a photo's person is told from what is behind them (``--segmenter``), apart
from :mod:`bodyfit.calib.silhouette` so that the command lines read them without loading
it.

- ``"backdrop"``: the colour model of a plain backdrop that fills the frame;
- ``"learned"``: the learned person segmentation (:mod:`bodyfit.calib.segment`), refined
  at its outline by the same colour comparison, for rooms;
- ``"auto"``: the backdrop where a plain one surrounds the person (the frame's border
  plain, the region found apart from the frame's edges), else the learned.
"""

from bodyfit.common.errors import UserError

__all__ = ["SEGMENTERS", "SEGMENTER_HELP", "check_segmenter"]

SEGMENTERS = ("auto", "backdrop", "learned")
#: ``--segmenter``'s help, the same in every command.
SEGMENTER_HELP = ("how the person is told from what is behind them: backdrop (a plain "
                  "backdrop's colour model), learned (a learned person segmentation refined "
                  "at its outline, for rooms), auto (backdrop where a plain backdrop "
                  "surrounds the person, else learned; the default)")


def check_segmenter(name: str) -> None:
    """UserError unless ``name`` is one of ``SEGMENTERS``."""
    if name not in SEGMENTERS:
        raise UserError(f"--segmenter must be one of {', '.join(SEGMENTERS)}, got {name!r}")
