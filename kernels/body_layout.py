"""The body's layout, shared by every package: part labels and pose degrees of freedom.

The kernels are the bottom layer, so the names both they and the body model
(:mod:`bodyfit.fitter.model.body_model`, which re-exports them) index arrays by live here.
Plain constants, no Warp: importing this module initialises nothing.
"""

from __future__ import annotations

import numpy as np

__all__ = ["PART_NAMES", "POSE_NAMES", "POSE_SIDES"]

#: The body parts, in label order (label = index): the nine of the paper's Table 2, then
#: the neck, which bodyfit splits from the paper's head (skull and neck) so that it can be
#: weighted on its own; appended last so that the nine keep their labels.
PART_NAMES = ("head", "chest", "waist", "hip", "leg", "foot", "arm", "elbow", "hand", "neck")

#: The paper's 4 pose DOF: abduction in the frontal plane, positive = limb moves away
#: from the body's midline. Order of the ``pose`` columns and of the rig chains/joints.
POSE_NAMES = (
    "shoulder_abduction_left",
    "shoulder_abduction_right",
    "hip_abduction_left",
    "hip_abduction_right",
)
#: +1 for chains on the body's left (+x), -1 on the right: abduction turns them opposite ways.
POSE_SIDES = np.array([1.0, -1.0, 1.0, -1.0])
