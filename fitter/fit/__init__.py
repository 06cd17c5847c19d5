"""One person's fit: the person's silhouettes on canvases, the local solver (or the
population search), the fitted body and its measurements with their ±.

- :mod:`~bodyfit.fitter.fit.person`: the person's inputs (photos or masks, stature,
  camera) and their silhouettes;
- :mod:`~bodyfit.fitter.fit.canvas`, :mod:`~bodyfit.fitter.fit.pinhole_canvas`: the
  kernels' canvases through the paper's orthographic views or a pinhole camera;
- :mod:`~bodyfit.fitter.fit.weights`: the cost's part weights (presets, TOML files);
- :mod:`~bodyfit.fitter.fit.outline`: a body's sub-pixel outline in a view, with its
  derivatives;
- :mod:`~bodyfit.fitter.fit.local_solver`: Levenberg-Marquardt on the outline against the
  person's edge (the default method);
- :mod:`~bodyfit.fitter.fit.learned_start`: the solver's start read off the silhouettes;
- :mod:`~bodyfit.fitter.fit.optimizers`: the ask/tell optimisers (the paper's GA, CMA-ES);
- :mod:`~bodyfit.fitter.fit.search`: a search of shape and pose over the kernels' cost;
- :mod:`~bodyfit.fitter.fit.stature`: every candidate solved to the person's stature;
- :mod:`~bodyfit.fitter.fit.side_arms`: how the side view treats arms hanging down;
- :mod:`~bodyfit.fitter.fit.render_mesh`: the lighter mesh candidates are scored with;
- :mod:`~bodyfit.fitter.fit.photo_extents`: girths scaled to the widths the photos show;
- :mod:`~bodyfit.fitter.fit.spreads`: the ± of each measurement;
- :mod:`~bodyfit.fitter.fit.contour`: the paper's contour registration (for overlays);
- :mod:`~bodyfit.fitter.fit.person_fit`: the fit's settings, methods and
  :func:`~bodyfit.fitter.fit.person_fit.fit_person`, which ties them together.
"""
