"""Every Python block of the README and of the documentation pages runs as written.

The blocks of one page run in order in one namespace, as a reader pastes them, in a fresh
folder (files they write land there); a block that raises fails its page. The README's
``closed_loop`` example used an undefined ``starts`` until this test ran it.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
_MARKDOWN = re.compile(r"^```python\n(.*?)^```", re.M | re.S)
_RST = re.compile(r"^\.\. code-block:: python\n((?:[ \t]*\n|   .*\n)+)", re.M)


def python_blocks(path: Path) -> list[str]:
    """The Python blocks of a Markdown or reStructuredText page, dedented."""
    text = path.read_text(encoding="utf-8")
    if path.suffix == ".md":
        return list(_MARKDOWN.findall(text))
    return ["\n".join(line[3:] for line in block.splitlines()) for block in _RST.findall(text)]


PAGES = sorted(
    path
    for path in [ROOT / "README.md", *(ROOT / "docs").rglob("*.rst")]
    if "_build" not in path.parts and python_blocks(path)
)


def test_the_pages_with_python_are_found():
    names = {path.name for path in PAGES}
    assert {"README.md", "simulate.rst", "plan.rst", "control.rst", "localise.rst"} <= names
    assert len(python_blocks(ROOT / "README.md")) >= 3


@pytest.mark.parametrize("page", PAGES, ids=lambda p: str(p.relative_to(ROOT)))
def test_every_python_block_runs(page, tmp_path, monkeypatch):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    # a fresh folder, beside which ../shared is the project's shared data (as for a checkout)
    work = tmp_path / "work"
    work.mkdir()
    if (ROOT.parent / "shared").is_dir():
        (tmp_path / "shared").symlink_to(ROOT.parent / "shared")
    monkeypatch.chdir(work)
    namespace: dict = {"__name__": "__doc_example__"}
    for number, block in enumerate(python_blocks(page), start=1):
        code = compile(block, f"{page.name} block {number}", "exec")
        exec(code, namespace)  # the documentation's own examples
    plt.close("all")


_BLOCK = re.compile(r"^\.\. code-block:: \w+\n((?:[ \t]*\n|   .*\n)+)", re.M)
CODE_WIDTH = 79
"""Columns a code block of the docs may use: wider lines overflow the theme's text column."""


def test_no_code_block_of_the_docs_is_wider_than_the_page():
    # the localise page's blocks ran 94 characters wide and scrolled sideways
    wide = []
    for page in sorted((ROOT / "docs").rglob("*.rst")):
        if {"_build", "auto_examples"} & set(page.parts):
            continue
        for block in _BLOCK.findall(page.read_text(encoding="utf-8")):
            wide += [f"{page.name}: {line.strip()}" for line in block.splitlines()
                     if len(line) - 3 > CODE_WIDTH]  # fmt: skip
    assert not wide, "\n".join(wide)


def test_every_gallery_card_keeps_its_title():
    # sphinx-gallery strips *…* from a card's title: "Hybrid A* … Hybrid A*" lost both stars
    from sphinx_gallery.gen_rst import _sanitize_rst

    for script in sorted((ROOT / "examples").glob("*.py")):
        lines = script.read_text(encoding="utf-8").split('"""')[1].strip().splitlines()
        assert _sanitize_rst(lines[0]) == lines[0], script.name


@pytest.mark.parametrize(
    ("script", "argv", "figure"),
    [
        ("odometry_umbmark", ["{out}"], "odometry_umbmark.png"),
        ("doc001_table1", ["--out", "{out}/doc001_table1.csv"], "doc001_table1.png"),
    ],
)
def test_the_examples_that_only_printed_draw_their_figure(script, argv, figure, tmp_path):
    # their gallery cards showed the placeholder thumbnail: the gallery shows what a script draws
    import runpy
    import sys

    pytest.importorskip("sphinx_gallery")
    old = sys.argv
    sys.argv = [script, *(arg.format(out=tmp_path) for arg in argv)]
    try:
        runpy.run_path(str(ROOT / "examples" / f"{script}.py"), run_name="__main__")
    finally:
        sys.argv = old
    assert (tmp_path / figure).read_bytes()[:4] == b"\x89PNG"
