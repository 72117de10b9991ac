"""Read a ``cardan`` geometry back off a URDF (so that a URDF can be the nominal of a calibration).

Works for URDFs with the leg layout ``hexapod urdf`` writes for cardan legs (revolute,
revolute, revolute, prismatic, revolute, revolute; 6-D closures; the home pose a pure
translation along z). At home, each joint's axis is read from its world Jacobian column; the
centres are the midpoints of the common normals of the two base and the two platform axes,
the offsets their lengths, the fixed axes those of the first and the last revolute joint.
The result is checked: its direct kinematics must match the URDF's on a few readings.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from ..exceptions import GeometryError, UrdfError
from .geometry import HexapodGeometry, LegGeometry
from .model import ClosedLoopModel
from .urdf import geometry_to_urdf

LAYOUT = ("R", "R", "R", "P", "R", "R")


def _line(J: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Unit axis and the point nearest the origin of a revolute joint's world twist column."""
    w = J[3:]
    w = w / np.linalg.norm(w)
    return w, np.cross(w, J[:3])


def _common_normal(a: tuple[np.ndarray, np.ndarray], b: tuple[np.ndarray, np.ndarray]) -> tuple[np.ndarray, float]:
    """Midpoint and length of the common normal of two lines (unit direction, point)."""
    (u, p), (v, q) = a, b
    n = np.cross(u, v)
    if np.linalg.norm(n) < 1e-9:
        raise UrdfError("<urdf>", "Cardan axes", "the two axes of a Cardan joint are parallel")
    A = np.column_stack([u, -v])
    s, t = np.linalg.lstsq(A, q - p, rcond=None)[0]
    x, y = p + s * u, q + t * v
    return (x + y) / 2, float(np.linalg.norm(y - x))


def geometry_of_urdf(clm: ClosedLoopModel) -> HexapodGeometry:
    """The :class:`HexapodGeometry` whose generated URDF has the same kinematics as ``clm``.

    Raises:
        UrdfError: not the generated cardan layout, a home pose that is not a z translation, or
            a geometry whose kinematics differ from the URDF's.
    """
    m = clm.model
    home = clm.home
    if clm.kind != "6d" or not np.allclose(home.rotation, np.eye(3), atol=1e-12) or np.any(home.translation[:2]):
        raise UrdfError(clm.source, "platform_joint", "a calibration nominal needs cardan legs and a home pose on z")
    d = m.createData()
    pin.computeJointJacobians(m, d, clm.q_home)
    legs = []
    for leg in clm.legs:
        kinds = tuple("P" if "JointModelP" in m.joints[j].shortname() else "R" for j in leg.joints)
        if kinds != LAYOUT:
            raise UrdfError(clm.source, leg.name, f"joint layout {''.join(kinds)}: calibration reads {''.join(LAYOUT)}")
        lines = {k: _line(d.J[:, m.joints[leg.joints[k]].idx_v]) for k in (0, 1, 4, 5)}
        b, eb = _common_normal(lines[0], lines[1])
        p, ep = _common_normal(lines[4], lines[5])
        k = int(np.flatnonzero(clm.prismatic_q == m.joints[leg.prismatic].idx_q)[0])
        legs.append(
            LegGeometry(
                base_anchor=tuple(b),
                platform_anchor=tuple(p - home.translation),
                stroke=(
                    float(clm.lower[m.joints[leg.prismatic].idx_q]),
                    float(clm.upper[m.joints[leg.prismatic].idx_q]),
                ),
                base_axis=tuple(lines[0][0]),
                platform_axis=tuple(lines[5][0]),
                base_offset=eb,
                platform_offset=ep,
                encoder_zero=float(clm.encoder_zero[k]),
                encoder_scale=float(clm.encoder_scale[k]),
            )
        )
    revolute = [m.joints[j].idx_q for j in clm.legs[0].joints if "JointModelR" in m.joints[j].shortname()]
    try:
        geom = HexapodGeometry(
            name=m.name or "from_urdf",
            joint_type="cardan",
            legs=tuple(legs),
            home_height=float(home.translation[2]),
            base_offset=legs[0].base_offset or 0.0,
            platform_offset=legs[0].platform_offset or 0.0,
            cardan_limit=float(clm.upper[revolute[0]]),
            roll_limit=float(clm.upper[revolute[2]]),
        )
    except GeometryError as exc:
        raise UrdfError(clm.source, exc.field, f"no geometry file describes it: {exc.reason}") from None
    _check_same(clm, geom)
    return geom


def _check_same(clm: ClosedLoopModel, geom: HexapodGeometry) -> None:
    """Refuse a geometry whose generated URDF does not put every joint axis where ``clm`` has it.

    Compared at home: a joint's world twist column fixes its line; a reversed axis negates it.
    """
    other = ClosedLoopModel(geometry_to_urdf(geom), f"<geometry of {clm.source}>")
    cols = []
    for model in (clm, other):
        J = pin.computeJointJacobians(model.model, model.model.createData(), model.q_home)
        cols.append([J[:, [model.model.joints[j].idx_v for j in leg.joints]] for leg in model.legs])
    for leg, a, b in zip(clm.legs, *cols):
        if not all(np.allclose(x, y, atol=1e-9) or np.allclose(x, -y, atol=1e-9) for x, y in zip(a.T, b.T)):
            raise UrdfError(clm.source, leg.name, "cannot read an equivalent geometry off this URDF")
