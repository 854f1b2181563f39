"""Imports run one way (README, "What is inside"): a module never imports a higher layer."""

import ast
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src" / "wheelbase"

# bottom to top; a module may import its own layer and the layers below it
LAYERS = (
    {"errors", "_validate", "_io", "_lazy", "_jax", "geometry", "polyline", "limits", "plot"},
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
