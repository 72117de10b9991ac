"""One error family for the whole package.

Every error raised on purpose by :mod:`hexapod_model` derives from :class:`HexapodError`,
so ``except hm.HexapodError`` catches them all. Each subclass carries the offending value
(and, where there is one, the limit it broke) as attributes, and its message names both.
"""

from __future__ import annotations

from typing import Any


class HexapodError(Exception):
    """Base class of every error raised by hexapod_model."""


def brief_repr(value: Any, limit: int = 200) -> str:
    """``repr(value)`` on one line (arrays print on several), shortened to ``limit`` characters."""
    text = " ".join(repr(value).split())
    return text if len(text) <= limit else text[: limit - 3] + "..."


class _BadValue(HexapodError, ValueError):
    """A value that cannot be used, with where it was found and why; the message is one line.

    Subclasses name the location attribute (``_where``) and the message format.
    """

    _where = "where"
    _format = "{where}: {reason} ({value})"

    def __init__(self, where: str, value: Any, reason: str):
        setattr(self, self._where, where)
        self.value = value
        self.reason = reason
        one_line = " ".join(str(reason).splitlines())
        super().__init__(self._format.format(where=where, value=brief_repr(value), reason=one_line))


class GeometryError(_BadValue):
    """A geometry description (dataclass or file) is malformed.

    Attributes:
        field: dotted name of the bad field, e.g. ``"legs[2].stroke"``.
        value: the value found there.
    """

    _where = "field"
    field: str
    _format = "geometry field {where!r} = {value}: {reason}"


class UrdfError(_BadValue):
    """A URDF does not follow the hexapod contract (see docs/urdf_contract.md).

    Attributes:
        path: the file (or ``"<string>"``).
        value: the offending element, link or joint name.
    """

    _where = "path"
    path: str


class MjcfError(UrdfError):
    """An MJCF file does not follow the hexapod contract (see docs/mjcf.md).

    A :class:`UrdfError` too: both say that the model file cannot be used.
    """


class InputError(_BadValue):
    """A solver input is invalid: NaN/inf, wrong count, unknown joint name, bad pose matrix.

    Attributes:
        name: what the input is (``"lengths"``, ``"pose"``, ...).
        value: the offending value.
    """

    _where = "name"
    name: str
    _format = "invalid {where} {value}: {reason}"


class LimitError(HexapodError, ValueError):
    """A joint value lies outside its limit (leg stroke, Cardan angle, ...).

    Attributes:
        joint: the URDF joint name.
        value: the value (metres for prismatic joints, radians for revolute ones).
        lower, upper: the limit, same unit.
    """

    def __init__(self, joint: str, value: float, lower: float, upper: float, what: str = "joint"):
        self.joint = joint
        self.value = float(value)
        self.lower = float(lower)
        self.upper = float(upper)
        unit = "m" if what == "stroke" else "rad"
        super().__init__(
            f"{what} limit: {joint} = {self.value:.9g} {unit} is outside [{self.lower:.9g}, {self.upper:.9g}] {unit}"
        )


class SolverError(HexapodError, RuntimeError):
    """The Newton solver did not return a pose to use.

    Attributes:
        result: the :class:`hexapod_model.kinematics.newton.solver.Solution` with ``status`` saying why
            (``"max_iterations"``, ``"singular"``, ``"out_of_limits"``).
    """

    def __init__(self, result: Any, reason: str):
        self.result = result
        self.status = getattr(result, "status", None)
        super().__init__(reason)


class ConvergenceError(SolverError):
    """The solver hit its iteration limit before the residual reached the tolerance."""


class SingularityError(SolverError):
    """The constraint Jacobian is (numerically) singular: the pose is at or near a singularity."""


class WorkspaceError(SolverError):
    """The solution leaves the workspace: a stroke or Cardan angle limit is violated."""


class AssemblyError(SolverError):
    """Direct kinematics cannot certify which assembly the readings belong to.

    Status ``ambiguous_assembly`` (``result.candidates`` holds the poses of the assemblies
    found) or ``uncertified`` (``result.pose`` closes the loops near a singularity, but may be
    another assembly than the one connected to the start).
    """


class HexapodWarning(UserWarning):
    """Base class of every warning issued by hexapod_model."""


class CompileWarning(HexapodWarning):
    """The solver's kernels compile now: the first solve after installation waits for it, once.

    Issued once per process, before the first compilation (the ``hexapod_model.compile`` logger
    says each entry at INFO). Silence it with ``warnings.filterwarnings("ignore", category=CompileWarning)``.
    """


class InconsistentReadingsError(SolverError):
    """Redundant readings fail their chi-square consistency test (status ``inconsistent_readings``).

    ``result.consistency`` holds the statistic, its bound and the readings the fault may be on;
    the message names them (see docs/redundancy.md).
    """


class ViewError(HexapodError):
    """The 3-D scene cannot be built or shown (missing optional package, bad configuration)."""


class RenderError(ViewError):
    """Chromium is missing or failed to render a snapshot."""


class UnreachableError(HexapodError, ValueError):
    """The robot of the cell cannot put its flange at the requested pose.

    Attributes:
        target: the 4x4 flange target in the robot base frame.
        error: remaining pose error norm (m and rad mixed) when the IK stopped.
    """

    def __init__(self, target, error: float, reason: str):
        import numpy as np

        self.target = target
        self.error = float(error)
        super().__init__(
            f"UR10 cannot reach the tool-changer pose at {np.round(target[:3, 3], 4).tolist()} m "
            f"(robot base frame): {reason}"
        )
