"""The body model: a PCA shape space over rest vertices and joints, a 4-angle skinning
rig, part labels and measurement landmarks.

- :mod:`~bodyfit.fitter.model.body_model`: :class:`~bodyfit.fitter.model.body_model.BodyModel`,
  its file format, and posing (:func:`~bodyfit.fitter.model.body_model.forward`);
- :mod:`~bodyfit.fitter.model.cache`: which model file is used (a user-built one in the
  cache, else the one shipped in ``bodyfit.fitter.data``) and loading it;
- :mod:`~bodyfit.fitter.model.limb_bends`: limbs swung outside the rig's abduction (for
  photographing bodies the fitter did not shape).

Building a model from Anny is :mod:`bodyfit.fitter.model_build` (docs/model.md).
"""
