"""Analyses built on the solver.

Built on the solver: Jacobians, workspace, the stream tracker, the standard (spherical) model,
the full formulation, the 3-6 sensor's geometric direct kinematics, trajectories.
"""
