"""The ways a photo's person is told from what is behind them (``--segmenter``), apart
from :mod:`bodyfit.calib.silhouette` so that the command lines read them without loading
it.

- ``"backdrop"``: the colour model of a plain backdrop that fills the frame;
- ``"learned"``: the learned person segmentation (:mod:`bodyfit.calib.segment`), refined
  at its outline by the same colour comparison, for rooms;
- ``"auto"``: the backdrop where a plain one surrounds the person (the frame's border
  plain, the region found apart from the frame's edges), else the learned.
"""

__all__ = ["SEGMENTERS"]

SEGMENTERS = ("auto", "backdrop", "learned")
