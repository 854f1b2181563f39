"""Gyrodometry (Borenstein and Feng 1996): the wheels' heading unless the gyro disagrees."""

import math

import numpy as np
import pytest

from wheelbase.errors import ConfigError, ScenarioError
from wheelbase.odometry import Encoder, WheelOdometry
from wheelbase.runner import prepare, run_metrics
from wheelbase.scenario import load_scenario
from wheelbase.sensors import Imu
from wheelbase.sim.gyrodometry import Gyrodometry
from wheelbase.sim.sensing import EncoderOdometry

RADIUS, HALF_TRACK, PULSES, DT = 0.065, 0.2275, 2048, 0.01
TICK_ROTATION = 2 * math.pi * RADIUS / PULSES / (2 * HALF_TRACK)
SILENT = Imu(gyro_noise_density=0.0, gyro_bias_std=0.0, accel_noise_density=0.0,
             accel_bias_std=0.0)  # fmt: skip


def _odometry(imu=SILENT, noise_std=0.0):
    inner = EncoderOdometry(Encoder(PULSES, noise_std=noise_std),
                            WheelOdometry(RADIUS, HALF_TRACK, PULSES))  # fmt: skip
    return Gyrodometry(inner, imu)


def _drive(odometry, ticks, gyro, state=None):
    """Dead-reckon rows of ``ticks`` (K, 2) with gyro readings ``gyro`` (K,) [rad/s]."""
    if state is None:
        state = odometry.start(np.zeros((1, 3)), np.zeros(1))
    pose = np.zeros((1, 3))
    for tick, rate in zip(ticks, gyro, strict=True):
        pose, twist, state = odometry.update(
            pose, np.array([tick]), DT, None, None, state=state, index=np.array([0]),
            imu=np.array([[rate, 0.0, 0.0]]),
        )  # fmt: skip
    return pose, twist, state


def _wheels_alone(ticks):
    odometry = _odometry().inner
    pose = np.zeros((1, 3))
    for tick in ticks:
        pose, *_ = odometry.update(pose, np.array([tick]), DT, None, None)
    return pose


def test_a_spinning_wheel_turns_the_wheels_heading_but_not_the_gyros():
    # the right wheel turns 10 ticks a step more than the left: 0.44 rad/s by the wheels, the
    # gyro reads no turn (the right wheel spins). The window passes the threshold after a few
    # steps; the heading then catches up on the steps counted on the wheels till then, so it
    # is the gyro's 0 throughout, where the wheels alone counted 4.4°
    odometry = _odometry()
    ticks = [[20, 30]] * 100
    pose, twist, _ = _drive(odometry, ticks, [0.0] * 100)
    assert twist[0, 2] == pytest.approx(10 * TICK_ROTATION / DT)  # the twist is the wheels'
    assert _wheels_alone(ticks)[0, 2] == pytest.approx(100 * 10 * TICK_ROTATION)
    assert pose[0, 2] == pytest.approx(0.0, abs=1e-12)
    assert pose[0, 0] > 0.0  # the distance is the wheels'


def test_one_ticks_quantisation_a_step_is_not_taken_for_a_slip():
    # a straight drive whose right wheel is half a tick ahead of the left: the counts alternate,
    # so the wheels' rotation jumps by one tick a step (δ/Δt = 1.6 °/s, more than a slip a
    # per-step comparison can tell from it) while the gyro reads the true 0. Over the window
    # the quantisation stays within 2 ticks: the heading is the wheels' to the bit
    encoder = Encoder(PULSES)
    per_tick = encoder.radians_per_tick
    angle = np.arange(301)[:, None] * 7.5 * per_tick + np.array([0.0, 0.5 * per_tick])
    counts = encoder.count(angle)
    ticks = np.diff(counts, axis=0)
    assert set(np.unique(ticks[:, 1] - ticks[:, 0])) == {-1, 1}
    pose, *_ = _drive(_odometry(), ticks, np.zeros(len(ticks)))
    assert pose.tolist() == _wheels_alone(ticks).tolist()


def test_a_slow_slip_that_no_single_step_shows_is_seen_over_the_window():
    # the right wheel gains one tick every 4th step on a straight drive (0.4 °/s of spin), the
    # gyro reads the true 0: no step's disagreement (one tick) passes the 2-tick bound, the
    # window's 12 do, and from then the heading is the gyro's, where the wheels counted 50 ticks
    ticks = [[8, 9] if k % 4 == 3 else [8, 8] for k in range(200)]
    pose, *_ = _drive(_odometry(), ticks, np.zeros(len(ticks)))
    assert _wheels_alone(ticks)[0, 2] == pytest.approx(50 * TICK_ROTATION)
    assert pose[0, 2] == pytest.approx(0.0, abs=1e-12)


def test_the_threshold_is_two_ticks_and_the_gyros_error_over_the_window():
    imu = Imu()
    odometry = _odometry(imu)
    steps = odometry.steps(DT)
    span = steps * DT
    noise = imu.gyro_noise_density
    gyro = 4 * (noise * math.sqrt(span) + noise * span)  # calibration 1 s at rest
    assert steps == 50
    assert odometry.threshold(DT) == pytest.approx(2 * TICK_ROTATION + gyro)
    noisy = _odometry(imu, noise_std=0.5)
    assert noisy.threshold(DT) == pytest.approx(
        odometry.threshold(DT) + 4 * TICK_ROTATION * 0.5 * math.sqrt(2 * steps)
    )


def test_the_gyro_bias_comes_from_the_start_up_calibration():
    # a gyro biased 0.1 °/s at rest: calibrated, a spin's heading is the true 0; uncalibrated,
    # the bias is read as a turn while the gyro is used (100 steps: 0.1°)
    bias = math.radians(0.1)
    odometry = _odometry()
    ticks, gyro = [[20, 30]] * 100, [bias] * 100
    state = odometry.start(np.zeros((1, 3)), np.zeros(1))
    calibrated = odometry.calibrate(state, np.array([[bias, 0.0, 0.0]]), np.zeros((1, 3)))
    assert calibrated["bias"].tolist() == [bias]
    pose, *_ = _drive(odometry, ticks, gyro, calibrated)
    assert pose[0, 2] == pytest.approx(0.0, abs=1e-12)
    pose, *_ = _drive(odometry, ticks, gyro, state)
    assert pose[0, 2] == pytest.approx(100 * DT * bias)
    # a robot that starts turning at r is told so: the reading less r is the bias
    moving = odometry.calibrate(state, np.array([[0.3 + bias, 0.0, 0.0]]), np.array([[0, 0, 0.3]]))
    assert moving["bias"][0] == pytest.approx(bias)


def test_gyrodometry_refuses_what_it_cannot_wrap():
    with pytest.raises(ConfigError, match="encoder odometry"):
        Gyrodometry(object(), SILENT)
    with pytest.raises(ConfigError, match="imu"):
        Gyrodometry(_odometry().inner, object())
    with pytest.raises(ConfigError, match="window"):
        Gyrodometry(_odometry().inner, SILENT, window=0.0)


def _ice_demo(gyro: bool, imu: dict | None = None) -> dict:
    data = load_scenario("demo").model_dump(mode="json")
    data["terrain"] = {"surface": "ice"}
    data["controller"]["traction_control"] = {"friction": "estimate", "slow_down": True,
                                              "rolling_resistance": 0.013}  # fmt: skip
    data["sensors"] = {"imu": {} if imu is None else imu}
    data["odometry"]["gyro"] = gyro
    return data


def test_odometry_gyro_needs_the_imu_and_plain_odometry():
    data = _ice_demo(True)
    data["sensors"] = {"imu": None}
    with pytest.raises(ScenarioError, match=r"odometry\.gyro"):
        load_scenario(data)
    data = _ice_demo(True)
    data["localization"] = {"method": "ekf"}
    data["sensors"]["landmarks"] = {"positions": [[3.0, 3.0]], "max_range": 5.0}
    with pytest.raises(ScenarioError, match=r"odometry\.gyro"):
        prepare(data)


def test_the_engine_hands_the_start_up_calibration_to_the_odometry():
    # the bias is the run's drawn bias within 5 σ of the 1 s calibration's noise N/√1 s
    prepared = prepare(_ice_demo(True, {"gyro_bias_std_deg": 1.0}))
    assert isinstance(prepared.engine.estimator, Gyrodometry)
    state = prepared.engine.reset(prepared.start, seeds=[0])
    drawn = state.imu.bias[0, 0]
    assert abs(drawn) > math.radians(0.01)
    assert state.estimator["bias"][0] == pytest.approx(
        drawn, abs=5 * prepared.engine.imu.gyro_noise_density
    )


def test_the_start_spin_on_ice_no_longer_turns_the_odometry():
    # the ice demo with the friction estimate: the start spin (right wheel, t ≈ 0.3-0.4 s)
    # turned the wheels' heading 0.5° within 0.5 s and the turns' slip 1.9° by 20 s (seed 0,
    # measured, 1.96° at most); with the gyro the heading stays within 0.5° (0.26° measured)
    # and the odometry within 0.06 m of the truth at the end (0.05 measured; 0.20 without),
    # the true error below 0.12 m (0.094 measured; 0.22 without)
    errors = {}
    for gyro in (False, True):
        prepared = prepare(_ice_demo(gyro))
        log = prepared.engine.run(prepared.start, seeds=[0])
        n = int(log.length[0])
        heading = log.estimated_pose[0, :n, 2] - log.true_pose[0, :n, 2]
        heading = np.abs((heading + np.pi) % (2 * np.pi) - np.pi)
        at = np.searchsorted(log.t[:n], 1.0)
        metrics = run_metrics(prepared, log, 0)
        odometry = np.hypot(*(log.estimated_pose[0, n - 1, :2] - log.true_pose[0, n - 1, :2]))
        errors[gyro] = (heading[at], heading.max(), odometry,
                        metrics["final_position_error_true_m"])  # fmt: skip
    assert errors[False][0] > math.radians(0.3)  # what the gyro is for
    assert errors[True][0] < math.radians(0.05)
    assert errors[True][1] < math.radians(0.5) < math.radians(1.0) < errors[False][1]
    assert errors[True][2] < 0.06 < errors[False][2]
    assert errors[True][3] < 0.12 < errors[False][3]
