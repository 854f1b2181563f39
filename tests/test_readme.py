"""The README tells the truth: its measured tables are what benchmarks/readme_figures.py prints,
and it sends nobody to a folder a clone does not have."""

from __future__ import annotations

import importlib.util
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text(encoding="utf-8")


def _figures_script():
    spec = importlib.util.spec_from_file_location(
        "readme_figures", ROOT / "benchmarks" / "readme_figures.py"
    )
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_integrator_table_is_what_the_script_prints():
    script = _figures_script()
    table = script.markdown({"integrators": script.integrators()})
    for line in table.splitlines():
        assert line in README, f"README's integrator table differs: expected {line!r}"


def test_no_reader_is_sent_to_the_shared_seeds_folder():
    # The reference documents are cited by title, authors and year (file names kept).
    assert "shared/seeds" not in README
    for number in ("000", "001", "002", "003"):
        assert re.search(rf"document {number} \(`{number}_[0-9a-f]{{16}}\.txt`\) \| \S", README)
