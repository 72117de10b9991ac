"""Calibration: identify a hexapod's joint geometry from measured platform poses.

* :mod:`.parameters` — the unknowns: per-leg corrections to a nominal geometry;
* :mod:`.sensors` — a redundant hexapod's extra sensors: their unknowns and readings;
* :mod:`.frames` — the measurement model (measuring device and marker frames);
* :mod:`.derivatives` — the corrected hexapod and the exact derivative of its solved poses;
* :mod:`.problem` — the least-squares problem and its Jacobian;
* :mod:`.identifiability` — which parameter combinations the data determine;
* :mod:`.identify` — the fit (:func:`~hexapod_model.calibration.identify.identify`);
* :mod:`.gauge` — the result in the calibration's base and platform frame convention;
* :mod:`.validation` — k-fold validation on held-out poses;
* :mod:`.planning` — which poses to measure.
"""
