"""The analytic backend's engine: Ranger's cycle as one fused numba call.

:class:`._detector.FusedDetector` (a subclass of :class:`armguard.detect.Detector`, declared by
``AnalyticBackend.ranger_detector``) compiles the scene's Model (:mod:`._model`; its kinematic tree from
the Pinocchio model, :meth:`armguard.model.Model.kinematic_tree`; its element arrays and pairs from the GeometryModel and
``Model.pairs``, :mod:`._from_model`; :mod:`._bvh`,
:mod:`._hulls`, :mod:`._prep`) into packed buffers (:mod:`._layout`) and checks it with one numba
call (:mod:`._kernel`, entered through :mod:`._entry`; the narrow phase :mod:`._step`,
:mod:`._narrow`; culling :mod:`._cull`; the large kernels called at their addresses, not linked:
:mod:`._calls`, :mod:`._native`); :mod:`._pair_rows` is the analytic Checker's entry point,
:mod:`._pair_jacobian` its distance Jacobians, :mod:`._warm` the first-run warm-up.  Moved here from ``armguard.detect``, which keeps
the framework: the public ``Detector``, Ranger's algorithm over any Checker, the result types.
"""
