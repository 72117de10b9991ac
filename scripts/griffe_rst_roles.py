"""Griffe extension of the documentation site: the docstrings' reST roles as links to the API reference.

The docstrings name objects the Sphinx way (``:class:`~hexapod_model.kinematics.hexapod.Hexapod```,
``:mod:`.kernels```); mkdocstrings renders Markdown, where such a role would show as typed. This
extension, loaded by ``mkdocs.yml`` (``extensions`` of the Python handler), rewrites each role as
an optional mkdocs-autorefs cross-reference: a link to the name's entry in the API pages, shown
as code the way Sphinx shows it (``~`` keeps the last component only); a name the site does not
document (a private function) stays plain code. A relative name (``.kernels``, ``..rotations.x``)
is resolved against the package of the docstring's module, one level up per extra dot; a bare
one (``InputError``, ``Hexapod.forward``) as Python would in the docstring's scope (its imports,
its class), once the whole package is loaded.
"""

from __future__ import annotations

import html
import re
from typing import Any

import griffe

ROLE = re.compile(r":(?:mod|class|func|meth|data|attr|exc|obj):`(~?)([^`]+)`")
#: a Markdown code span (or reST literal) of a full dotted name of the package: a link as well
DOTTED = re.compile(r"(?<!`)``?(hexapod_model(?:\.\w+)+)``?(?!`)")


def identifier(name: str, package: str, known: frozenset[str] = frozenset()) -> str:
    """The dotted path ``name`` names from inside ``package`` (a leading dot: relative to it).

    With ``known`` (every documented path), a relative name not found under ``package`` is
    looked for in the packages around it, outward, as Sphinx does.
    """
    if not name.startswith("."):
        return name
    dots = len(name) - len(name.lstrip("."))
    parts = package.split(".")
    base = parts[: len(parts) - (dots - 1)] if dots > 1 else parts
    first = ".".join([*base, name[dots:]])
    if first in known or not known:
        return first
    for k in range(len(base) - 1, 0, -1):
        outer = ".".join([*base[:k], name[dots:]])
        if outer in known:
            return outer
    return first


def in_scope(name: str, scope: griffe.Object | None) -> str:
    """The dotted path of a bare ``name`` (``Hexapod.forward``) in ``scope``, or ``name`` when it does not resolve."""
    if scope is None or name.startswith(("hexapod_model.", ".")):
        return name
    head, _, rest = name.partition(".")
    try:
        path = scope.resolve(head)
    except Exception:  # noqa: BLE001 - griffe's NameResolutionError and friends: leave the name as written
        return name
    return f"{path}.{rest}" if rest else path


def markdown_roles(
    text: str, package: str = "hexapod_model", scope: griffe.Object | None = None, known: frozenset[str] = frozenset()
) -> str:
    """``text`` with every reST role as an optional cross-reference shown as code.

    Args:
        text: a docstring.
        package: the dotted package of the docstring's module (relative names start from it).
        scope: the documented object (bare names resolve in its scope), or None.
        known: every documented dotted path (relative names are looked for outward in them).
    """

    def link(match: re.Match) -> str:
        tilde, name = match.groups()
        shown = name.rsplit(".", 1)[-1] if tilde else name
        target = identifier(in_scope(name.lstrip("~"), scope), package, known)
        return f'<autoref identifier="{html.escape(target)}" optional><code>{html.escape(shown)}</code></autoref>'

    def dotted(match: re.Match) -> str:
        name = html.escape(match.group(1))
        return f'<autoref identifier="{name}" optional><code>{name}</code></autoref>'

    return DOTTED.sub(dotted, ROLE.sub(link, text))


def package_of(obj: griffe.Object) -> str:
    """The dotted package of ``obj``'s module: the module itself for an ``__init__``."""
    module = obj if obj.is_module else obj.module
    return module.path if module.is_package else module.path.rsplit(".", 1)[0]


def _objects(obj: griffe.Object):
    """``obj`` and every object it defines (not the names it imports)."""
    yield obj
    for member in obj.members.values():
        if not member.is_alias:
            yield from _objects(member)


class RstRoles(griffe.Extension):
    """Rewrite the roles of every docstring of the package, once it is loaded (its names resolve then)."""

    def on_package(self, *, pkg: griffe.Module, **kwargs: Any) -> None:
        """Called once the whole package is loaded."""
        objects = list(_objects(pkg))
        known = frozenset(obj.path for obj in objects)
        for obj in objects:
            if obj.docstring is not None:
                obj.docstring.value = markdown_roles(obj.docstring.value, package_of(obj), obj, known)
