"""Warp kernels: skin, project, rasterise and score whole populations of bodies."""
