"""Load a hexapod URDF into Pinocchio, check the contract, and index what the solver needs.

:class:`ClosedLoopModel` holds

* ``model`` / ``data``: the Pinocchio model of the URDF tree (``nq``, ``nv`` as Pinocchio
  gives them; the platform is a free flyer whose configuration is relative to the home pose);
* ``constraints``: one Pinocchio ``FrameAnchorConstraintModel`` (``6d`` closure) or
  ``PointAnchorConstraintModel`` (``3d``) per leg, tip side first;
* index arrays of each leg's joints and of the measured prismatic joints;
* ``encoder_zero``, ``encoder_scale``: (6,) each leg's encoder model from the URDF's
  ``<encoder>`` elements (reading = zero + (1 + scale) * prismatic value; zeros without one).
"""

from __future__ import annotations

import functools
import xml.etree.ElementTree as ET
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pinocchio as pin

from ..exceptions import UrdfError
from .mjcf import COLLISION_GROUP
from .presets import PRESETS
from .urdf import Closure, read_closures, validate_urdf

_REVOLUTE = ("JointModelRX", "JointModelRY", "JointModelRZ", "JointModelRevoluteUnaligned")
_PRISMATIC = ("JointModelPX", "JointModelPY", "JointModelPZ", "JointModelPrismaticUnaligned")


def same_placement(a: pin.SE3, b: pin.SE3, tol: float = 1e-12) -> bool:
    """Whether two placements agree entry by entry to ``tol`` (m and rotation-matrix entries)."""
    return bool(np.max(np.abs(a.homogeneous - b.homogeneous)) <= tol)


@dataclass(frozen=True)
class Leg:
    """Indices of one leg in the Pinocchio model (joint ids, and their q / v indices)."""

    name: str
    joints: tuple[int, ...]  # base -> tip
    prismatic: int  # joint id of the measured joint
    tip_frame: int
    anchor_frame: int


class ClosedLoopModel:
    """A hexapod URDF loaded in Pinocchio with its six loop closures.

    Args:
        urdf_xml: the URDF text.
        source: file name used in error messages.

    Raises:
        UrdfError: the URDF breaks the contract (no or several floating joints, a missing
            closure link, a leg with zero or two prismatic joints, a continuous joint, a
            zero configuration that is not assembled, ...).
    """

    def __init__(self, urdf_xml: str, source: str = "<string>"):
        self.source = source
        self.urdf_xml: str | None = urdf_xml
        self.mjcf_xml: str | None = None
        closures = read_closures(urdf_xml, source)
        try:
            model = pin.buildModelFromXML(urdf_xml)
        except (RuntimeError, ValueError) as exc:
            validate_urdf(urdf_xml, source)  # a clearer message when the file breaks the URDF format
            raise UrdfError(source, str(exc).strip()[:200], "Pinocchio cannot parse the URDF") from None
        self._setup(model, closures)

    @classmethod
    def from_pinocchio(
        cls,
        model: pin.Model,
        closures: Sequence[Closure],
        constraints: Sequence | None = None,
        source: str = "<model>",
    ) -> ClosedLoopModel:
        """A hexapod from a Pinocchio model built elsewhere (e.g. by Pinocchio's MJCF parser).

        The model must follow the URDF contract's rules: one free flyer from the root whose
        joint placement is the home pose (its configuration relative to home), six legs of
        revolute and prismatic joints, and a zero configuration that closes every loop.

        Args:
            model: the Pinocchio model (kept, not copied).
            closures: one per leg, in leg order; ``link1``/``link2`` name the tip and anchor frames.
            constraints: Pinocchio's constraint models of the closures, same order (e.g. those
                its MJCF parser returns); ``None`` builds them from the frames. They must join
                the frames' joints.
            source: file name used in error messages.

        Raises:
            UrdfError: the model breaks the contract, or a constraint joins other joints than
                its closure's frames.
        """
        self = cls.__new__(cls)
        self.source = source
        self.urdf_xml = self.mjcf_xml = None
        self._setup(model, list(closures), constraints)
        return self

    def _setup(self, model: pin.Model, closures: list[Closure], constraints: Sequence | None = None) -> None:
        """Check the contract on ``model`` and index legs, limits and closures."""
        source = self.source
        self.closures: list[Closure] = closures
        self.model = model
        self.data = self.model.createData()
        m = self.model
        ff = [j for j in range(1, m.njoints) if m.joints[j].shortname() == "JointModelFreeFlyer"]
        if len(ff) != 1:
            raise UrdfError(source, len(ff), "need exactly one floating joint carrying the platform")
        self.platform_joint = ff[0]
        if m.parents[self.platform_joint] != 0:
            raise UrdfError(source, m.names[self.platform_joint], "the floating joint must hang from the root link")
        for j in range(1, m.njoints):
            kind = m.joints[j].shortname()
            if j != self.platform_joint and kind not in _REVOLUTE + _PRISMATIC:
                raise UrdfError(
                    source, m.names[j], f"unsupported joint type {kind} (use revolute with limits or prismatic)"
                )
        if len(self.closures) != 6:
            raise UrdfError(source, len(self.closures), "a hexapod needs exactly 6 loop_closure elements")
        kinds = {c.kind for c in self.closures}
        if len(kinds) != 1:
            raise UrdfError(source, sorted(kinds), "all closures must have the same type")
        self.kind = kinds.pop()
        self.legs = tuple(self._leg(c) for c in self.closures)
        used = [j for leg in self.legs for j in leg.joints]
        if len(used) != len(set(used)):
            raise UrdfError(source, "legs", "two legs share a joint; each leg must be its own chain")
        if constraints is None:
            self.constraints = [self._constraint(leg) for leg in self.legs]
        else:
            self.constraints = self._given_constraints(constraints)
        self.constraint_datas = [c.createData() for c in self.constraints]
        self.q_home = pin.neutral(m)
        self.nq, self.nv = m.nq, m.nv
        self.lower = m.lowerPositionLimit.copy()
        self.upper = m.upperPositionLimit.copy()
        self.prismatic_q = np.array([m.joints[leg.prismatic].idx_q for leg in self.legs])
        self.prismatic_v = np.array([m.joints[leg.prismatic].idx_v for leg in self.legs])
        self.platform_q = m.joints[self.platform_joint].idx_q
        self.platform_v = m.joints[self.platform_joint].idx_v
        self.home = m.jointPlacements[self.platform_joint].copy()
        found = read_encoders(self.urdf_xml, source) if self.urdf_xml is not None else {}
        self.encoder_zero, self.encoder_scale = self._encoders(found)  # MJCF carries none
        self._check_assembled()

    @classmethod
    def from_file(cls, path: str | Path) -> ClosedLoopModel:
        """Load the URDF file ``path``."""
        path = Path(path)
        try:
            text = path.read_text()
        except OSError as exc:
            # a misspelt preset name reaches here as a file name: name the presets too
            presets = f"; nor a preset ({', '.join(PRESETS)})" if isinstance(exc, FileNotFoundError) else ""
            raise UrdfError(str(path), str(path), f"cannot read URDF: {exc.strerror}{presets}") from None
        return cls(text, str(path))

    # ----- construction steps -----
    def _leg(self, c: Closure) -> Leg:
        m = self.model
        tip, anchor = m.getFrameId(c.link1), m.getFrameId(c.link2)
        if tip >= len(m.frames) or anchor >= len(m.frames):
            raise UrdfError(
                self.source,
                c.link1 if tip >= len(m.frames) else c.link2,
                f"closure {c.name}: link not found in the Pinocchio model",
            )
        if m.frames[anchor].parentJoint != self.platform_joint:
            raise UrdfError(self.source, c.link2, f"closure {c.name}: link2 must be fixed to the platform")
        chain = []
        j = m.frames[tip].parentJoint
        while j != 0:
            if j == self.platform_joint:
                raise UrdfError(self.source, c.link1, f"closure {c.name}: link1 must be a leg tip, not on the platform")
            chain.append(j)
            j = m.parents[j]
        prismatic = [j for j in chain if m.joints[j].shortname() in _PRISMATIC]
        if len(prismatic) != 1:
            raise UrdfError(
                self.source,
                [m.names[j] for j in prismatic] or c.link1,
                f"closure {c.name}: the leg chain must hold exactly one prismatic joint, found {len(prismatic)}",
            )
        return Leg(c.name, tuple(reversed(chain)), prismatic[0], tip, anchor)

    def _encoders(self, found: dict[str, tuple[float, float]]) -> tuple[np.ndarray, np.ndarray]:
        """(6,) zero (m) and scale of each leg's reading, from the ``<encoder>`` elements."""
        names = [self.model.names[leg.prismatic] for leg in self.legs]
        stray = sorted(set(found) - set(names))
        if stray:
            raise UrdfError(self.source, stray[0], "an <encoder> must name a leg's prismatic joint")
        zero = np.array([found.get(n, (0.0, 0.0))[0] for n in names])
        return zero, np.array([found.get(n, (0.0, 0.0))[1] for n in names])

    def _constraint(self, leg: Leg):
        m = self.model
        f1, f2 = m.frames[leg.tip_frame], m.frames[leg.anchor_frame]
        cls = pin.FrameAnchorConstraintModel if self.kind == "6d" else pin.PointAnchorConstraintModel
        c = cls(m, f1.parentJoint, f1.placement, f2.parentJoint, f2.placement)
        c.name = leg.name
        return c

    def _given_constraints(self, constraints: Sequence) -> list:
        """``constraints`` checked against the legs: one per leg, of the closure kind, joining its frames."""
        cls = pin.FrameAnchorConstraintModel if self.kind == "6d" else pin.PointAnchorConstraintModel
        out = list(constraints)
        if len(out) != len(self.legs):
            raise UrdfError(self.source, len(out), f"need one constraint model per closure ({len(self.legs)})")
        m = self.model
        for c, leg in zip(out, self.legs):
            f1, f2 = m.frames[leg.tip_frame], m.frames[leg.anchor_frame]
            if not (
                isinstance(c, cls)
                and (c.joint1_id, c.joint2_id) == (f1.parentJoint, f2.parentJoint)
                and same_placement(c.joint1_placement, f1.placement)
                and same_placement(c.joint2_placement, f2.placement)
            ):
                raise UrdfError(
                    self.source, leg.name, f"the constraint model is not a {cls.__name__} joining the closure frames"
                )
            c.name = leg.name
        return out

    def _check_assembled(self) -> None:
        err = self.closure_errors(self.q_home)
        worst = int(np.argmax(err))
        if err[worst] > 1e-9:
            raise UrdfError(
                self.source,
                f"{self.legs[worst].name}: {err[worst]:.3g}",
                "the zero configuration does not close the loop "
                "(contract: all leg joints at zero close every loop at home)",
            )

    # ----- queries -----
    def closure_errors(self, q: np.ndarray) -> np.ndarray:
        """Per-leg closure error through Pinocchio's constraint models.

        Per-leg closure error norm (log6 for 6d, point distance for 3d) at ``q``, through
        Pinocchio's constraint models (the slow, reference path; data of its own per call, so
        that threads may share the model).
        """
        data = self.model.createData()
        pin.computeJointJacobians(self.model, data, q)
        out = np.empty(6)
        for i, c in enumerate(self.constraints):
            cd = c.createData()
            c.calc(self.model, data, cd)
            M = cd.c1Mc2
            out[i] = np.linalg.norm(pin.log6(M).vector if self.kind == "6d" else M.translation)
        return out

    def joint_name_of_q(self, iq: int) -> str:
        """URDF joint name owning configuration index ``iq``."""
        if not 0 <= iq < len(self._q_joint_names):
            raise IndexError(iq)
        return self._q_joint_names[iq]

    @functools.cached_property
    def _q_joint_names(self) -> tuple[str, ...]:
        """The joint name of each configuration index (the joints' layout is fixed once loaded)."""
        m = self.model
        names = [""] * m.nq
        for j in range(1, m.njoints):
            joint = m.joints[j]
            names[joint.idx_q : joint.idx_q + joint.nq] = [m.names[j]] * joint.nq
        return tuple(names)

    def visual_model(self) -> pin.GeometryModel:
        """Pinocchio's visual geometry of the hexapod, from its URDF or MJCF text."""
        if self.urdf_xml is not None:
            return pin.buildGeomFromUrdfString(self.model, self.urdf_xml, pin.GeometryType.VISUAL)
        if self.mjcf_xml is None:
            return pin.GeometryModel()
        import tempfile

        from .mjcf import FLOOR

        with tempfile.TemporaryDirectory() as tmp:  # Pinocchio reads MJCF from files only
            path = Path(tmp) / "hexapod.xml"
            path.write_text(self.mjcf_xml)
            visual = pin.buildGeomFromMJCF(self.model, str(path), pin.GeometryType.VISUAL)
        hexapod = pin.GeometryModel()  # without the exported scene's floor nor the collision bodies: not drawn
        hidden = {
            str(el.get("name"))
            for el in ET.fromstring(self.mjcf_xml).iter("geom")
            if el.get("group") == str(COLLISION_GROUP)
        }
        for g in visual.geometryObjects:
            if not (g.name == FLOOR and g.parentJoint == 0) and g.name not in hidden:
                hexapod.addGeometryObject(g.copy())
        return hexapod

    def limited_q(self) -> np.ndarray:
        """Indices of q that carry finite joint limits (all leg joints)."""
        return np.array([m_j.idx_q for leg in self.legs for m_j in (self.model.joints[j] for j in leg.joints)])


def read_encoders(urdf_xml: str, source: str = "<string>") -> dict[str, tuple[float, float]]:
    """``joint name -> (zero, scale)`` of the robot-level ``<encoder>`` elements.

    ``<encoder joint="leg1_prismatic" zero="0.001" scale="0"/>`` says that leg 1's reading is
    ``zero + (1 + scale) * q`` for its prismatic joint value ``q`` (m); legs without one read ``q``.

    Raises:
        UrdfError: malformed XML, a missing or non-numeric attribute, a scale outside
            (-0.5, 0.5), or two elements for the same joint.
    """
    try:
        root = ET.fromstring(urdf_xml)
    except ET.ParseError as exc:
        raise UrdfError(source, str(exc), "not well-formed XML") from None
    out: dict[str, tuple[float, float]] = {}
    for el in root.findall("encoder"):
        text = ET.tostring(el, encoding="unicode").strip()
        joint = el.get("joint")
        try:
            zero, scale = float(el.get("zero", "0")), float(el.get("scale", "0"))
        except ValueError:
            raise UrdfError(source, text, "encoder zero and scale must be numbers") from None
        if not joint or not (np.isfinite(zero) and abs(scale) < 0.5):
            raise UrdfError(source, text, "encoder needs a joint, a finite zero (m) and |scale| < 0.5")
        if joint in out:
            raise UrdfError(source, joint, "two <encoder> elements for the same joint")
        out[joint] = (zero, scale)
    return out
