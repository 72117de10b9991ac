"""The tables of the body kernel, read off a loaded hexapod's Pinocchio model and its collision bodies.

:func:`kernel_tables` turns the model's joint tree (placements, kinds, unit axes), the
collision bodies of :mod:`~hexapod_model.description.collision` (capsules, spheres, plates)
with their pairs, and the joints' cones (:class:`~.cones.ConeGeometry`) into the integer and
float rows that :mod:`.placement_kernel` and :mod:`.clearance_kernel` read (the rows are named
in :mod:`.placement_kernel`). Built once per query object; read-only afterwards.
"""

from __future__ import annotations

import coal
import numpy as np
import pinocchio as pin

from ..exceptions import UrdfError
from . import placement_kernel as pk
from .cones import ConeGeometry


def kernel_tables(
    model: pin.Model, geometry: pin.GeometryModel, cones: ConeGeometry | None = None, limits: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The model's joint tree, bodies and cones as the tables :func:`~.clearance_kernel.measure_body` reads.

    Returns:
        ``(ints, floats, frames)``: the integer and float rows named in
        :mod:`~.placement_kernel`, and the joint placements then the body placements (4x4 each).
    """
    nj = model.njoints
    objects = geometry.geometryObjects
    ng, npairs = len(objects), len(geometry.collisionPairs)
    cardan, ball, tips, home = (
        cones.kernel_rows() if cones is not None else (np.zeros((0, 3), np.int64),) * 2 + (np.zeros((0, 3)),) * 2
    )
    width = max(nj + ng, npairs, 12)
    ints = np.zeros((pk.N_INT, width), dtype=np.int64)
    floats = np.zeros((pk.N_FLOAT, width))
    data = model.createData()
    q0 = pin.neutral(model)
    for j in range(1, nj):
        if model.joints[j].shortname() == "JointModelFreeFlyer":
            ints[pk.KIND, j] = pk.FREE
            continue
        J = pin.computeJointJacobian(model, data, q0, j)[:, model.joints[j].idx_v]  # local frame: (v, w)
        revolute = np.linalg.norm(J[3:]) > 0.5
        ints[pk.KIND, j] = pk.REVOLUTE if revolute else pk.PRISMATIC
        floats[pk.AXIS : pk.AXIS + 3, j] = J[3:] if revolute else J[:3]
    ints[pk.PARENT, :nj] = model.parents
    ints[pk.IDX_Q, :nj] = [max(model.joints[j].idx_q, 0) for j in range(nj)]
    for g, o in enumerate(objects):
        ints[pk.BODY_JOINT, g] = o.parentJoint
        shape = o.geometry
        if isinstance(shape, coal.Capsule):
            floats[pk.HALF, g], floats[pk.RADIUS, g] = shape.halfLength, shape.radius
        elif isinstance(shape, coal.Sphere):
            floats[pk.RADIUS, g] = shape.radius
        elif isinstance(shape, coal.Cylinder):
            floats[pk.HALF, g], floats[pk.RADIUS, g] = shape.halfLength, shape.radius
            ints[pk.SHAPE, g] = pk.DISC
        else:
            raise UrdfError("<collision>", o.name, "the clearance query handles capsules, spheres and cylinders")
    ints[pk.FIRST, :npairs] = [p.first for p in geometry.collisionPairs]
    ints[pk.SECOND, :npairs] = [p.second for p in geometry.collisionPairs]
    platform = 0 if cones is None else cones.clm.platform_joint  # its placement turns the ball legs' axes
    first, second = ints[pk.FIRST, :npairs], ints[pk.SECOND, :npairs]
    plate = (ints[pk.SHAPE, first] == pk.DISC) | (ints[pk.SHAPE, second] == pk.DISC)
    ints[pk.ORDER, :npairs] = np.concatenate([np.flatnonzero(~plate), np.flatnonzero(plate)])
    reach = floats[pk.HALF] + floats[pk.RADIUS]
    floats[pk.REACH, :npairs] = reach[first] + reach[second]
    sizes = nj, ng, npairs, len(cardan), len(ball), platform, npairs - plate.sum(), pk.FLAGS + npairs
    ints[pk.SIZES, :8] = sizes
    joint_of_q = {model.joints[j].idx_q: j for j in range(1, nj)}
    for row, col in ((pk.CARDAN_A, 0), (pk.CARDAN_B, 1)):
        ints[row, : len(cardan)] = [joint_of_q[i] for i in cardan[:, col]]
    ints[pk.CARDAN_SLOT, : len(cardan)] = cardan[:, 2]
    for row, col in ((pk.BALL_SLOT, 0), (pk.BALL_SECOND, 1), (pk.BALL_TIP, 2)):
        ints[row, : len(ball)] = ball[:, col]
    floats[pk.LIMIT, :12] = np.inf if limits is None else np.asarray(limits, dtype=float).ravel()
    floats[pk.TIP : pk.TIP + 3, : len(tips)] = tips.T
    floats[pk.HOME : pk.HOME + 3, : len(home)] = home.T
    placements = [*model.jointPlacements, *(o.placement for o in objects)]
    ints[pk.SHIFT, : nj + ng] = [np.array_equal(M.rotation, np.eye(3)) for M in placements]
    ints[pk.UNIT, :nj] = -1
    for j in range(1, nj):
        unit = [k for k in range(3) if np.array_equal(floats[pk.AXIS : pk.AXIS + 3, j], np.eye(3)[k])]
        ints[pk.UNIT, j] = unit[0] if unit else -1
    frames = np.array([M.homogeneous for M in model.jointPlacements] + [o.placement.homogeneous for o in objects])
    return ints, floats, frames
