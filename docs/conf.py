"""Sphinx configuration of the wheelbase documentation.

Build it (``pip install -e ".[docs]"``)::

    python -m sphinx -b html docs docs/_build/html          # full: the gallery runs examples/
    python -m sphinx -W -b html -D plot_gallery=0 docs docs/_build/html   # quick: not run

The gallery runs every script of ``examples/`` and shows the PNG figures each one writes (the
scripts take their output folder as their first argument): no figure in the docs is pasted.
"""

from __future__ import annotations

import shutil
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))

import wheelbase  # noqa: E402

project = "wheelbase"
author = "the wheelbase authors"
copyright = "2026, the wheelbase authors"
release = version = wheelbase.__version__

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.mathjax",
    "numpydoc",
    "sphinx_gallery.gen_gallery",
]
exclude_patterns = ["_build", "images", "foxglove"]
html_theme = "furo"
html_title = f"wheelbase {release}"
html_static_path: list[str] = []
# The gallery's configuration holds functions, so Sphinx cannot cache it between builds (it
# rereads every page instead): a notice about caching, not about the documentation.
suppress_warnings = ["config.cache"]

# numpydoc: the docstrings are numpydoc already; members are listed by autodoc, not numpydoc.
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False
autodoc_member_order = "bysource"
autodoc_typehints = "none"  # the docstrings give the types, with units


def _escape_bars(app, what, name, obj, options, lines):
    """Docstrings write absolute values and norms as ``|v|`` (plain text, like the papers):
    escape those bars, which reStructuredText would read as substitutions. Line blocks (``| ``
    at the start of a line) and tables are left alone."""
    for index, line in enumerate(lines):
        stripped = line.lstrip()
        if "|" not in stripped or stripped.startswith(("+", "| ")) or stripped == "|":
            continue
        lines[index] = line[: len(line) - len(stripped)] + stripped.replace("|", "\\|")


def setup(app):
    """Register the docstring filter."""
    app.connect("autodoc-process-docstring", _escape_bars)


# ----------------------------------------------------------------------------- the gallery
_OUT = Path(tempfile.mkdtemp(prefix="wheelbase-gallery-"))


def _example_argv(gallery_conf, script_vars):
    """Each example writes its figures into its own folder (its first argument; the table of
    document 001 takes ``--out FILE``)."""
    name = Path(script_vars["src_file"]).stem
    folder = _OUT / name
    folder.mkdir(parents=True, exist_ok=True)
    if name == "doc001_table1":
        return ["--out", str(folder / "doc001_table1.csv"), "--overwrite"]
    return [str(folder)]


class _WrittenFigures:
    """A scraper that shows the PNG files an example wrote into its folder (in name order)."""

    def __repr__(self) -> str:  # a stable repr keeps Sphinx's environment cache valid
        return "_WrittenFigures"

    def __call__(self, block, block_vars, gallery_conf):
        from sphinx_gallery.scrapers import figure_rst

        folder = _OUT / Path(block_vars["src_file"]).stem
        shown = []
        for png, target in zip(
            sorted(folder.glob("*.png")), block_vars["image_path_iterator"], strict=False
        ):
            shutil.copyfile(png, target)
            shown.append(target)
        return figure_rst(shown, gallery_conf["src_dir"])


sphinx_gallery_conf = {
    "examples_dirs": str(ROOT / "examples"),
    "gallery_dirs": "auto_examples",
    "filename_pattern": r"\.py$",  # run every script
    # gym_ppo.py trains for minutes and needs the rl extra: its figure is docs/images/gym_ppo.png
    "ignore_pattern": r"(__init__|_util|gym_ppo)\.py$",
    "reset_argv": _example_argv,
    "image_scrapers": (_WrittenFigures(),),
    "download_all_examples": False,
    "remove_config_comments": True,
    "within_subsection_order": "FileNameSortKey",
    "abort_on_example_error": False,
    "only_warn_on_example_error": True,
}
