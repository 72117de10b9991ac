"""Regenerate urdf/<preset>.urdf for every bundled preset (run after changing the generator).

    python scripts/generate_urdfs.py [--check]

With --check nothing is written; the exit code is 1 when a file differs from the generator
(tests/test_urdf.py runs the same comparison).
"""

from __future__ import annotations

import argparse
from pathlib import Path

from hexapod_model.description.presets import PRESETS, get_preset
from hexapod_model.description.urdf import geometry_to_urdf

URDF_DIR = Path(__file__).resolve().parent.parent / "urdf"


def expected_files() -> dict[Path, str]:
    """Path -> text the generator writes for every preset."""
    return {URDF_DIR / f"{name}.urdf": geometry_to_urdf(get_preset(name)) for name in PRESETS}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--check", action="store_true", help="compare only, write nothing")
    args = ap.parse_args(argv)
    stale = []
    for path, text in expected_files().items():
        if not path.exists() or path.read_text() != text:
            stale.append(path)
            if not args.check:
                path.parent.mkdir(parents=True, exist_ok=True)
                path.write_text(text)
    verb = "differ from the generator" if args.check else "rewritten"
    for path in stale:
        print(f"{path.name}: {verb}")
    return 1 if (args.check and stale) else 0


if __name__ == "__main__":
    raise SystemExit(main())
