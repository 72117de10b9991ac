"""Per-package line coverage of ``hexapod_model`` from a coverage data file, and the floor.

Reads the data a ``pytest --cov=hexapod_model`` run left (``.coverage`` by default), sums the
statements and the missed ones of every module under ``hexapod_model/`` per sub-package (a
module never imported counts with all its statements missed, so a new module is measured
without any configuration), prints a table, and exits 1 when the total is under
``[tool.coverage.report] fail_under`` of ``pyproject.toml``.

numba-compiled functions run as machine code, which coverage does not trace: their lines count
as covered only where a test runs the kernel as Python (the NumPy-path tests).

Usage: ``python scripts/coverage_table.py [--data-file .coverage]``
"""

from __future__ import annotations

import argparse
import sys
from collections import defaultdict
from pathlib import Path

import coverage

ROOT = Path(__file__).resolve().parent.parent
PACKAGE = ROOT / "hexapod_model"


def package_of(module: Path, package: Path = PACKAGE) -> str:
    """The sub-package a module file belongs to (``kinematics`` for ``kinematics/newton/x.py``), or ``(top)``."""
    parts = module.relative_to(package).parts
    return parts[0] if len(parts) > 1 else "(top)"


def per_package(cov: coverage.Coverage, package: Path = PACKAGE) -> dict[str, tuple[int, int]]:
    """Statements and missed statements per sub-package, over every ``.py`` file under ``package``."""
    sums: dict[str, list[int]] = defaultdict(lambda: [0, 0])
    for module in sorted(package.rglob("*.py")):
        _, statements, _, missing, _ = cov.analysis2(str(module))
        row = sums[package_of(module, package)]
        row[0] += len(statements)
        row[1] += len(missing)
    return {name: (n, m) for name, (n, m) in sorted(sums.items())}


def percent(statements: int, missed: int) -> float:
    """Covered share of ``statements`` in %, 100 for none."""
    return 100.0 * (statements - missed) / statements if statements else 100.0


def table(rows: dict[str, tuple[int, int]]) -> tuple[str, float]:
    """The printed table (one line a sub-package, then the total) and the total in %."""
    total_n = sum(n for n, _ in rows.values())
    total_m = sum(m for _, m in rows.values())
    width = max([len(name) for name in rows] + [len("TOTAL")])
    lines = [f"{'package':<{width}}  {'stmts':>6}  {'miss':>6}  {'cover':>6}"]
    lines += [f"{name:<{width}}  {n:>6}  {m:>6}  {percent(n, m):>5.1f}%" for name, (n, m) in rows.items()]
    total = percent(total_n, total_m)
    lines.append(f"{'TOTAL':<{width}}  {total_n:>6}  {total_m:>6}  {total:>5.1f}%")
    return "\n".join(lines), total


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data-file", default=".coverage", help="the coverage data file (default: .coverage)")
    args = parser.parse_args(argv)
    if not Path(args.data_file).is_file():
        print(f"coverage_table: no coverage data file {args.data_file}", file=sys.stderr)
        return 2
    cov = coverage.Coverage(data_file=args.data_file, config_file=str(ROOT / "pyproject.toml"))
    cov.load()
    text, total = table(per_package(cov))
    print(text)
    floor = float(cov.get_option("report:fail_under") or 0.0)  # type: ignore[arg-type]
    if total < floor:
        print(f"coverage_table: total coverage {total:.1f}% is under the floor {floor:.1f}%", file=sys.stderr)
        return 1
    print(f"total {total:.1f}% >= floor {floor:.1f}% ([tool.coverage.report] fail_under)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
