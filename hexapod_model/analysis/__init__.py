"""Analyses built on the solver.

Jacobians and conditioning, workspace, sensitivity, the standard (spherical) model, the full
formulation, the 3-6 sensor's geometric direct kinematics, trajectories.
"""
