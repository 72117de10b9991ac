"""The UR10 of example-robot-data: where its URDF and meshes are installed.

The robot cell's views (:mod:`hexapod_model.viz.robot_cell`) and the changeover planner
(:mod:`hexapod_model.planning.robot`) load the same files; each names the extra it comes with.
"""

from __future__ import annotations

from pathlib import Path

from ..exceptions import HexapodError
from ..extras import require_distribution

URDF_SUFFIX = "robots/ur_description/urdf/ur10_robot.urdf"


def ur10_files(extra: str, what: str | None = None) -> tuple[Path, Path]:
    """The UR10 URDF and the folder that resolves its ``package://`` mesh paths.

    Args:
        extra: the extra that installs example-robot-data for the caller (named in the install hint).
        what: what needs it, for the hint (default: the extra's description).

    Raises:
        MissingExtraError: example-robot-data is not installed.
        HexapodError: it is installed without the UR10.
    """
    dist = require_distribution("example-robot-data", extra, what)
    for f in dist.files or ():
        if str(f).endswith(URDF_SUFFIX):
            urdf = Path(str(dist.locate_file(f)))
            return urdf, urdf.parents[3]  # .../share/example-robot-data/robots
    raise HexapodError(f"example-robot-data is installed but has no {URDF_SUFFIX}")
