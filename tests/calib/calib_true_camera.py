"""The camera the tests photograph boards with: what calibration must give back."""

import numpy as np

# Phone-like: 1280x720, about 63 degrees across, principal point off centre, fx != fy,
# and the paper's radial model (k1, k2) with phone-like values.
TRUE_K = np.array([[1050.0, 0.0, 648.5], [0.0, 1046.0, 352.3], [0.0, 0.0, 1.0]])
TRUE_DIST = np.array([-0.11, 0.21, 0.0, 0.0, 0.0])
IMAGE_SIZE = (1280, 720)
