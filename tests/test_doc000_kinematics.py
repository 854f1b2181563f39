"""Document 000 §3.2 (000_da8bbdc5a43f14d5.txt): the behaviour it describes, against closed forms.

The example ``examples/doc000_kinematics.py`` runs the document's five cases; these tests check
its results: equal wheel speeds drive straight, opposite ones spin in place, unequal ones (and
constant body twists) drive on circles about the instantaneous centre of curvature (ICC). The
Euler error of the document's integration is measured, and explained.
"""

import importlib.util
import math
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from wheelbase import BodyTwist, simulate
from wheelbase.geometry import wrap_angle

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "doc000_kinematics.py"


def _load_example():
    spec = importlib.util.spec_from_file_location("doc000_kinematics", EXAMPLE)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


doc = _load_example()
A, D = doc.WHEEL_RADIUS, doc.HALF_TRACK
X0, Y0, PSI0 = doc.START


@pytest.fixture(scope="module")
def euler():
    return doc.run_cases("euler")


@pytest.fixture(scope="module")
def exact():
    return doc.run_cases("exact")


def fit_circle(points):
    """Least-squares circle through points (n, 2): centre (2,), radius, max radial residual."""
    x, y = points.T
    design = np.column_stack([x, y, np.ones_like(x)])
    (b, c, e), *_ = np.linalg.lstsq(design, x**2 + y**2, rcond=None)
    centre = np.array([b / 2, c / 2])
    radius = math.sqrt(e + centre @ centre)
    residual = np.max(np.abs(np.hypot(*(points - centre).T) - radius))
    return centre, radius, residual


def icc_world(u, v, r):
    """ICC of a constant body twist, world frame: p0 + R(ψ0)·(−v/r, u/r)."""
    c, s = math.cos(PSI0), math.sin(PSI0)
    bx, by = -v / r, u / r
    return np.array([X0 + c * bx - s * by, Y0 + s * bx + c * by])


def test_the_example_uses_the_documents_settings():
    assert tuple(doc.START) == (0.0, 0.0, math.pi / 2)
    assert doc.DT == 0.1
    assert (A, D) == (0.05, 0.2)
    assert doc.TWIST_PROGRAMS == {"twist_1": (0.1, 0.05, 0.3), "twist_2": (0.6, 0.0, -0.3)}
    assert doc.WHEEL_CASES == {
        "wheels_1": (0.8, 0.6),
        "wheels_2": (0.6, 0.6),
        "wheels_3": (0.6, -0.6),
    }
    assert doc.TWIST_DURATION == 10.0 and doc.WHEEL_DURATION == 100.0


def test_equal_wheel_speeds_drive_straight_along_plus_y(euler):
    result = euler["wheels_2"]
    omega = 0.6
    # Heading π/2 never changes, so Euler is exact: y = a·ω·t along +y, x = 0.
    np.testing.assert_allclose(result.poses[:, 0], 0.0, atol=1e-15)
    np.testing.assert_allclose(result.poses[:, 1], A * omega * result.t, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(result.poses[:, 2], math.pi / 2, rtol=0, atol=1e-15)
    assert result.poses[-1, 1] == pytest.approx(3.0, rel=1e-12)  # 0.05 m · 0.6 rad/s · 100 s


def test_opposite_wheel_speeds_spin_in_place(euler):
    result = euler["wheels_3"]
    left, right = doc.WHEEL_CASES["wheels_3"]
    rate = A * (right - left) / (2 * D)
    assert rate == pytest.approx(-0.15)
    np.testing.assert_array_equal(result.poses[:, :2], 0.0)
    expected = wrap_angle(PSI0 + rate * result.t)
    np.testing.assert_allclose(wrap_angle(result.poses[:, 2] - expected), 0.0, atol=1e-12)


def test_unequal_wheel_speeds_drive_on_the_icc_circle(euler, exact):
    left, right = doc.WHEEL_CASES["wheels_1"]
    radius = D * (left + right) / (right - left)  # signed, doc 001 eq. 7: −1.4 m (to the right)
    v, omega = A * (left + right) / 2, A * (right - left) / (2 * D)
    assert radius == pytest.approx(-1.4) and radius == pytest.approx(v / omega)
    assert float(doc.robot().icc_radius(left, right)) == pytest.approx(radius)
    centre = icc_world(v, 0.0, omega)
    np.testing.assert_allclose(centre, [1.4, 0.0], atol=1e-15)

    # The closed-form arc: x = x0 + R(sin ψ − sin ψ0), y = y0 − R(cos ψ − cos ψ0).
    psi = PSI0 + omega * exact["wheels_1"].t
    arc = np.column_stack(
        [X0 + radius * (np.sin(psi) - np.sin(PSI0)), Y0 - radius * (np.cos(psi) - np.cos(PSI0))]
    )
    np.testing.assert_allclose(exact["wheels_1"].poses[:, :2], arc, atol=1e-12)
    distances = np.hypot(*(exact["wheels_1"].poses[:, :2] - centre).T)
    np.testing.assert_allclose(distances, abs(radius), rtol=1e-12)

    # Euler (the document's method) ends 3.3 mm off the arc after 100 s.
    end_error = float(np.hypot(*(euler["wheels_1"].poses[-1, :2] - arc[-1])))
    assert end_error == pytest.approx(3.32e-3, abs=0.01e-3)


def test_why_euler_is_off_the_arc(euler):
    """Euler walks a regular polygon: side h·v, turn h·ω, i.e. a circle of radius
    h·v / (2 sin(h|ω|/2)), tilted by h·ω/2 about the start. Its error is therefore
    (h|ω|/2)·|p(t) − p0| to first order, and halves with the step."""
    h = doc.DT
    for name, (u, v, r) in doc.TWIST_PROGRAMS.items():
        _, radius, residual = fit_circle(euler[name].poses[:, :2])
        speed = math.hypot(u, v)
        assert residual < 1e-9
        assert radius == pytest.approx(h * speed / (2 * math.sin(abs(r) * h / 2)), rel=1e-9)
        assert radius == pytest.approx(speed / abs(r), rel=1e-3)  # → √(u²+v²)/r as h → 0

    left, right = doc.WHEEL_CASES["wheels_1"]
    omega = A * (right - left) / (2 * D)
    result = euler["wheels_1"]
    exact_end = simulate(doc.robot(), doc.START, (left, right), 100.0, h, "exact").poses[-1]
    error = np.hypot(*(result.poses[-1, :2] - exact_end[:2]))
    predicted = abs(omega) * h / 2 * np.hypot(*(result.poses[-1, :2] - [X0, Y0]))
    assert error == pytest.approx(predicted, rel=0.01)
    half = simulate(doc.robot(), doc.START, (left, right), 100.0, h / 2, "euler").poses[-1]
    assert np.hypot(*(half[:2] - exact_end[:2])) / error == pytest.approx(0.5, abs=0.01)


@pytest.mark.parametrize("name", ["twist_1", "twist_2"])
def test_body_twist_programs_drive_circles(exact, name):
    u, v, r = doc.TWIST_PROGRAMS[name]
    radius = math.hypot(u, v) / abs(r)  # 0.3727 m and 2 m
    centre = icc_world(u, v, r)
    distances = np.hypot(*(exact[name].poses[:, :2] - centre).T)
    np.testing.assert_allclose(distances, radius, rtol=1e-12)
    # The heading turns at r; the body velocity stays at the same angle to the radius.
    expected = wrap_angle(PSI0 + r * exact[name].t)
    np.testing.assert_allclose(wrap_angle(exact[name].poses[:, 2] - expected), 0, atol=1e-12)
    # Same circle from the model's own derivative: the pose rate is tangent to it.
    rates = BodyTwist().derivative(exact[name].poses, (u, v, r))
    radial = exact[name].poses[:, :2] - centre
    np.testing.assert_allclose(np.sum(rates[:, :2] * radial, axis=1), 0.0, atol=1e-12)


def test_program_1_radii():
    assert math.hypot(0.1, 0.05) / 0.3 == pytest.approx(0.372678, abs=1e-6)
    assert math.hypot(0.6, 0.0) / 0.3 == pytest.approx(2.0)
    np.testing.assert_allclose(icc_world(0.1, 0.05, 0.3), [-1 / 3, -1 / 6], atol=1e-15)
    np.testing.assert_allclose(icc_world(0.6, 0.0, -0.3), [2.0, 0.0], atol=1e-15)


def test_example_script_writes_its_figures(tmp_path, capsys):
    assert doc.main([str(tmp_path)]) == 0
    printed = capsys.readouterr().out
    assert "3.321" in printed  # case 1's Euler error [mm]
    names = [f"doc000_{case}" for case in (*doc.TWIST_PROGRAMS, *doc.WHEEL_CASES)]
    for name in names:
        assert (tmp_path / f"{name}.png").read_bytes()[:4] == b"\x89PNG"
        with Image.open(tmp_path / f"{name}.gif") as gif:
            assert 2 <= gif.n_frames <= 150
        assert (tmp_path / f"{name}.gif").stat().st_size < 2_000_000
    for group in ("twist", "wheel"):
        assert (tmp_path / f"doc000_{group}_paths.png").exists()
