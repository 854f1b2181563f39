"""Start-up stays light: heavy dependencies load on first use, not on import or --help."""

import subprocess
import sys

HEAVY = ("numba", "scipy", "matplotlib", "jax", "pydantic", "dask", "shapely")


def loaded_after(code: str) -> list[str]:
    probe = (
        f"{code}\nimport sys\nprint('LOADED:', ' '.join(m for m in {HEAVY!r} if m in sys.modules))"
    )
    done = subprocess.run(
        [sys.executable, "-c", probe], capture_output=True, text=True, check=True, timeout=120
    )
    return done.stdout.rsplit("LOADED:", 1)[1].split()


def test_import_wheelbase_loads_no_heavy_dependency():
    assert loaded_after("import wheelbase") == []


def test_cli_help_loads_no_heavy_dependency():
    code = "from wheelbase.cli import app\ntry:\n    app(['--help'])\nexcept SystemExit:\n    pass"
    assert loaded_after(code) == []


def test_public_names_still_resolve_on_use():
    code = "import wheelbase\nwheelbase.HybridAStar\nwheelbase.run\nwheelbase.Log"
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert "has no attribute 'Log'" in done.stderr  # Log is wheelbase.sim's, not re-exported
    assert loaded_after("import wheelbase\nwheelbase.HybridAStar") != []


def test_no_public_name_is_shadowed_by_a_submodule():
    """A lazily exported name equal to a submodule's name would become the module once the
    submodule is imported; such names must be bound eagerly."""
    import importlib
    import pkgutil

    for package in ("wheelbase", "wheelbase.control", "wheelbase.models", "wheelbase.odometry",
                    "wheelbase.planning", "wheelbase.sensors", "wheelbase.sim"):  # fmt: skip
        module = importlib.import_module(package)
        for info in pkgutil.iter_modules(module.__path__):
            if info.name in module.__all__:
                importlib.import_module(f"{package}.{info.name}")
                assert not hasattr(getattr(module, info.name), "__path__"), info.name
                assert getattr(module, info.name).__class__.__name__ != "module", info.name
