"""hexapod_model: leg readings <-> platform pose for Stewart-Gough hexapods with offset Cardan joints.

Quick start::

    import hexapod_model as hm
    hexa = hm.Hexapod.from_preset("reference")     # or hm.Hexapod.from_urdf("my.urdf")
    sol = hexa.forward(lengths)                     # sol.pose: 4x4 base -> platform (m)
    back = hexa.inverse(sol.pose)                   # back.lengths (m)
"""

from .exceptions import (ConvergenceError, GeometryError, HexapodError, InputError, LimitError, RenderError,
                         SingularityError, SolverError, UnreachableError, UrdfError, ViewError, WorkspaceError)
from .geometry import HexapodGeometry, LegGeometry, geometry_from_dict, load_geometry
from .hexapod import Hexapod
from .presets import DEFAULT_PRESET, PRESETS, get_preset
from .solver import STATUSES, Solution
from .urdf import geometry_to_urdf, read_closures, write_urdf

__version__ = "0.1.0"

__all__ = [
    "ConvergenceError", "GeometryError", "HexapodError", "InputError", "LimitError", "RenderError",
    "SingularityError", "SolverError", "UnreachableError", "UrdfError", "ViewError", "WorkspaceError", "HexapodGeometry", "LegGeometry", "geometry_from_dict",
    "load_geometry", "Hexapod", "DEFAULT_PRESET", "PRESETS", "get_preset", "STATUSES", "Solution",
    "geometry_to_urdf", "read_closures", "write_urdf", "__version__",
]
