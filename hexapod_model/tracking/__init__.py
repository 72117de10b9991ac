"""Tracking a stream of leg readings: predicted starts, statistical checks, singular passages.

* :mod:`.tracker` — :class:`~hexapod_model.tracking.tracker.Tracker`, one sample at a time;
* :mod:`.types` — predictors (Jakobović and Jelenković's eqs. 22-24) and the per-sample result;
* :mod:`.reading_tests` — the settings, the motion model and the per-leg reading tests;
* :mod:`.kernels` — the compiled per-sample arithmetic;
* :mod:`.passage` and :mod:`.branches` — which assembly a platform leaves a singular
  neighbourhood on.
"""
