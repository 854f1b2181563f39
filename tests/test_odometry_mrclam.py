"""Dead reckoning on real data: UTIAS MRCLAM dataset 6, robot 1 (odometry vs Vicon)."""

import math

import numpy as np
import pytest

from shared_data import DATA as SHARED_DATA
from shared_data import absent
from wheelbase.datasets import MrclamData, load_mrclam
from wheelbase.errors import ConfigError, DataError
from wheelbase.odometry import command_response, dead_reckoning_errors, yaw_rate_fit

DATA = SHARED_DATA / "mrclam"
ODOMETRY = DATA / "Dataset6_Robot1_Odometry.dat"
TRUTH = DATA / "Dataset6_Robot1_Groundtruth.dat"
needs_data = pytest.mark.skipif(
    not (ODOMETRY.is_file() and TRUTH.is_file()),
    reason=absent(DATA),
)


@pytest.fixture(scope="module")
def data():
    return load_mrclam(ODOMETRY, TRUTH)


@needs_data
def test_loader_aligns_the_files(data):
    raw_truth = np.loadtxt(TRUTH, comments="#")
    assert data.t[0] >= raw_truth[0, 0] and data.t[-1] <= raw_truth[-1, 0]
    assert np.all(np.diff(data.t) > 0)
    assert data.t.size > 40000 and data.duration > 700
    assert np.all(np.abs(data.true_pose[:, 2]) <= math.pi)
    # At an odometry time that is also a ground-truth time, the interpolation is the sample.
    common, i_odo, i_gt = np.intersect1d(data.t, raw_truth[:, 0], return_indices=True)
    assert common.size > 10
    np.testing.assert_allclose(data.true_pose[i_odo, :2], raw_truth[i_gt, 1:3], atol=1e-12)


@needs_data
def test_dead_reckoning_errors_on_real_data(data):
    records = dead_reckoning_errors(data, horizons=(10.0, 300.0), n_starts=4)
    by = {}
    for r in records:
        by.setdefault((r["horizon_s"], r["method"]), []).append(r)
    short = np.median([r["position_error_m"] for r in by[10.0, "exact"]])
    long = np.median([r["position_error_m"] for r in by[300.0, "exact"]])
    assert short < 0.2 < 1.0 < long  # metres: a few cm after 10 s, metres after 5 minutes
    # At 100 Hz the choice of update is irrelevant against the sensor errors (< 5 cm apart).
    for horizon in (10.0, 300.0):
        for method in ("euler", "midpoint"):
            a = [r["position_error_m"] for r in by[horizon, method]]
            b = [r["position_error_m"] for r in by[horizon, "exact"]]
            np.testing.assert_allclose(a, b, atol=0.05)
    # Over 300 s the heading error dominates: with the true heading the error is far smaller.
    with_true_heading = np.median([r["true_heading_position_error_m"] for r in by[300.0, "exact"]])
    assert with_true_heading < 0.3 * long


@needs_data
def test_yaw_rate_of_the_odometry_is_late_and_too_large(data):
    # What dominates the heading error: the odometry yaw rate leads the Vicon one by about
    # 0.2 s and over-reports turning by about 15-20 % (an effective-track error, UMBmark type A).
    fit = yaw_rate_fit(data)
    assert 0.1 <= fit["lag_s"] <= 0.4
    assert fit["correlation"] > 0.85
    assert 0.75 < fit["scale"] < 0.92


def test_yaw_rate_fit_recovers_a_synthetic_lag_and_scale():
    t = np.arange(0.0, 60.0, 0.01)
    omega = 0.3 * np.sin(0.7 * t) + 0.2 * np.sin(2.1 * t)
    lag, scale = 0.3, 0.8
    heading = scale * (-0.3 / 0.7 * np.cos(0.7 * (t - lag)) - 0.2 / 2.1 * np.cos(2.1 * (t - lag)))
    pose = np.column_stack([np.zeros_like(t), np.zeros_like(t), np.angle(np.exp(1j * heading))])
    fit = yaw_rate_fit(MrclamData(t, np.zeros_like(t), omega, pose))
    assert fit["lag_s"] == pytest.approx(lag, abs=0.051)
    assert fit["scale"] == pytest.approx(scale, rel=0.03)


@needs_data
def test_the_robot_follows_its_speed_command_later_than_its_yaw_rate_command(data):
    # the forward speed needs the robot's mass accelerated: its mean delay is longer
    fit = command_response(data)
    assert 0.15 <= fit["yaw_rate_delay_s"] <= 0.25
    assert 0.22 <= fit["speed_delay_s"] <= 0.36
    assert 0.9 < fit["speed_gain"] < 1.0 and 0.9 < fit["yaw_rate_gain"] < 1.02


def test_command_response_recovers_synthetic_delays_and_gains():
    rng = np.random.default_rng(5)
    t = np.arange(0.0, 300.0, 0.01)
    change = np.cumsum(rng.exponential(2.0, 400))  # commands held for ~2 s
    which = np.searchsorted(change, t)
    v_cmd = rng.uniform(0.0, 0.1, 401)[which]
    w_cmd = rng.uniform(-0.4, 0.4, 401)[which]
    (dv, gv), (dw, gw) = (0.3, 0.95), (0.1, 0.9)
    v = gv * v_cmd[np.clip(np.arange(t.size) - round(dv / 0.01), 0, None)]
    w = gw * w_cmd[np.clip(np.arange(t.size) - round(dw / 0.01), 0, None)]
    heading = np.concatenate([[0.0], np.cumsum(w[:-1] * 0.01)])
    mid = heading[:-1] + 0.5 * w[:-1] * 0.01
    x = np.concatenate([[0.0], np.cumsum(v[:-1] * 0.01 * np.cos(mid))])
    y = np.concatenate([[0.0], np.cumsum(v[:-1] * 0.01 * np.sin(mid))])
    pose = np.column_stack([x, y, np.angle(np.exp(1j * heading))])
    fit = command_response(MrclamData(t, v_cmd, w_cmd, pose))
    assert fit["speed_delay_s"] == pytest.approx(dv, abs=0.02)
    assert fit["yaw_rate_delay_s"] == pytest.approx(dw, abs=0.02)
    assert fit["speed_gain"] == pytest.approx(gv, rel=0.02)
    assert fit["yaw_rate_gain"] == pytest.approx(gw, rel=0.02)
    assert fit["speed_response"].shape == (24,)


def write(path, rows, header="# comment\n"):
    path.write_text(header + "\n".join(" ".join(map(str, row)) for row in rows) + "\n")
    return path


def test_heading_is_interpolated_across_the_wrap(tmp_path):
    odo = write(tmp_path / "odo.dat", [[0.5, 0.1, 0.0], [1.5, 0.1, 0.0], [9.0, 0.1, 0.0]])
    gt = write(tmp_path / "gt.dat", [[0.0, 0, 0, 3.0], [1.0, 0, 0, -3.0], [2.0, 0, 0, -3.0]])
    data = load_mrclam(odo, gt)
    assert data.t.tolist() == [0.5, 1.5]  # the sample after the ground truth ends is dropped
    assert abs(data.true_pose[0, 2]) == pytest.approx(math.pi, abs=1e-12)


def test_bad_files(tmp_path):
    gt = write(tmp_path / "gt.dat", [[0.0, 0, 0, 0], [1.0, 0, 0, 0]])
    with pytest.raises(DataError, match="not found"):
        load_mrclam(tmp_path / "missing.dat", gt)
    bad = tmp_path / "bad.dat"
    bad.write_text("# header\n1.0 abc 2\n")
    with pytest.raises(DataError, match="malformed"):
        load_mrclam(bad, gt)
    wrong = write(tmp_path / "wrong.dat", [[0.0, 1.0], [1.0, 1.0]])
    with pytest.raises(DataError, match="3 columns"):
        load_mrclam(wrong, gt)
    later = write(tmp_path / "later.dat", [[5.0, 0.1, 0.0], [6.0, 0.1, 0.0]])
    with pytest.raises(DataError, match="overlap"):
        load_mrclam(later, gt)


def test_error_report_checks_its_arguments():
    t = np.linspace(0, 20, 201)
    data = MrclamData(t, np.full(201, 0.1), np.zeros(201), np.column_stack([0.1 * t, 0 * t, 0 * t]))
    records = dead_reckoning_errors(data, horizons=(10.0,), n_starts=3)
    assert len(records) == 9
    assert max(r["position_error_m"] for r in records) < 1e-12
    assert records[0]["distance_m"] == pytest.approx(1.0)
    with pytest.raises(ConfigError, match="horizon"):
        dead_reckoning_errors(data, horizons=(30.0,))
    with pytest.raises(ConfigError, match="n_starts"):
        dead_reckoning_errors(data, n_starts=0)
