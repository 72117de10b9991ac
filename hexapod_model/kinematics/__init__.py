"""Leg readings <-> pose.

Leg readings <-> pose: the user-facing :class:`~hexapod_model.kinematics.hexapod.Hexapod`, the
Newton solver, its compiled kernels, and rotation conversions.
"""
