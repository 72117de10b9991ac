"""Griffe extension of the documentation site: the docstrings' reST roles as links to the API reference.

The docstrings name objects the Sphinx way (``:class:`~hexapod_model.kinematics.hexapod.Hexapod```,
``:mod:`.kernels```); mkdocstrings renders Markdown, where such a role would show as typed. This
extension, loaded by ``mkdocs.yml`` (``extensions`` of the Python handler), rewrites each role as
an optional mkdocs-autorefs cross-reference: a link to the name's entry in the API pages, shown
as code the way Sphinx shows it (``~`` keeps the last component only); a name the site does not
document (a private helper) stays plain code. A relative name (``.kernels``, ``..rotations.x``)
is resolved against the package of the docstring's module, one level up per extra dot.
"""

from __future__ import annotations

import html
import re
from typing import Any

import griffe

ROLE = re.compile(r":(?:mod|class|func|meth|data|attr|exc|obj):`(~?)([^`]+)`")


def identifier(name: str, package: str) -> str:
    """The dotted path ``name`` names from inside ``package`` (a leading dot: relative to it)."""
    if not name.startswith("."):
        return name
    dots = len(name) - len(name.lstrip("."))
    parts = package.split(".")
    base = parts[: len(parts) - (dots - 1)] if dots > 1 else parts
    return ".".join([*base, name[dots:]])


def markdown_roles(text: str, package: str = "hexapod_model") -> str:
    """``text`` with every reST role as an optional cross-reference shown as code.

    Args:
        text: a docstring.
        package: the dotted package of the docstring's module (relative names start from it).
    """

    def link(match: re.Match) -> str:
        tilde, name = match.groups()
        shown = name.rsplit(".", 1)[-1] if tilde else name
        target = identifier(name.lstrip("~"), package)
        return f'<autoref identifier="{html.escape(target)}" optional><code>{html.escape(shown)}</code></autoref>'

    return ROLE.sub(link, text)


def package_of(obj: griffe.Object) -> str:
    """The dotted package of ``obj``'s module: the module itself for an ``__init__``."""
    module = obj if obj.is_module else obj.module
    return module.path if module.is_package else module.path.rsplit(".", 1)[0]


class RstRoles(griffe.Extension):
    """Rewrite the roles of every docstring griffe reads."""

    def on_instance(self, *, obj: griffe.Object, **kwargs: Any) -> None:
        """Called for each module, class, function and attribute."""
        if obj.docstring is not None:
            obj.docstring.value = markdown_roles(obj.docstring.value, package_of(obj))
