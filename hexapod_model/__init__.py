"""hexapod_model: leg readings <-> platform pose for Stewart-Gough hexapods with offset Cardan joints.

Quick start::

    import hexapod_model as hm
    hexa = hm.Hexapod.from_preset("reference")     # or hm.Hexapod.from_urdf("my.urdf")
    sol = hexa.forward(lengths)                     # sol.pose: 4x4 base -> platform (m)
    back = hexa.inverse(sol.pose)                   # back.lengths (m)
"""

from ._version import __version__
from .description.geometry import HexapodGeometry, LegGeometry, geometry_from_dict, load_geometry
from .description.mjcf import geometry_to_mjcf, urdf_to_mjcf
from .description.presets import DEFAULT_PRESET, PRESETS, get_preset
from .description.urdf import geometry_to_urdf, read_closures, write_urdf
from .exceptions import (
    AssemblyError,
    CompileWarning,
    ConvergenceError,
    GeometryError,
    HexapodError,
    HexapodWarning,
    InconsistentReadingsError,
    InputError,
    LimitError,
    MjcfError,
    RenderError,
    SingularityError,
    SolverError,
    UnreachableError,
    UrdfError,
    ViewError,
    WorkspaceError,
)
from .kinematics.batch import BatchResult
from .kinematics.hexapod import Hexapod, load_hexapod
from .kinematics.newton.solver import STATUSES, Solution

__all__ = [
    "AssemblyError",
    "CompileWarning",
    "ConvergenceError",
    "GeometryError",
    "HexapodError",
    "HexapodWarning",
    "InconsistentReadingsError",
    "InputError",
    "LimitError",
    "MjcfError",
    "RenderError",
    "SingularityError",
    "SolverError",
    "UnreachableError",
    "UrdfError",
    "ViewError",
    "WorkspaceError",
    "HexapodGeometry",
    "LegGeometry",
    "geometry_from_dict",
    "load_geometry",
    "Hexapod",
    "BatchResult",
    "load_hexapod",
    "DEFAULT_PRESET",
    "PRESETS",
    "get_preset",
    "STATUSES",
    "Solution",
    "geometry_to_urdf",
    "read_closures",
    "write_urdf",
    "geometry_to_mjcf",
    "urdf_to_mjcf",
    "__version__",
]
