"""Document 001, Table I (examples/doc001_table1.py): identities, error bound, printed digits."""

from __future__ import annotations

import csv
import importlib.util
import math
import sys
from pathlib import Path

import numpy as np
import pytest

from wheelbase import simulate
from wheelbase.geometry import rotation_2d

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "doc001_table1.py"


def _load_example():
    spec = importlib.util.spec_from_file_location("doc001_table1", EXAMPLE)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses look their module up
    spec.loader.exec_module(module)
    return module


doc = _load_example()
V, OMEGA = doc.body_speeds(*doc.WHEEL_SPEEDS)
METHODS = ("exact", *doc.METHOD_COLUMNS)


@pytest.fixture(scope="module")
def rows():
    return doc.table1()


def end_pose(method: str, heading_deg: float) -> np.ndarray:
    pose0 = [0.0, 0.0, math.radians(heading_deg)]
    return simulate(doc.ROBOT, pose0, doc.WHEEL_SPEEDS, doc.DURATION_S, doc.STEP_S, method).poses[
        -1
    ]


def test_theta_column_error_is_zero(rows):
    # θ̇ = ω is integrated exactly by every method for constant inputs (document 001: error 0).
    turn = math.degrees(OMEGA * doc.DURATION_S)
    for row in rows:
        if row.variable == "theta":
            assert row.exact == pytest.approx(row.heading_deg + turn, abs=1e-12)
            for name in doc.METHOD_COLUMNS:
                assert abs(row.errors[name]) < 1e-12
            assert round(row.exact, 1) == row.printed_actual == row.printed_simpson


def test_simpson_error_is_within_its_bound_and_equals_the_leading_term(rows):
    bound = doc.simpson_error_bound(V, OMEGA, doc.DURATION_S, doc.STEP_S)
    assert bound == pytest.approx(doc.DURATION_S * doc.STEP_S**4 * V * OMEGA**4 / 2880, rel=1e-12)
    assert bound < 1e-6  # the printed errors are 0.29-0.49 m
    for heading in doc.HEADINGS_DEG:
        exact = end_pose("exact", heading)
        simpson = end_pose("simpson", heading)
        error = simpson[:2] - exact[:2]
        assert np.all(np.abs(error) <= bound)
        # f'''' = ω⁴ f, so S − I ≈ (h/2)⁴/180 · ω⁴ · ∫f dt = (hω)⁴/2880 · (Δx, Δy).
        leading = (doc.STEP_S * OMEGA) ** 4 / 2880 * exact[:2]
        np.testing.assert_allclose(error, leading, rtol=1e-2)
    table_errors = [abs(r.errors["simpson"]) for r in rows if r.variable != "theta"]
    assert max(table_errors) <= bound


def test_rk4_equals_simpson_for_constant_inputs():
    for heading in doc.HEADINGS_DEG:
        np.testing.assert_allclose(
            end_pose("rk4", heading), end_pose("simpson", heading), rtol=0, atol=1e-12
        )


@pytest.mark.parametrize("method", METHODS)
def test_rotating_the_initial_heading_rotates_the_end_point(method):
    base = end_pose(method, 0.0)
    for heading in (45.0, 90.0, 180.0):
        rotated = end_pose(method, heading)
        expected = rotation_2d(math.radians(heading)) @ base[:2]
        np.testing.assert_allclose(rotated[:2], expected, rtol=0, atol=1e-12)
    quarter = end_pose(method, 90.0)
    assert quarter[0] == pytest.approx(-base[1], abs=1e-12)
    assert quarter[1] == pytest.approx(base[0], abs=1e-12)


def test_the_printed_table_rotates_the_same_way():
    for column in ("actual", "simpson"):
        x0, y0, theta0 = doc.PRINTED[0.0][column]
        x90, y90, theta90 = doc.PRINTED[90.0][column]
        assert (x90, y90) == (-y0, x0)
        assert theta90 == pytest.approx(theta0 + 90.0)
        x45, y45, _ = doc.PRINTED[45.0][column]
        assert abs(x45 - (x0 - y0) / math.sqrt(2)) < 0.015
        assert abs(y45 - (x0 + y0) / math.sqrt(2)) < 0.015
    # The 180° row: y is (−y₀) for both columns; the Simpson x lost its sign in print.
    assert doc.PRINTED[180.0]["actual"][:2] == (-9.56, 7.42)
    assert doc.PRINTED[180.0]["simpson"][1] == -doc.PRINTED[0.0]["simpson"][1]
    assert doc.PRINTED[180.0]["simpson"][0] == doc.PRINTED[0.0]["simpson"][0]  # should be −9.28


def test_no_exact_arc_gives_the_printed_actual():
    # Inscribed angle: an arc's chord bears θ₀ + Δθ/2. True of our exact arcs ...
    for heading in doc.HEADINGS_DEG:
        x, y, _ = end_pose("exact", heading)
        bearing = math.degrees(math.atan2(y, x))
        half_turn = math.degrees(OMEGA * doc.DURATION_S) / 2
        assert bearing == pytest.approx(heading + half_turn, abs=1e-9)
    # ... but the printed (9.56, −7.42) with Δθ = −69.8° misses it by ~3°, far beyond rounding.
    x, y, turn = doc.PRINTED[0.0]["actual"]
    assert abs(math.degrees(math.atan2(y, x)) - turn / 2) > 2.5
    _, worst = doc.fit_exact_arc()
    assert worst > 0.2


def test_heading_first_euler_reproduces_every_printed_actual_digit(rows):
    for heading in doc.HEADINGS_DEG:
        x, y, theta = doc.document_actual(heading, V, OMEGA)
        px, py, ptheta = doc.PRINTED[heading]["actual"]
        assert (round(x, 2), round(y, 2), round(theta, 1)) == (px, py, ptheta)
    for row in rows:
        digits = 1 if row.variable == "theta" else 2
        assert round(row.document_actual, digits) == row.printed_actual


def test_only_twelve_steps_match_the_printed_bearing_and_the_fit_gives_our_inputs():
    x, y, turn = doc.PRINTED[0.0]["actual"]
    bearing = math.degrees(math.atan2(y, x))
    matching = [n for n in range(2, 60) if abs(turn * (n + 1) / (2 * n) - bearing) < 0.05]
    assert matching == [12]
    fitted_v, fitted_omega = doc.fit_document_actual()
    assert fitted_v == pytest.approx(V, rel=1e-3)
    assert fitted_omega == pytest.approx(OMEGA, rel=1e-3)
    assert doc.WHEEL_SPEEDS[0] > doc.WHEEL_SPEEDS[1]  # a right turn: left wheel faster


def test_main_prints_and_writes_csv_without_overwriting(tmp_path, capsys):
    out = tmp_path / "table1.csv"
    rows = doc.main(["--out", str(out)])
    printed = capsys.readouterr().out
    assert "Table I" in printed and "bound" in printed
    with out.open() as handle:
        records = list(csv.DictReader(handle))
    assert len(records) == len(rows) == 12
    first = records[0]
    assert (first["heading_deg"], first["variable"], first["unit"]) == ("0.0", "x", "m")
    assert float(first["simpson"]) - float(first["exact"]) == pytest.approx(
        float(first["simpson_error"]), abs=1e-12
    )
    with pytest.raises(FileExistsError, match="overwrite"):
        doc.main(["--out", str(out)])
    doc.main(["--out", str(out), "--overwrite"])
