"""Imports run one way (README, "What is inside"): a module never imports a higher layer."""

import ast
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src" / "wheelbase"

# bottom to top; a module may import its own layer and the layers below it
LAYERS = (
    {
        "errors",
        "_validate",
        "_io",
        "_lazy",
        "_jax",
        "geometry",
        "geometry_numba",
        "polyline",
        "limits",
        "plot",
    },
    {"models", "planning"},
    {
        "integrate",
        "integrate_numba",
        "integrate_jax",
        "dynamics",
        "trajectory",
        "timing",
        "motor",
        "inertial",
        "terrain",
    },
    {"sensors", "odometry", "datasets"},
    {"perception", "world"},
    {"control", "localization", "mapping"},
    {"sim", "navigation"},
    {
        "runner",
        "exploration",
        "batch",
        "scenario",
        "scenario_sensors",
        "scenario_world",
        "scenario_navigation",
        "scenario_terrain",
        "scenario_ground",
        "terrain_plot",
        "report",
        "dynamics_plot",
        "world_plot",
        "mcap_export",
    },
    {"gym"},
    {"cli", "commands", "__main__"},
)
LEVEL = {name: level for level, names in enumerate(LAYERS) for name in names}


def top_module(path: Path) -> str:
    part = path.relative_to(SRC).parts[0]
    return part[:-3] if part.endswith(".py") else part


MODULES = sorted(
    path for path in SRC.rglob("*.py")
    if path.relative_to(SRC).parts[0] not in ("__init__.py", "data")
)  # fmt: skip


def test_every_module_has_a_layer():
    assert {top_module(path) for path in MODULES} <= set(LEVEL)


@pytest.mark.parametrize("path", MODULES, ids=lambda p: str(p.relative_to(SRC)))
def test_imports_run_one_way(path):
    own = top_module(path)
    for node in ast.walk(ast.parse(path.read_text())):
        if (
            isinstance(node, ast.ImportFrom)
            and node.module
            and node.module.startswith("wheelbase.")
        ):
            target = node.module.split(".")[1]
            assert LEVEL[target] <= LEVEL[own], (
                f"{path.relative_to(SRC)} (layer {LEVEL[own]}) imports wheelbase.{target} "
                f"(layer {LEVEL[target]}) at line {node.lineno}"
            )


def test_the_library_never_imports_the_benchmark_harness():
    for path in MODULES:
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, (ast.Import, ast.ImportFrom)):
                names = [node.module or ""] if isinstance(node, ast.ImportFrom) else []
                names += [alias.name for alias in getattr(node, "names", [])]
                assert not any(name.split(".")[0] == "control_cases" for name in names), path


# What decides (controllers, estimators, perception, replanning) sees the world only through
# its sensors: it never reads the truth of wheelbase.world (issue 22).
DECIDERS = ("control", "localization", "perception", "navigation")


def world_imports(source: str, path: Path) -> list[tuple[str, int]]:
    """Every name under ``wheelbase.world`` that ``source`` (the file ``path``) imports."""
    found = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.ImportFrom):
            module = node.module or ""
            if node.level:  # relative: resolve against the file's package
                parts = path.relative_to(SRC).parts[: -node.level]
                module = ".".join(("wheelbase", *parts, module)).rstrip(".")
            names = [module] + [f"{module}.{alias.name}" for alias in node.names]
        elif isinstance(node, ast.Import):
            names = [alias.name for alias in node.names]
        else:
            continue
        found += [(n, node.lineno) for n in names
                  if n == "wheelbase.world" or n.startswith("wheelbase.world.")]  # fmt: skip
    return found


@pytest.mark.parametrize("package", DECIDERS)
def test_what_decides_never_imports_the_world(package):
    for path in MODULES:
        if top_module(path) == package:
            imports = world_imports(path.read_text(), path)
            assert not imports, (
                f"{path.relative_to(SRC)} imports {imports[0][0]} at line {imports[0][1]}: "
                "what decides may not read the world's truth"
            )


@pytest.mark.parametrize(
    "line",
    ["from wheelbase.world import World", "import wheelbase.world.cast",
     "from wheelbase import world", "from ..world.state import WorldState"],
)  # fmt: skip
def test_the_world_check_finds_every_form_of_import(line):
    assert world_imports(line, SRC / "control" / "x.py")


# Import cycles: within a package (planning's readers and grid, maps and world files, paths and
# their plots were three circles) or across packages of one layer. Every import counts: at the
# top of a module, inside a function (a lazy import is a dependency that runs later) and under
# TYPE_CHECKING (a type-only import still means the module cannot be read without the other).
def module_name(path: Path, root: Path) -> str:
    parts = ("wheelbase", *path.relative_to(root).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def import_graph(root: Path) -> dict[str, set[str]]:
    """Module -> the modules of the package under ``root`` that it imports. A name imported
    from a package is resolved to its submodule, or through the package's lazy ``_EXPORTS``
    table to the module that defines it, else to the package itself."""
    files = {module_name(p, root): p for p in root.rglob("*.py") if "data" not in p.parts}
    exports: dict[str, dict[str, str]] = {}
    for name, path in files.items():
        if path.name == "__init__.py":
            for node in ast.walk(ast.parse(path.read_text())):
                if (
                    isinstance(node, ast.Assign)
                    and any(getattr(t, "id", None) == "_EXPORTS" for t in node.targets)
                    and isinstance(node.value, ast.Dict)
                ):
                    exports[name] = {
                        k.value: v.value
                        for k, v in zip(node.value.keys, node.value.values, strict=True)
                        if isinstance(k, ast.Constant) and isinstance(v, ast.Constant)
                    }
    graph: dict[str, set[str]] = {name: set() for name in files}
    for name, path in files.items():
        package = name if path.name == "__init__.py" else name.rpartition(".")[0]
        for node in ast.walk(ast.parse(path.read_text())):
            targets = []
            if isinstance(node, ast.ImportFrom):
                base = node.module or ""
                if node.level:
                    up = package.split(".")[: len(package.split(".")) - node.level + 1]
                    base = ".".join([*up, base]) if base else ".".join(up)
                for alias in node.names:
                    full = f"{base}.{alias.name}"
                    if full in files:
                        targets.append(full)
                    else:
                        targets.append(exports.get(base, {}).get(alias.name, base))
            elif isinstance(node, ast.Import):
                targets = [alias.name for alias in node.names]
            graph[name] |= {t for t in targets if t in files and t != name}
    return graph


def import_cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan), each as a cycle."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    found = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        for w in sorted(graph[v]):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return found


def test_no_import_cycles():
    cycles = import_cycles(import_graph(SRC))
    assert not cycles, "import cycles: " + "; ".join(" <-> ".join(c) for c in cycles)


def test_the_cycle_check_finds_lazy_typing_and_package_imports(tmp_path):
    root = tmp_path / "wheelbase"
    (root / "pkg").mkdir(parents=True)
    (root / "__init__.py").write_text("")
    files = {
        "pkg/__init__.py": '_EXPORTS = {"Grid": "wheelbase.pkg.grid"}\n',
        "pkg/grid.py": "def load():\n    from wheelbase.pkg.reader import read\n",
        "pkg/reader.py": "from wheelbase.pkg import Grid\n",
        "pkg/path.py": "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n"
        "    from .plot import draw\n",
        "pkg/plot.py": "from wheelbase.pkg.path import Path\n",
        "pkg/one_way.py": "import wheelbase.pkg.grid\n",
    }
    for name, text in files.items():
        (root / name).write_text(text)
    cycles = import_cycles(import_graph(root))
    assert sorted(cycles) == [
        ["wheelbase.pkg.grid", "wheelbase.pkg.reader"],
        ["wheelbase.pkg.path", "wheelbase.pkg.plot"],
    ]
