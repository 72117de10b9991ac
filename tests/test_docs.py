"""The README and the docs pages are true to the code: their Python runs, their names and links resolve.

Each check is a function over a text, tested here on the repository's files and on a text with
an injected fault (a failing block, a bad dotted path, a dead link, a development-process word),
so that a check that can no longer fail is noticed.
"""

from __future__ import annotations

import importlib
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
README = ROOT / "README.md"
DOC_PAGES = sorted((ROOT / "docs").rglob("*.md"))
MARKDOWN = [README, ROOT / "CONTRIBUTING.md", *DOC_PAGES]

#: words about how the product was developed, not about the product (a browser's session storage is
#: the product's)
PROCESS_WORDS = re.compile(
    r"\bsessions?\b(?! storage)|\bissues? ?#?\d+|\(issue\b|\bhelpers?\b|\bthis round\b|\bother developers?\b",
    re.IGNORECASE,
)
#: the files a user reads or runs: every text file of these folders and these files
PRODUCT_FOLDERS = ("hexapod_model", "docs", "examples", "benchmarks", "scripts")
PRODUCT_FILES = ("README.md", "CONTRIBUTING.md", "CITATION.cff", "mkdocs.yml", "pyproject.toml")
TEXT_SUFFIXES = {".py", ".md", ".toml", ".yml", ".yaml", ".csv", ".cff", ".txt", ".json"}


def python_blocks(text: str) -> list[str]:
    """The fenced ```python blocks of a Markdown text, in order."""
    return re.findall(r"^```python\n(.*?)^```", text, re.S | re.M)


def run_blocks(text: str, cwd: Path) -> subprocess.CompletedProcess:
    """Run the text's Python blocks in order as one script, in a fresh interpreter in ``cwd``."""
    env = {**os.environ, "PYTHONPATH": str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", "")}
    script = "\n".join(python_blocks(text))
    return subprocess.run([sys.executable, "-c", script], cwd=cwd, env=env, capture_output=True, text=True, timeout=600)


def dotted_paths(text: str) -> set[str]:
    """Every ``hexapod_model.a.b`` named in a text (not a logger's name: "the `hexapod_model.x` logger")."""
    return set(re.findall(r"\bhexapod_model(?:\.[A-Za-z_]\w*)++(?!`? logger)", text))


def _module_file_exists(dotted: str) -> bool:
    """Whether ``dotted`` names a module file (found without running it)."""
    try:
        return importlib.util.find_spec(dotted) is not None
    except (ImportError, ValueError):  # a parent is not a package
        return False


def resolves(dotted: str) -> bool:
    """Whether ``dotted`` is an importable module, or an attribute reached from the longest one."""
    parts = dotted.split(".")
    for k in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:k]))
        except ImportError:
            if k == len(parts) and _module_file_exists(dotted):
                return True  # a module that imports an extra's package (e.g. the ros extra's cyclonedds)
            continue
        try:
            for name in parts[k:]:
                obj = getattr(obj, name)
        except AttributeError:
            return False
        return True
    return False


def dead_links(path: Path, text: str) -> list[str]:
    """Relative Markdown links and images of ``path`` whose target does not exist."""
    links = re.findall(r"\]\(([^)\s#]+)(?:#[^)]*)?\)", text)
    return [link for link in links if "://" not in link and not (path.parent / link).exists()]


def missing_files(text: str) -> list[str]:
    """Source files named in backquotes (``kinematics/certificate.py``) that are not in the repository."""
    named = re.findall(r"`([\w./-]+/[\w.-]+\.py)\b", text)
    return [p for p in named if not (ROOT / p).exists() and not (ROOT / "hexapod_model" / p).exists()]


def process_words(text: str) -> list[str]:
    """The development-process words of a text, with their line numbers."""
    return [
        f"line {n}: {m.group(0)!r}" for n, line in enumerate(text.splitlines(), 1) for m in PROCESS_WORDS.finditer(line)
    ]


def product_files() -> list[Path]:
    files = [ROOT / f for f in PRODUCT_FILES if (ROOT / f).exists()]
    for folder in PRODUCT_FOLDERS:
        files += [p for p in (ROOT / folder).rglob("*") if p.is_file() and p.suffix in TEXT_SUFFIXES]
    return files


def test_readme_python_blocks_run_in_order_as_one_script(tmp_path):
    out = run_blocks(README.read_text(), tmp_path)
    assert out.returncode == 0, out.stderr
    assert "converged" in out.stdout


def test_python_api_page_blocks_run_in_order_as_one_script(tmp_path):
    text = (ROOT / "docs" / "python.md").read_text()
    out = run_blocks(text + "\n```python\nprint(rows.status, hybrid.status)\n```\n", tmp_path)
    assert out.returncode == 0, out.stderr
    assert out.stdout.split() == ["['converged'", "'converged']", "converged"]


def test_a_failing_block_fails_the_run(tmp_path):
    text = README.read_text() + "\n```python\nhexa.forward([0.0] * 5)  # five readings\n```\n"
    out = run_blocks(text, tmp_path)
    assert out.returncode != 0 and "InputError" in out.stderr


@pytest.mark.parametrize("path", MARKDOWN, ids=lambda p: p.name)
def test_every_dotted_path_resolves(path):
    if not path.exists():
        pytest.skip(f"{path.name} is not there")
    bad = sorted(p for p in dotted_paths(path.read_text()) if not resolves(p))
    assert not bad, f"{path.relative_to(ROOT)}: {bad}"


def test_dotted_path_check_finds_a_bad_path():
    text = "`hexapod_model.kinematics.hexapod.Hexapod`, `hexapod_model.kinematics.solver.NewtonSolver`"
    assert sorted(p for p in dotted_paths(text) if not resolves(p)) == ["hexapod_model.kinematics.solver.NewtonSolver"]
    assert not resolves("hexapod_model.kinematics.hexapod.Hexapod.no_such_method")
    assert resolves("hexapod_model.kinematics.newton.solver.NewtonSolver.iterate")
    assert dotted_paths("one line on the `hexapod_model.compile` logger") == set()


@pytest.mark.parametrize("path", MARKDOWN, ids=lambda p: p.name)
def test_links_and_named_source_files_exist(path):
    if not path.exists():
        pytest.skip(f"{path.name} is not there")
    text = path.read_text()
    assert not dead_links(path, text), f"{path.relative_to(ROOT)}: dead links {dead_links(path, text)}"
    assert not missing_files(text), f"{path.relative_to(ROOT)}: no such files {missing_files(text)}"


def test_link_and_file_checks_find_missing_targets():
    text = "[ok](docs/geometry.md) [gone](docs/nowhere.md) `kinematics/certificate.py` `analysis/tracker_kernels.py`"
    assert dead_links(README, text) == ["docs/nowhere.md"]
    assert missing_files(text) == ["analysis/tracker_kernels.py"]


def test_no_development_process_words_in_the_product():
    found = {
        str(p.relative_to(ROOT)): words
        for p in product_files()
        if (words := process_words(p.read_text(encoding="utf-8", errors="replace")))
    }
    assert not found, found


@pytest.mark.parametrize(
    "text", ["as measured in this session", "see (issue 12)", "issue #9", "a helper found", "In this round"]
)
def test_process_word_check_finds_injected_words(text):
    assert process_words("clean line\n" + text) and process_words(text)[0].startswith("line 1")
    assert not process_words("the page keeps the token in the tab's session storage")


def test_readme_stays_short():
    assert len(README.read_text().splitlines()) <= 300


def test_citation_names_this_version_and_the_papers():
    import yaml

    import hexapod_model

    cff = yaml.safe_load((ROOT / "CITATION.cff").read_text())
    assert cff["version"] == hexapod_model.__version__ and cff["type"] == "software"
    assert {r["authors"][0]["family-names"] for r in cff["references"]} == {"Bem", "Jakobović", "Shi"}


def test_the_csv_page_names_every_status():
    import hexapod_model as hm

    text = (ROOT / "docs" / "formats.md").read_text()
    named = {s for s in hm.STATUSES if s != "converged"} | {"ok", "near_singular"}  # converged rows say ok
    assert not [s for s in sorted(named) if f"`{s}`" not in text]


def test_performance_page_is_generated_by_the_current_script():
    import importlib.util
    import shlex

    spec = importlib.util.spec_from_file_location("performance_table", ROOT / "benchmarks" / "performance_table.py")
    assert spec is not None and spec.loader is not None
    table = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(table)
    text = (ROOT / "docs" / "performance.md").read_text()
    assert text.startswith("# Performance\n") and "| figure | value | command | load | date |" in text
    for quick, _, _ in table.BENCHMARKS:  # every benchmark of the script has its rows on the page
        assert f"`python benchmarks/{' '.join(shlex.quote(a) for a in quick)}`" in text


def test_the_sites_roles_become_links_that_keep_the_names():
    import importlib.util

    # the site's griffe extension: griffe comes with mkdocstrings (the docs extra, installed with the linters)
    pytest.importorskip("griffe", reason="griffe (the documentation site's) is not installed: pip install -e '.[docs]'")
    spec = importlib.util.spec_from_file_location("griffe_rst_roles", ROOT / "scripts" / "griffe_rst_roles.py")
    assert spec is not None and spec.loader is not None
    roles = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(roles)
    text = "See :class:`~hexapod_model.kinematics.hexapod.Hexapod`, :mod:`.kernels` and ``q``."
    # a link where the site documents the name (an optional cross-reference: plain code where it does not)
    assert roles.markdown_roles(text, "hexapod_model.kinematics.newton") == (
        'See <autoref identifier="hexapod_model.kinematics.hexapod.Hexapod" optional><code>Hexapod</code></autoref>, '
        '<autoref identifier="hexapod_model.kinematics.newton.kernels" optional><code>.kernels</code></autoref>'
        " and ``q``."
    )
    assert roles.markdown_roles("`hexapod_model.io.tables` or ``hexapod_model.files``") == (
        '<autoref identifier="hexapod_model.io.tables" optional><code>hexapod_model.io.tables</code></autoref> or '
        '<autoref identifier="hexapod_model.files" optional><code>hexapod_model.files</code></autoref>'
    )
    assert roles.markdown_roles(":func:`..rotations.pose_distance`", "hexapod_model.kinematics.newton") == (
        '<autoref identifier="hexapod_model.kinematics.rotations.pose_distance" optional>'
        "<code>..rotations.pose_distance</code></autoref>"
    )


def test_every_docs_page_is_in_the_sites_nav():
    import yaml

    class Loader(yaml.SafeLoader):  # mkdocs.yml may carry !!python/name tags: read them as text
        pass

    Loader.add_multi_constructor("", lambda loader, suffix, node: None)
    config = yaml.load((ROOT / "mkdocs.yml").read_text(), Loader=Loader)

    def pages(nav) -> list[str]:
        if isinstance(nav, str):
            return [nav]
        items = nav.values() if isinstance(nav, dict) else nav
        return [p for item in items for p in pages(item)]

    listed = set(pages(config["nav"]))
    assert all((ROOT / "docs" / p).exists() for p in listed)
    on_disk = {str(p.relative_to(ROOT / "docs")) for p in DOC_PAGES}
    assert sorted(on_disk - listed) == [], "pages missing from the nav of mkdocs.yml"
