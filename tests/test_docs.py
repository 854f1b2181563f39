"""The documentation site builds, warnings as errors and nitpicky (every cross-reference
resolves; the quick build: examples not run)."""

import subprocess
import sys
from pathlib import Path

import pytest

pytest.importorskip("sphinx")
pytest.importorskip("numpydoc")
pytest.importorskip("sphinx_gallery")
pytest.importorskip("furo")

DOCS = Path(__file__).resolve().parents[1] / "docs"


def test_quick_build_has_no_warning_and_documents_the_api(tmp_path):
    out = tmp_path / "html"
    done = subprocess.run(
        [sys.executable, "-m", "sphinx", "-n", "-W", "--keep-going", "-q", "-b", "html",
         "-D", "plot_gallery=0", "-d", str(tmp_path / "doctrees"), str(DOCS), str(out)],
        capture_output=True, text=True, timeout=600, check=False,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr[-4000:]
    # Every task page and the comparison page are there, and the API pages hold the objects.
    for page in ("simulate", "plan", "control", "scenario", "batch", "localise", "foxglove",
                 "gymnasium"):  # fmt: skip
        assert (out / "tasks" / f"{page}.html").is_file()
    assert "plannerHybridAStar" in (out / "coming_from.html").read_text()
    api = {
        "models": "wheelbase.models.DiffDrive",
        "planning": "wheelbase.planning.HybridAStar",
        "sim": "wheelbase.sim.Engine",
        "gym": "wheelbase.gym.NavigateVectorEnv",
        "mcap_export": "wheelbase.mcap_export.write_mcap",
        "localization": "wheelbase.localization.mrclam.localize",
        "limits": "wheelbase.limits.MAX_STEPS",
    }
    for page, anchor in api.items():
        assert f'id="{anchor}"' in (out / "api" / f"{page}.html").read_text(), anchor
    assert (
        'id="wheelbase.localization.mrclam.MRCLAM_PARAMETERS"'
        in (out / "api" / "localization.html").read_text()
    )
    # A re-export links to where it is documented (wheelbase.run → wheelbase.runner.run).
    assert (
        'href="../api/runner.html#wheelbase.runner.run"'
        in (out / "tasks" / "scenario.html").read_text()
    )
    gallery = {path.stem for path in (out / "auto_examples").glob("*.html")}
    scripts = {path.stem for path in (DOCS.parent / "examples").glob("*.py")}
    assert scripts - {"gym_ppo"} <= gallery
