"""Camera calibration and the image front end (undistortion, silhouettes)."""
