"""One rule for angles: every wrap in the library goes through wheelbase.geometry.wrap_angle or
its compiled twin, and gives (−π, π], so an angle of exactly −π comes out +π everywhere."""

from __future__ import annotations

import ast
import math
from pathlib import Path

import numpy as np

from wheelbase.control import PolarPose
from wheelbase.control.point import go_to_point_law
from wheelbase.control.tracking import tracking_errors
from wheelbase.geometry import wrap_angle
from wheelbase.geometry_numba import wrap_angle_scalar

SRC = Path(__file__).resolve().parents[1] / "src" / "wheelbase"
# The MPPI modules are being split apart by another change; their own wraps stay until then
# (mppi_numba's maps −π to +π; mppi_jax's is jnp.arctan2 on the JAX backend).
NOT_YET = {"control/mppi_numba.py", "control/mppi_jax.py"}


def test_the_compiled_twin_agrees_with_wrap_angle():
    rng = np.random.default_rng(0)
    angles = np.concatenate([
        rng.uniform(-1e4, 1e4, 2000),
        np.arange(-40, 41) * math.pi,  # every multiple of π: the interval's ends
        np.nextafter(np.arange(-9, 10, 2) * math.pi, np.inf),
        np.nextafter(np.arange(-9, 10, 2) * math.pi, -np.inf),
        [0.0, -0.0, 1e-300, -1e-300],
    ])  # fmt: skip
    twin = np.array([wrap_angle_scalar(float(a)) for a in angles])
    numpy = wrap_angle(angles)
    assert np.all((twin > -math.pi) & (twin <= math.pi))
    assert np.all((numpy > -math.pi) & (numpy <= math.pi))
    # the same angle to rounding (compared on the circle: near ±π they may sit at either end)
    gap = np.abs(wrap_angle(twin - numpy))
    assert np.all(gap <= 4e-16 * np.abs(angles) + 1e-15), gap.max()
    for a in (-math.pi, math.pi):  # −π is +π, exactly
        assert wrap_angle_scalar(a) == float(wrap_angle(a)) == math.pi
    for a in (3 * math.pi, -3 * math.pi, -101 * math.pi):  # (odd multiples to rounding)
        assert abs(wrap_angle_scalar(a) - math.pi) < 1e-13
    assert math.isnan(wrap_angle_scalar(math.nan))


def raw_wraps(path: Path) -> list[int]:
    """Lines of ``path`` that wrap by hand: ``atan2(sin(a), cos(a))`` (math, NumPy or JAX)."""
    lines = []
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Call) and len(node.args) == 2:
            name = getattr(node.func, "attr", getattr(node.func, "id", ""))
            parts = [getattr(a, "func", None) for a in node.args]
            inner = [getattr(p, "attr", getattr(p, "id", "")) for p in parts]
            if name in ("atan2", "arctan2") and inner == ["sin", "cos"]:
                lines.append(node.lineno)
    return lines


def test_no_module_wraps_angles_by_hand():
    found = {}
    for path in SRC.rglob("*.py"):
        name = str(path.relative_to(SRC))
        if name in NOT_YET or name == "geometry.py":  # geometry.py: the helper itself
            continue
        if lines := raw_wraps(path):
            found[name] = lines
    assert not found, f"wrap with wheelbase.geometry.wrap_angle or its twin: {found}"


def test_the_hand_wrap_finder_sees_every_spelling(tmp_path):
    source = tmp_path / "m.py"
    source.write_text(
        "a = np.arctan2(np.sin(x), np.cos(x))\nb = math.atan2(math.sin(y), math.cos(y))\n"
        "c = jnp.arctan2(jnp.sin(z), jnp.cos(z))\nd = np.arctan2(dy, dx)\n"
    )
    assert raw_wraps(source) == [1, 2, 3]


def test_a_heading_error_of_exactly_minus_pi_is_plus_pi_in_every_law():
    # tracking: the reference faces the other way (0 − π = −π exactly)
    errors = tracking_errors([0.0, 0.0, math.pi], [0.0, 0.0, 0.0])
    assert errors[2] == math.pi
    # go to a point straight behind (atan2(−0, −1) = −π): e_φ = +π, the turn is positive
    _, omega = go_to_point_law(np.array(-1.0), np.array(-0.0), np.array(0.0), 2.0, 1.0)
    assert float(omega) == 2.0 * math.pi
    # the polar pose law 1 m ahead of its goal, facing away from it: α = wrap(−π − 0) = +π,
    # β = wrap(−0 − α) = +π, so ω = (k_α + k_β)·π
    law = PolarPose(k_rho=1.0, k_alpha=3.0, k_beta=-1.0, bidirectional=False)
    command = law(0.0, [1.0, 0.0, 0.0], [0.0, 0.0, 0.0])
    np.testing.assert_allclose(command, [1.0, (3.0 - 1.0) * math.pi], atol=1e-12)
