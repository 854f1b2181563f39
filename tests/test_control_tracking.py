import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from wheelbase import ConfigError, InputError, Unicycle
from wheelbase.control import VelocityLimits
from wheelbase.control.tracking import (
    Kanayama,
    LinearTracker,
    sample_reference,
    tracking_errors,
)
from wheelbase.models import reference_from_derivatives
from wheelbase.sim import closed_loop

LIMITS = VelocityLimits(0.5, 1.5)


def figure_eight(duration=30.0, dt=0.01):
    t = np.arange(0.0, duration + 1e-9, dt)
    w = 2 * np.pi / duration
    return reference_from_derivatives(
        1.1 + 0.7 * np.sin(w * t),
        0.9 + 0.7 * np.sin(2 * w * t),
        0.7 * w * np.cos(w * t),
        1.4 * w * np.cos(2 * w * t),
        -0.7 * w * w * np.sin(w * t),
        -2.8 * w * w * np.sin(2 * w * t),
        t=t,
    )


def test_errors_in_the_robot_frame():
    e = tracking_errors([1.0, 1.0, 0.5 * math.pi], [1.0, 3.0, 0.0])
    np.testing.assert_allclose(e, [2.0, 0.0, -0.5 * math.pi], atol=1e-12)
    e = tracking_errors([0.0, 0.0, 0.0], [1.0, -2.0, 3.0])
    np.testing.assert_allclose(e, [1.0, -2.0, 3.0])


@given(st.floats(0.05, 1.0), st.floats(-2.0, 2.0), st.floats(0.2, 1.5), st.floats(1.0, 100.0))
def test_linear_tracker_poles(v_r, omega_r, zeta, g):
    # Jacobian of the error dynamics ė_x = ω e_y − v + v_r cos e_θ, ė_y = −ω e_x + v_r sin e_θ,
    # ė_θ = ω_r − ω at e = 0 under the law: poles −2ζω_n and −ζω_n ± ω_n√(ζ² − 1)
    law = LinearTracker(zeta=zeta, g=g, min_natural_frequency=0.0)  # the textbook law
    k_x, k_y, k_theta = law.gains(v_r, omega_r)
    jac = np.array([[-k_x, omega_r, 0.0], [-omega_r, 0.0, v_r], [0.0, -k_y, -k_theta]])
    natural = math.sqrt(omega_r**2 + g * v_r**2)
    root = np.sqrt(complex(zeta**2 - 1.0))
    expected = [-2 * zeta * natural, (-zeta + root) * natural, (-zeta - root) * natural]
    got = np.linalg.eigvals(jac)
    np.testing.assert_allclose(np.sort_complex(got), np.sort_complex(expected), atol=1e-6)


@pytest.mark.parametrize("law", [LinearTracker(limits=LIMITS), Kanayama(limits=LIMITS)])
def test_figure_eight_is_tracked_to_the_millimetre(law):
    reference = figure_eight()
    result = closed_loop(law, Unicycle(), [1.1, 0.8, 0.0], reference, 30.0, 0.01)
    errors = tracking_errors(result.true_pose[0], reference.poses)
    late = result.t >= 5.0
    assert np.abs(errors[late, 1]).max() < 1e-3
    assert np.hypot(errors[late, 0], errors[late, 1]).max() < 2e-3
    assert np.abs(errors[0, 1]) > 0.05  # it started off the reference


def test_reference_forms_agree():
    reference = figure_eight()
    pose, v, omega = sample_reference(reference, 7.0)
    index = 700
    np.testing.assert_allclose(pose, reference.poses[index], atol=1e-12)
    assert float(v) == pytest.approx(reference.v[index])
    law = Kanayama()
    from_object = law(7.0, [1.0, 1.0, 0.2], reference)
    from_tuple = law(7.0, [1.0, 1.0, 0.2], (pose, v, omega))
    from_callable = law(7.0, [1.0, 1.0, 0.2], lambda t: (pose, v, omega))
    np.testing.assert_allclose(from_object, from_tuple)
    np.testing.assert_allclose(from_callable, from_tuple)


def test_kanayama_on_the_reference_is_the_feed_forward():
    command = Kanayama()(0.0, [1.0, 2.0, 0.3], ([1.0, 2.0, 0.3], 0.4, -0.2))
    np.testing.assert_allclose(command, [0.4, -0.2])


def test_bad_tracking_input():
    with pytest.raises(InputError, match="moving reference"):
        LinearTracker(min_natural_frequency=0.0)(0.0, [0.0, 0.0, 0.0], ([1.0, 0.0, 0.0], 0.0, 0.0))
    with pytest.raises(ConfigError, match="min_natural_frequency"):
        LinearTracker(min_natural_frequency=-1.0)


def test_linear_tracker_holds_a_standing_reference():
    # At rest, K_x = K_θ = 2ζ·a_min: the x and heading errors are corrected, y is not.
    law = LinearTracker(zeta=0.7, min_natural_frequency=0.5)
    v, omega = law(0.0, [0.0, 0.0, 0.1], ([0.2, 0.0, 0.0], 0.0, 0.0))
    assert v == pytest.approx(0.7 * 0.2 * math.cos(0.1), rel=1e-9)
    assert omega == pytest.approx(-0.7 * 0.1, rel=1e-9)
    v, omega = law(0.0, [0.0, 0.0, 0.0], ([0.0, 0.3, 0.0], 0.0, 0.0))
    assert v == pytest.approx(0.0) and omega == pytest.approx(0.0)
    with pytest.raises(ConfigError, match="k_y"):
        Kanayama(k_y=-1.0)
    with pytest.raises(ConfigError, match="zeta"):
        LinearTracker(zeta=0.0)
    with pytest.raises(InputError, match="tracking reference"):
        Kanayama()(0.0, [0.0, 0.0, 0.0], 3.0)


@pytest.mark.parametrize("law", [Kanayama(), LinearTracker()])
def test_trackers_converge_on_a_reversing_reference(law):
    # The reference backs along −x facing +x; the robot starts 10 cm aside, 0.2 rad off.
    # Kanayama's textbook heading term (v_r·K_θ) is unstable backwards: errors grew to metres.
    pose, dt = np.array([0.0, 0.1, 0.2]), 0.01
    for step in range(1500):
        t = step * dt
        reference = (np.array([-0.3 * t, 0.0, 0.0]), -0.3, 0.0)
        v, omega = law(t, pose, reference)
        pose = pose + dt * np.array([v * math.cos(pose[2]), v * math.sin(pose[2]), omega])
    target = np.array([-0.3 * 1500 * dt, 0.0])
    assert np.hypot(*(pose[:2] - target)) < 2e-3 and abs(pose[2]) < 2e-3
