"""The package's layering: no import cycle, no printing, argv parsing or backend choice outside the CLI.

The layer order itself is an import-linter contract (``lint-imports``, in ``.ci/run``).
"""

from __future__ import annotations

import ast
from pathlib import Path

import grimp

PACKAGE = Path(__file__).resolve().parents[1] / "hexapod_model"


def test_no_import_cycle_deferred_imports_included():
    graph = grimp.build_graph("hexapod_model")  # grimp reads every import statement, in functions too
    cycles = []
    for module in sorted(graph.modules):
        for imported in graph.find_modules_directly_imported_by(module):
            chain = graph.find_shortest_chain(importer=imported, imported=module)
            if chain is not None and not module.startswith(imported + "."):  # a package importing its own module
                cycles.append(" -> ".join((module, *chain)))
    assert not cycles, "\n".join(cycles)


def _calls(tree: ast.AST) -> list[str]:
    names = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Call):
            f = node.func
            names.append(f.id if isinstance(f, ast.Name) else f.attr if isinstance(f, ast.Attribute) else "")
    return names


def _imports(tree: ast.AST) -> set[str]:
    names = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module:
            names.add(node.module)
            names.update(f"{node.module}.{a.name}" for a in node.names)
    return names


def test_library_never_prints_parses_argv_or_picks_a_backend():
    offenders = []
    for path in sorted(PACKAGE.rglob("*.py")):
        rel = path.relative_to(PACKAGE)
        if rel.parts[0] == "cli":
            continue
        text = path.read_text()
        tree = ast.parse(text)
        if "print" in _calls(tree):
            offenders.append(f"{rel}: print()")
        imported = _imports(tree)
        if "argparse" in imported or "sys.argv" in text:
            offenders.append(f"{rel}: argv parsing")
        if "matplotlib.pyplot" in imported or "matplotlib.use" in text:
            offenders.append(f"{rel}: picks a matplotlib backend / uses pyplot")
    assert not offenders, offenders
