"""UMBmark (Borenstein & Feng 1996): the square test, its linear model and the correction."""

import math

import numpy as np
import pytest

from wheelbase.errors import ConfigError
from wheelbase.models import DiffDrive
from wheelbase.odometry import (
    OdometryErrors,
    WheelOdometry,
    calibrate_umbmark,
    umbmark_correction,
    umbmark_test,
)

ROBOT = DiffDrive(wheel_radius=0.05, half_track=0.2)
ODO = WheelOdometry(0.05, 0.2, 2**30)  # fine encoder: the systematic part alone
L = 4.0


def test_target_reduction_for_ed_1_005_and_eb_1_02():
    cal = calibrate_umbmark(1.005, 1.02)
    assert cal.before.e_max_syst > 0.5  # metres, before correction
    assert cal.reduction >= 10.0
    assert cal.correction.diameter_ratio == pytest.approx(1.005, abs=1e-4)
    assert cal.correction.track_ratio == pytest.approx(1.02, abs=2e-3)
    c_left, c_right = OdometryErrors(1.005, 1.02).scale_factors
    assert cal.correction.scale_left == pytest.approx(c_left, abs=1e-4)
    assert cal.correction.scale_right == pytest.approx(c_right, abs=1e-4)
    assert cal.correction.track == pytest.approx(0.4 * 1.02, abs=1e-3)


def test_a_second_round_removes_the_linearisation_error():
    cal = calibrate_umbmark(0.99, 0.97, iterations=2)
    assert cal.reduction > 100.0
    assert cal.correction.track_ratio == pytest.approx(0.97, abs=1e-4)
    assert cal.correction.diameter_ratio == pytest.approx(0.99, abs=1e-4)


def test_type_a_error_matches_the_linear_model():
    eb = 1.0005
    alpha = 0.5 * math.pi * (1 - 1 / eb)  # each 90° turn falls short by α
    result = umbmark_test(ROBOT, OdometryErrors(track_ratio=eb), ODO, side=L, runs=1)
    np.testing.assert_allclose(result.cg_cw, -2 * L * alpha * np.array([1, 1]), rtol=0.02)
    np.testing.assert_allclose(result.cg_ccw, -2 * L * alpha * np.array([1, -1]), rtol=0.02)
    corr = umbmark_correction(result, ODO)
    assert corr.alpha == pytest.approx(alpha, rel=0.02)
    assert abs(corr.beta) < 1e-3 * alpha


def test_type_b_error_matches_the_linear_model():
    ed = 1.0005
    c_left, c_right = OdometryErrors(ed).scale_factors
    beta = (c_right - c_left) * L / (2 * 0.2)  # the legs curve left by β
    result = umbmark_test(ROBOT, OdometryErrors(diameter_ratio=ed), ODO, side=L, runs=1)
    np.testing.assert_allclose(result.cg_cw, -2 * L * beta * np.array([1, 1]), rtol=0.02)
    np.testing.assert_allclose(result.cg_ccw, 2 * L * beta * np.array([1, -1]), rtol=0.02)
    corr = umbmark_correction(result, ODO, use="x")
    assert corr.beta == pytest.approx(beta, rel=0.02)
    assert corr.diameter_ratio == pytest.approx(ed, abs=1e-6)


def test_perfect_robot_closes_the_square():
    result = umbmark_test(ROBOT, OdometryErrors(), WheelOdometry(0.05, 0.2, 4096), runs=5)
    assert result.e_max_syst < 1e-3
    assert result.errors_cw.shape == (5, 2) and result.paths_ccw.shape == (5, 9, 3)
    # The ccw square lies in y > 0, the cw one in y < 0 (start facing +x).
    assert result.paths_ccw[0, 2:7, 1].min() > 3.9 - 4 and result.paths_ccw[0, 4, 1] > 3.9
    assert result.paths_cw[0, 4, 1] < -3.9


@pytest.mark.parametrize("seed", [0, 1])
def test_random_slip_limits_what_five_runs_can_estimate(seed):
    # 0.1 % slip per segment scatters the return errors by ~5 cm: the centres of gravity of
    # five runs, hence the estimates, carry that noise, and the residual E_max is at its level.
    cal = calibrate_umbmark(1.005, 1.02, slip_std=0.001, seed=seed)
    assert cal.correction.diameter_ratio == pytest.approx(1.005, abs=5e-4)
    assert cal.correction.track_ratio == pytest.approx(1.02, abs=3e-3)
    scatter = np.std(cal.after.errors_cw, axis=0).max()
    assert cal.reduction > 5.0
    assert cal.after.e_max_syst < 3 * scatter


def test_bad_input():
    with pytest.raises(ConfigError, match="runs"):
        umbmark_test(ROBOT, OdometryErrors(), ODO, runs=0)
    with pytest.raises(ConfigError, match="side"):
        umbmark_test(ROBOT, OdometryErrors(), ODO, side=-4.0)
    with pytest.raises(ConfigError, match="iterations"):
        calibrate_umbmark(iterations=0)
    with pytest.raises(ConfigError, match="diameter_ratio"):
        calibrate_umbmark(diameter_ratio=-1.0)
