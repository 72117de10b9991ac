"""Analyses built on the solver.

Jacobians and conditioning, workspace, sensitivity, the standard (spherical) model, the full
formulation, trajectories (the 3-6 sensor's geometric direct kinematics is
:mod:`hexapod_model.kinematics.three_six`).
"""
