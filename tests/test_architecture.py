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


#: underscored names that are a public API: the namedtuple methods, and documented module functions
PUBLIC_UNDERSCORED = {
    "_replace": "namedtuple's documented method",
    "_fields": "namedtuple's documented attribute",
    "_asdict": "namedtuple's documented method",
    "os._exit": "documented: exit without cleanup (the service's second Ctrl-C)",
}
#: reaches into a third-party object's privates where it has no public API, by module, with the reason
ALLOWED_PRIVATE = {
    ("cli/main.py", "_get_subactions"): "argparse has no public list of a sub-parsers action's help entries",
    ("kinematics/newton/first_compile.py", "_cache"): "numba has no public query of a dispatcher's cache index",
    ("kinematics/newton/first_compile.py", "_cache_file"): "numba has no public query of a dispatcher's cache index",
    ("kinematics/newton/first_compile.py", "_index_path"): "numba has no public query of a dispatcher's cache index",
    ("kinematics/newton/views.py", "_getvalue"): "numba's documented way to read a struct proxy's LLVM value (cgutils)",
}
#: argparse's type of ``add_subparsers()``'s result has no public name (the sub-commands annotate with it)
ALLOWED_ANYWHERE = {"argparse._SubParsersAction"}


def _private(name: str) -> bool:
    return name.startswith("_") and not name.startswith("__")


def _defined_names(tree: ast.AST) -> set[str]:
    """Every name a module defines: functions, classes, arguments, assigned names and attributes."""
    names = set()
    for node in ast.walk(tree):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            names.add(node.name)
        elif isinstance(node, ast.arg):
            names.add(node.arg)
        elif isinstance(node, ast.Name) and isinstance(node.ctx, ast.Store):
            names.add(node.id)
        elif isinstance(node, ast.Attribute) and isinstance(node.ctx, (ast.Store, ast.Del)):
            names.add(node.attr)
    return names


def _reaches(tree: ast.AST, rel: str) -> list[str]:
    """The module-level ``Name = Any`` aliases and the reaches into another module's private names of ``tree``."""
    found = []
    for node in tree.body if isinstance(tree, ast.Module) else ():
        if isinstance(node, (ast.Assign, ast.AnnAssign)) and isinstance(node.value, (ast.Name, ast.Attribute)):
            value = node.value.id if isinstance(node.value, ast.Name) else node.value.attr
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            for t in targets:
                if value == "Any" and isinstance(t, ast.Name) and t.id[:1].isupper():
                    found.append(f"{rel}:{node.lineno}: {t.id} = Any")
    own = _defined_names(tree)
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            for alias in node.names:
                if _private(alias.name):
                    found.append(f"{rel}:{node.lineno}: from {'.' * node.level}{node.module or ''} import {alias.name}")
        elif isinstance(node, ast.Attribute) and isinstance(node.ctx, ast.Load) and _private(node.attr):
            if isinstance(node.value, ast.Name) and node.value.id in ("self", "cls"):
                continue
            text = ast.unparse(node)
            if node.attr in own or node.attr in PUBLIC_UNDERSCORED or text in PUBLIC_UNDERSCORED:
                continue
            if (rel, node.attr) in ALLOWED_PRIVATE or text in ALLOWED_ANYWHERE:
                continue
            found.append(f"{rel}:{node.lineno}: {text}")
    return found


def test_no_any_alias_and_no_private_reach():
    """No ``Name = Any`` stands in for a project class, and no module reads another module's ``_private`` names.

    A module may use the private names it defines itself (its helpers, its own classes'
    attributes); ``self._x`` and ``cls._x`` are the object's own.
    """
    offenders = []
    for path in sorted(PACKAGE.rglob("*.py")):
        rel = path.relative_to(PACKAGE).as_posix()
        offenders += _reaches(ast.parse(path.read_text()), rel)
    assert not offenders, "\n".join(offenders)


def test_the_private_reach_rules_flag_what_they_say():
    source = """
from typing import Any
from .other import _helper, public
Engine = Any
lower = Any
class Own:
    def __init__(self, other):
        self._mine = 1
        other._theirs()
        self._mine.bit
        other._mine
        cls_free = type(self)._mine
"""
    found = [line.split(": ", 1)[1] for line in _reaches(ast.parse(source), "m.py")]
    assert found == ["Engine = Any", "from .other import _helper", "other._theirs"]
