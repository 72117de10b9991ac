"""Leg readings <-> pose.

Leg readings <-> pose: the user-facing :class:`~hexapod_model.kinematics.hexapod.Hexapod`, the
solve engine under it (:mod:`~hexapod_model.kinematics.engine`), the Newton solver and its compiled
kernels (rotations and rigid motions: :mod:`hexapod_model.lie`).
"""
