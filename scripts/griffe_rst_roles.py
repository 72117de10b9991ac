"""Griffe extension of the documentation site: the docstrings' reST roles as Markdown code.

The docstrings name objects the Sphinx way (``:class:`~hexapod_model.kinematics.hexapod.Hexapod```,
``:mod:`.kernels```); mkdocstrings renders Markdown, where such a role would show as typed. This
extension, loaded by ``mkdocs.yml`` (``extensions`` of the Python handler), rewrites each role as
a code span of the name as Sphinx would show it (``~`` keeps the last component only).
"""

from __future__ import annotations

import re
from typing import Any

import griffe

ROLE = re.compile(r":(?:mod|class|func|meth|data|attr|exc|obj):`(~?)([^`]+)`")


def as_code(match: re.Match) -> str:
    """One role as a Markdown code span."""
    tilde, name = match.groups()
    return f"`{name.rsplit('.', 1)[-1] if tilde else name}`"


def markdown_roles(text: str) -> str:
    """``text`` with every reST role as a code span."""
    return ROLE.sub(as_code, text)


class RstRoles(griffe.Extension):
    """Rewrite the roles of every docstring griffe reads."""

    def on_instance(self, *, obj: griffe.Object, **kwargs: Any) -> None:
        """Called for each module, class, function and attribute."""
        if obj.docstring is not None:
            obj.docstring.value = markdown_roles(obj.docstring.value)
