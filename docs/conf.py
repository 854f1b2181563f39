"""Sphinx configuration of the wheelbase documentation.

Build it (``pip install -e ".[docs]"``)::

    python -m sphinx -b html docs docs/_build/html          # full: the gallery runs examples/
    python -m sphinx -W -b html -D plot_gallery=0 docs docs/_build/html   # quick: not run

The gallery runs every script of ``examples/`` and shows the PNG figures each one writes (the
scripts take their output folder as their first argument): no figure in the docs is pasted.
"""

from __future__ import annotations

import re
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
# Every exported name has an entry (a dataclass field such as EngineState.sensors has no
# docstring of its own, and a reference to one must still resolve).
autodoc_default_options = {"undoc-members": True}


_TABLE_BORDER = re.compile(r"^\s*=+(\s+=+)+\s*$")


def _escape_bars(app, what, name, obj, options, lines):
    """Docstrings write absolute values and norms as ``|v|`` (plain text, like the papers):
    escape those bars, which reStructuredText would read as substitutions. Line blocks (``| ``
    at the start of a line) and grid tables are left alone; in a simple table (``===`` borders)
    a bar becomes ∣ (U+2223), the same width, so that the columns stay aligned."""
    in_table = False
    for index, line in enumerate(lines):
        if _TABLE_BORDER.match(line):
            after = lines[index + 1] if index + 1 < len(lines) else ""
            in_table = not (in_table and not after.strip())
            continue
        stripped = line.lstrip()
        if "|" not in stripped or stripped.startswith(("+", "| ")) or stripped == "|":
            continue
        if in_table:
            lines[index] = line.replace("|", "\u2223")
        else:
            lines[index] = line[: len(line) - len(stripped)] + stripped.replace("|", "\\|")


# ----------------------------------------------------------------------------- references
# The build is nitpicky (tests/test_docs.py: -n -W): every cross-reference must resolve. Names of
# other projects (the standard library, NumPy, matplotlib) cannot link offline, without an
# intersphinx inventory, so they stay plain text on purpose; every wheelbase name must resolve.
_OTHERS = "concurrent|copy|dataclasses|typing|numpy|scipy|matplotlib|gymnasium|dask|numba|jax"
nitpick_ignore_regex = [(r"py:.*", rf"({_OTHERS})\..*")]


def _import(name: str):
    """The Python object a dotted name denotes, or None."""
    import importlib

    parts = name.split(".")
    for cut in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:cut]))
        except ImportError:
            continue
        try:
            for attribute in parts[cut:]:
                obj = getattr(obj, attribute)
        except AttributeError:
            return None
        return obj
    return None


def _identity(obj) -> int:
    """The identity of an object; a bound method (a classmethod read from its class) is its
    function, which stays the same object from one lookup to the next."""
    return id(getattr(obj, "__func__", obj))


def _documented(env, fresh: bool = False) -> dict:
    """``{(id(object), last name part): documented name}`` of every documented Python object
    (cached once the pages are read; ``fresh`` while they are)."""
    cache = None if fresh else getattr(env, "_wheelbase_documented", None)
    if cache is None:
        seen = env.__dict__.setdefault("_wheelbase_identities", {})  # name: identity
        for name in env.get_domain("py").objects:
            if name not in seen:
                obj = _import(name)
                seen[name] = None if obj is None else _identity(obj)
        cache = {}
        for name in sorted(seen, key=len):
            if seen[name] is not None:
                cache.setdefault((seen[name], name.rsplit(".", 1)[-1]), name)
        if not fresh:
            env._wheelbase_documented = cache
    return cache


def _resolve_by_object(app, env, node, contnode):
    """Resolve a reference by the object it names: ``wheelbase.run`` (the re-export) links to
    ``wheelbase.runner.run`` where it is documented, ``STATUSES`` in a docstring of
    ``wheelbase.sim.engine`` to ``wheelbase.sim.STATUSES``. One object, one documented entry."""
    from sphinx.util.nodes import make_refnode

    if node.get("refdomain") != "py":
        return None
    target = node["reftarget"].lstrip("~.")
    module, cls = node.get("py:module"), node.get("py:class")
    candidates = [target]
    if module:
        if cls:
            candidates.append(f"{module}.{cls}.{target}")
        parts = module.split(".")
        candidates += [".".join([*parts[:cut], target]) for cut in range(len(parts), 0, -1)]
    objects = env.get_domain("py").objects
    found = None
    for candidate in candidates:
        obj = _import(candidate)
        if obj is not None:
            found = _documented(env).get((_identity(obj), candidate.rsplit(".", 1)[-1]))
            if found is not None:
                break
    if found is None:  # a name that exactly one documented object ends with (a class moved
        # to a module of its own, wheelbase.control.DWA → wheelbase.control.dwa.DWA)
        identities = env.__dict__.get("_wheelbase_identities", {})
        for suffix in dict.fromkeys((target, target.rsplit(".", 1)[-1])):
            ends = sorted((name for name in objects if name.endswith(f".{suffix}")), key=len)
            # one object, perhaps under two names (a constant a second module imports)
            if ends and len({identities.get(name, name) for name in ends}) == 1:
                found = ends[0]
                break
    if found is None:
        return None
    entry = objects[found]
    return make_refnode(app.builder, node["refdoc"], entry.docname, entry.node_id, contnode, found)


def _module_constants(module_name: str) -> list[str]:
    """The public constants (UPPER_CASE, not callable) a module assigns at its top level."""
    import importlib

    from sphinx.pycode import ModuleAnalyzer

    module = importlib.import_module(module_name)
    try:
        analyzer = ModuleAnalyzer.for_module(module_name)
        analyzer.analyze()
    except Exception:  # no source to analyse: nothing to list
        return []
    return [
        name
        for name in analyzer.tagorder
        if "." not in name
        and name.isupper()
        and not name.startswith("_")
        and hasattr(module, name)
        and type(getattr(module, name)).__module__ == "builtins"  # an array would show
        and not callable(getattr(module, name))  # NumPy's docstring for its own
    ]


def _constant_lines(module_name: str, known) -> list[str]:
    """``.. autodata::`` lines for the module's constants no page documents yet: autodoc's
    ``:members:`` lists module data only when it has a docstring, and a reference to a constant
    (``wheelbase.integrate.METHODS``) must resolve all the same."""
    return [
        f".. autodata:: {module_name}.{name}"
        for name in _module_constants(module_name)
        if f"{module_name}.{name}" not in known
    ]


def _submodules_directive():
    """``.. wheelbase-submodules:: PACKAGE``: the docstring of every public module of a package
    that no page documents yet, so that a reference to a module (``wheelbase.gym.task``) links
    to its description; a new module appears without editing the page."""
    import importlib
    import inspect
    import pkgutil

    from docutils import nodes
    from docutils.statemachine import StringList
    from sphinx.util.docutils import SphinxDirective

    class Submodules(SphinxDirective):
        required_arguments = 1

        def run(self):
            package = importlib.import_module(self.arguments[0])
            known = self.env.get_domain("py").modules
            lines = [".. rubric:: Modules", ""]
            for info in sorted(pkgutil.iter_modules(package.__path__), key=lambda i: i.name):
                name = f"{package.__name__}.{info.name}"
                shadow = getattr(package, info.name, None)  # planning.astar: the function
                shadowed = shadow is not None and not inspect.ismodule(shadow)
                if info.name.startswith("_") or name in known or shadowed:
                    continue
                # What the package exports is on its page; what the module exports beyond it
                # (wheelbase.control.local_path.PathWindow) and its constants
                # (wheelbase.sim.log.STATUSES) are listed here, where the module explains them.
                objects = self.env.get_domain("py").objects
                shown = {key[0] for key in _documented(self.env, fresh=True)}
                module = importlib.import_module(name)
                more = [
                    member
                    for member in getattr(module, "__all__", [])
                    if callable(getattr(module, member, None))  # constants: below
                    and _identity(getattr(module, member)) not in shown
                ]
                option = f"   :members: {', '.join(more)}" if more else "   :no-members:"
                lines += [f".. automodule:: {name}", option, ""]
                lines += [line for c in _constant_lines(name, objects) for line in (c, "")]
            holder = nodes.section()
            holder.document = self.state.document
            self.state.nested_parse(StringList(lines), self.content_offset, holder)
            return holder.children

    return Submodules


def _constants_directive():
    """``.. wheelbase-constants:: MODULE``: the module's constants that ``automodule`` left out
    (those without a docstring), after it on the page."""
    from docutils import nodes
    from docutils.statemachine import StringList
    from sphinx.util.docutils import SphinxDirective

    class Constants(SphinxDirective):
        required_arguments = 1

        def run(self):
            objects = self.env.get_domain("py").objects
            lines = [line for c in _constant_lines(self.arguments[0], objects) for line in (c, "")]
            holder = nodes.section()
            holder.document = self.state.document
            self.state.nested_parse(StringList(lines), self.content_offset, holder)
            return holder.children

    return Constants


def setup(app):
    """Register the docstring filter, the reference resolver and the modules directive."""
    app.connect("autodoc-process-docstring", _escape_bars)
    app.connect("missing-reference", _resolve_by_object)
    app.add_directive("wheelbase-submodules", _submodules_directive())
    app.add_directive("wheelbase-constants", _constants_directive())


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
    """A scraper that shows the PNG and GIF files an example wrote into its folder (in name
    order; an animation keeps its ``.gif`` suffix)."""

    def __repr__(self) -> str:  # a stable repr keeps Sphinx's environment cache valid
        return "_WrittenFigures"

    def __call__(self, block, block_vars, gallery_conf):
        from sphinx_gallery.scrapers import figure_rst

        folder = _OUT / Path(block_vars["src_file"]).stem
        shown = []
        written = sorted([*folder.glob("*.png"), *folder.glob("*.gif")])
        for image, target in zip(written, block_vars["image_path_iterator"], strict=False):
            target = str(Path(target).with_suffix(image.suffix))
            shutil.copyfile(image, target)
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
