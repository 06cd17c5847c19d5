"""What a fit writes for people to use and read: meshes, measurement files, pictures,
the report.

- :mod:`~bodyfit.fitter.output.result_files`: measurement files and staged, atomic
  result folders;
- :mod:`~bodyfit.fitter.output.mesh_io`: OBJ and PLY meshes, read and written;
- :mod:`~bodyfit.fitter.output.render`: pictures of bodies coloured by part;
- :mod:`~bodyfit.fitter.output.overlays`: the fitted outline over the photos, the
  matched contours;
- :mod:`~bodyfit.fitter.output.plots`: line charts (the convergence plot);
- :mod:`~bodyfit.fitter.output.report`: the self-contained report.html.
"""
