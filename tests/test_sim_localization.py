"""Sensors and localisation in the closed loop: readings at the true poses, EKF/UKF/AMCL."""

import math

import numpy as np
import pytest

from wheelbase import DiffDrive
from wheelbase.control import Kanayama, VelocityLimits
from wheelbase.errors import ConfigError, EstimationError, MapError
from wheelbase.localization import AMCL, EKF, UKF, OdometryMotion, VelocityMotion
from wheelbase.odometry import Encoder, WheelOdometry
from wheelbase.planning import OccupancyGrid
from wheelbase.sensors import LandmarkSensor, Lidar
from wheelbase.sim import (
    Arrival,
    EncoderOdometry,
    Engine,
    KalmanLocalizer,
    KinematicPlant,
    ParticleLocalizer,
    Readings,
    SensorSuite,
    WheelAxle,
)
from wheelbase.timing import SpeedLimits, time_parametrize

RADIUS, HALF_TRACK, PULSES = 0.05, 0.2, 1024


def room() -> OccupancyGrid:
    """A 6 m × 4 m room (5 cm cells) with two boxes, so that no pose has a twin."""
    cells = np.zeros((80, 120), bool)
    cells[[0, -1], :] = True
    cells[:, [0, -1]] = True
    cells[10:22, 30:40] = True  # box at x 1.5–2.0 m, y 0.5–1.1 m
    cells[50:70, 85:92] = True  # box at x 4.25–4.6 m, y 2.5–3.5 m
    return OccupancyGrid.from_array(cells, 0.05)


GRID = room()
LANDMARKS = np.array([[1.0, 3.5], [3.0, 0.3], [5.5, 1.0], [3.0, 3.7], [0.4, 0.4]])


def reference():
    poses = np.column_stack([np.linspace(1.0, 5.0, 41), np.full(41, 2.0), np.zeros(41)])
    return time_parametrize(poses, limits=SpeedLimits(max_speed=0.5), dt=0.02)


def odometry(noise=0.0):
    return EncoderOdometry(
        Encoder(PULSES, noise_std=noise), WheelOdometry(RADIUS, HALF_TRACK, PULSES)
    )


def engine(estimator, sensors=None, radius_scale=(1.0, 1.0), **options):
    ref = reference()
    settings = {
        "plant": KinematicPlant(
            DiffDrive(RADIUS, HALF_TRACK), WheelAxle(RADIUS, HALF_TRACK, radius_scale=radius_scale)
        ),
        "controller": Kanayama(limits=VelocityLimits(1.0, 2.0)),
        "reference": ref,
        "dt": 0.02,
        "duration": 15.0,
        "estimator": estimator,
        "sensors": sensors,
        "arrival": Arrival([5.0, 2.0, 0.0], (0.03, math.radians(5)), end_time=float(ref.t[-1])),
        "reference_pose": lambda t: ref.poses[min(round(t / 0.02), len(ref.t) - 1)],
    }
    settings.update(options)
    return Engine(**settings)


LIDAR = Lidar(beams=60, max_range=6.0, range_std=0.01)
LANDMARK_SENSOR = LandmarkSensor(
    max_range=4.0, range_std=0.03, bearing_std=math.radians(1.0), detection_probability=0.9,
    false_rate=0.2,
)  # fmt: skip
SUITE = SensorSuite(
    world=GRID, lidar=LIDAR, lidar_rate_hz=10.0, landmarks=LANDMARKS,
    landmark_sensor=LANDMARK_SENSOR, landmark_rate_hz=5.0,
)  # fmt: skip


def ekf(cls=EKF, noise=0.3):
    motion = VelocityMotion(distance_per_m=1e-4, heading_per_m=1e-4, heading_per_rad=1e-4)
    return KalmanLocalizer(
        cls(LANDMARKS, motion, range_std=0.03, bearing_std=math.radians(1.0)), odometry(noise)
    )


def amcl(noise=0.3, **options):
    settings = {
        "motion": OdometryMotion(1e-3, 5e-3, 1e-4, 1e-4),
        "sigma_hit": 0.05,
        "z_hit": 0.9,
        "z_rand": 0.1,
        "min_particles": 100,
        "max_particles": 300,
    }
    settings.update(options)
    return ParticleLocalizer(AMCL(grid=GRID, lidar=LIDAR, **settings), odometry(noise))


def test_sensors_are_read_at_their_rates_at_the_true_poses():
    exact = Lidar(beams=30, max_range=6.0)
    suite = SensorSuite(world=GRID, lidar=exact, lidar_rate_hz=10.0)
    log = engine(odometry(), suite).run([1.0, 2.0, 0.0])
    rows = sorted(row for _, row in log.scans)
    assert rows == list(range(5, int(log.length[0]), 5))  # 10 Hz at dt = 0.02 s
    for row in rows[::7]:
        truth = exact.scan(GRID, log.true_pose[0, row], noise=False)
        np.testing.assert_array_equal(log.scans[(0, row)], truth)
    assert SensorSuite(world=GRID, lidar=exact, lidar_rate_hz=60.0).due(0, 0.02) == (True, False)


@pytest.mark.parametrize("make", [ekf, lambda: ekf(UKF), amcl], ids=["ekf", "ukf", "amcl"])
def test_a_batch_with_sensors_and_filters_equals_its_single_runs(make):
    """Robot i of a batch is the single run with seed i: lidar and landmark noise, clutter,
    missed detections and particles all come from per-robot streams."""
    run = engine(make(), SUITE, radius_scale=(1.0, 1.01), duration=4.0)
    starts = np.array([[1.0, 2.0, 0.0], [1.05, 1.95, 0.05], [0.95, 2.05, -0.05]])
    batch = run.run(starts, seeds=[4, 5, 6])
    for i in range(3):
        alone = run.run(starts[i], seeds=[4 + i])
        picked = batch.robot(i)
        np.testing.assert_allclose(picked.true_pose, alone.true_pose, atol=1e-9, rtol=0)
        np.testing.assert_allclose(picked.estimated_pose, alone.estimated_pose, atol=1e-9, rtol=0)
        for key in ("est_cov_xx", "loc_landmarks_used", "loc_beams_used"):
            np.testing.assert_allclose(picked.extras[key], alone.extras[key], atol=1e-12)
        assert picked.scans.keys() == alone.scans.keys()


def test_a_kalman_filter_without_readings_is_dead_reckoning_with_its_predicted_covariance():
    far = KalmanLocalizer(
        EKF(np.array([[100.0, 100.0]]), VelocityMotion(1e-3, 0.0, 1e-4, 1e-3)), odometry(0.5)
    )
    suite = SensorSuite(landmarks=[[100.0, 100.0]], landmark_sensor=LandmarkSensor(max_range=4.0))
    filtered = engine(far, suite).run([1.0, 2.0, 0.0], seeds=[3])
    plain = engine(odometry(0.5)).run([1.0, 2.0, 0.0], seeds=[3])
    np.testing.assert_allclose(filtered.estimated_pose, plain.estimated_pose, atol=1e-9)
    # the logged covariances are the filter's predict_sequence over the odometry's increments
    one = filtered.robot(0)
    ticks = np.diff(one.ticks[0], axis=0)
    distance, rotation = far.odometry.odometry.increments(ticks)
    controls = np.column_stack([distance, rotation]) / 0.02
    _, covs = far.filter.predict_sequence(
        one.estimated_pose[0, 0], np.diag(np.square(far.initial_std)), controls,
        np.full(len(controls), 0.02),
    )  # fmt: skip
    np.testing.assert_allclose(one.extras["est_cov_xx"][0, 1:], covs[:, 0, 0], rtol=1e-9)
    np.testing.assert_allclose(one.extras["est_cov_ytheta"][0, 1:], covs[:, 1, 2], rtol=1e-9)
    assert one.extras["loc_updates"][0, -1] == 0


@pytest.mark.parametrize("make", [ekf, lambda: ekf(UKF), amcl], ids=["ekf", "ukf", "amcl"])
def test_filters_hold_the_estimate_where_odometry_drifts(make):
    """A 2 % wheel-radius error: odometry misses the goal; every filter arrives."""
    seeds = [0, 1, 2]
    starts = np.tile([1.0, 2.0, 0.0], (3, 1))
    drifting = engine(odometry(0.3), radius_scale=(1.0, 1.02)).run(starts, seeds=seeds)
    assert set(drifting.statuses) <= {"missed_goal", "timeout"}
    log = engine(make(), SUITE, radius_scale=(1.0, 1.02)).run(starts, seeds=seeds)
    assert log.statuses == ["arrived"] * 3
    metrics = log.metrics()
    assert max(m["localization_max_error_m"] for m in metrics) < 0.05
    assert min(m["localization_max_error_m"] for m in drifting.metrics()) > 0.1
    assert np.all(log.extras["loc_updates"][:, -1] > 5)


def test_a_failing_filter_ends_only_its_robot_diverged():
    class Fragile(EKF):
        """Predicts a NaN covariance for robots above y = 2.3 m."""

        def _predict(self, mean, cov, control, dt):
            new_mean, new_cov = super()._predict(mean, cov, control, dt)
            new_cov[mean[:, 1] > 2.3] = np.nan
            return new_mean, new_cov

    localizer = KalmanLocalizer(Fragile(LANDMARKS), odometry())
    with pytest.raises(EstimationError):  # what the engine's estimator turns into a status
        localizer.filter.predict([2.5, 2.4, 0.1], np.eye(3) * 1e-4, [0.1, 0.0], 0.02)
    starts = np.array([[1.0, 2.0, 0.0], [1.0, 2.4, 0.0], [1.0, 1.9, 0.0]])
    log = engine(localizer, SUITE).run(starts)
    assert log.statuses == ["arrived", "diverged", "arrived"]
    assert np.all(np.isfinite(log.estimated_pose))  # never a NaN handed to a controller


def test_bad_readings_are_skipped_and_counted():
    localizer = ekf(noise=0.0)
    state = localizer.start(np.array([[1.0, 2.0, 0.0]]), np.array([0]))
    ids = np.array([[0, 99, 1, 2]])  # 99 names no landmark
    z = np.array([[[2.0, 1.0], [1.0, 0.0], [np.nan, 0.0], [-1.0, 0.0]]])
    estimate, _, state = localizer.update(
        np.array([[1.0, 2.0, 0.0]]), np.zeros((1, 2), np.int64), 0.02, None, None,
        state=state, index=np.array([0]), readings=Readings(landmark_ids=ids, landmark_z=z),
    )  # fmt: skip
    signals = localizer.signals(state)
    assert signals["loc_landmarks_skipped"].tolist() == [3]
    assert signals["loc_landmarks_used"][0] + signals["loc_landmarks_rejected"][0] == 1
    assert np.all(np.isfinite(estimate))

    particles = amcl(noise=0.0, update_min_d=0.0, update_min_a=0.0)
    state = particles.start(np.array([[1.0, 2.0, 0.0]]), np.array([0]))
    scan = LIDAR.scan(GRID, [1.0, 2.0, 0.0], noise=False)[None]
    scan[0, :5] = np.nan
    scan[0, 5:8] = -1.0
    estimate, _, state = particles.update(
        np.array([[1.0, 2.0, 0.0]]), np.zeros((1, 2), np.int64), 0.02, None, None,
        state=state, index=np.array([0]), readings=Readings(scan=scan),
    )  # fmt: skip
    signals = particles.signals(state)
    assert signals["loc_beams_skipped"].tolist() == [8]
    assert signals["loc_updates"].tolist() == [1]
    assert np.hypot(*(estimate[0, :2] - [1.0, 2.0])) < 0.03


def test_bad_sensor_and_filter_settings_are_clear_errors():
    with pytest.raises(ConfigError, match="lidar or a landmark_sensor"):
        SensorSuite(world=GRID)
    with pytest.raises(ConfigError, match="lidar_rate_hz must be > 0"):
        SensorSuite(world=GRID, lidar=LIDAR, lidar_rate_hz=0.0)
    with pytest.raises(ConfigError, match="landmark_rate_hz must be > 0"):
        SensorSuite(landmarks=LANDMARKS, landmark_sensor=LANDMARK_SENSOR, landmark_rate_hz=-5)
    with pytest.raises(ConfigError, match="needs a world"):
        SensorSuite(lidar=LIDAR)
    with pytest.raises(ConfigError, match="needs landmarks"):
        SensorSuite(landmark_sensor=LANDMARK_SENSOR)
    with pytest.raises(ConfigError, match="initial_std x must be >= 0"):
        KalmanLocalizer(EKF(LANDMARKS), odometry(), initial_std=(-0.1, 0.1, 0.1))
    with pytest.raises(ConfigError, match=r"min_particles must be an integer in \[1, 1000000\]"):
        amcl(min_particles=0)
    with pytest.raises(ConfigError, match="sigma_hit must be > 0"):
        amcl(sigma_hit=0.0)
    with pytest.raises(ConfigError, match="sensors must be a SensorSuite"):
        engine(odometry(), sensors=LIDAR)
    full = OccupancyGrid.from_array(np.ones((10, 10), bool), 0.1)
    with pytest.raises(MapError, match="no free cell"):
        ParticleLocalizer(AMCL(grid=full, lidar=LIDAR), odometry(), global_start=True)


def test_the_particle_filter_gets_the_time_its_per_second_motion_noise_needs():
    # A robot at rest: the particles spread only by the motion model's per-second heading
    # noise, over the whole time since the start (11 steps of 0.1 s), as σ² = q·t.
    q = 0.01  # rad²/s
    amcl = AMCL(
        landmarks=LANDMARKS, motion=VelocityMotion(0.0, 0.0, 0.0, 0.0, 0.0, q),
        min_particles=4000, max_particles=4000, update_min_d=0.0, update_min_a=0.0,
    )  # fmt: skip
    localizer = ParticleLocalizer(amcl, odometry(), initial_std=(0.0, 0.0, 0.0))
    pose = np.array([[2.0, 2.0, 0.0]])
    state = localizer.start(pose, np.array([0]))
    index, still = np.array([0]), np.zeros((1, 2), dtype=np.int64)
    nothing = Readings(landmark_ids=np.zeros((1, 0), np.int64), landmark_z=np.zeros((1, 0, 2)))
    for k in range(11):
        readings = nothing if k == 10 else None  # the filter runs once, at t = 1.1 s
        _, _, state = localizer.update(
            pose, still, 0.1, pose, np.zeros((1, 3)), state=state, index=index, readings=readings
        )
    heading = state.filters[0].particles[:, 2]
    assert state.counts[0, 0] == 1 and state.filters[0].time == pytest.approx(1.1)
    assert np.std(heading) == pytest.approx(math.sqrt(q * 1.1), rel=0.05)


def _same(a, b) -> None:
    """Two engine states (or the parts of one) are equal, array by array."""
    import dataclasses

    if dataclasses.is_dataclass(a) and not isinstance(a, type):
        for f in dataclasses.fields(a):
            if f.name != "controllers":
                _same(getattr(a, f.name), getattr(b, f.name))
    elif isinstance(a, (list, tuple)):
        assert len(a) == len(b)
        for x, y in zip(a, b, strict=True):
            _same(x, y)
    elif isinstance(a, np.ndarray):
        np.testing.assert_array_equal(a, b)
    elif isinstance(a, (int, float, np.number)):
        assert a == b or (np.isnan(a) and np.isnan(b))


@pytest.mark.parametrize(
    "make",
    [
        lambda: ekf(),
        lambda: amcl(),
        lambda: ParticleLocalizer(
            AMCL(grid=GRID, lidar=LIDAR, min_particles=100, max_particles=300),
            EncoderOdometry(
                Encoder(PULSES, noise_std=0.3, miss_probability=0.01),
                WheelOdometry(RADIUS, HALF_TRACK, PULSES),
            ),
        ),
    ],
)
def test_stepping_one_state_twice_gives_the_same_state(make):
    import copy

    eng = engine(make(), SUITE, radius_scale=(1.0, 1.01))
    state = eng.reset([[1.0, 2.0, 0.0], [1.0, 2.05, 0.0]], seeds=[3, 4])
    for _ in range(30):  # past a few sensor readings and filter updates
        state, _ = eng.step(state)
    saved = copy.deepcopy(state)
    first, _ = eng.step(state)
    second, _ = eng.step(state)
    _same(state, saved)  # the step changed nothing of what it was given
    _same(first, second)
    for _ in range(40):  # and the futures of the two stay equal
        first, _ = eng.step(first)
        second, _ = eng.step(second)
    _same(first, second)
    assert not np.array_equal(first.pose, saved.pose)


class _Blind:
    """An estimator that hands the one it wraps NaN for the true start poses."""

    def __init__(self, inner):
        self.inner = inner

    def __getattr__(self, name):
        return getattr(self.inner, name)

    def start(self, poses, seeds):
        return self.inner.start(np.full_like(poses, np.nan), seeds)


def test_global_localisation_never_starts_from_the_truth():
    def make():
        filter_ = amcl(min_particles=500, max_particles=3000, update_min_d=0.1).amcl
        return ParticleLocalizer(filter_, odometry(0.3), global_start=True)

    starts = [[1.0, 2.0, 0.0], [1.0, 2.05, 0.0]]
    seen = engine(make(), SUITE).run(starts, seeds=[5, 6])
    hidden = engine(_Blind(make()), SUITE).run(starts, seeds=[5, 6])
    # the truth of the start plays no part: a run that hides it is the same run
    np.testing.assert_array_equal(seen.estimated_pose, hidden.estimated_pose)
    np.testing.assert_array_equal(seen.true_pose, hidden.true_pose)
    np.testing.assert_array_equal(seen.status, hidden.status)
    # the first estimate is the filter's heaviest cluster of a spread over the room, flagged
    # not converged; it converges once the lidar has told where the robot is
    first_error = np.hypot(*(seen.estimated_pose[:, 0, :2] - np.array(starts)[:, :2]).T)
    assert np.all(first_error > 0.05)
    converged = seen.extras["loc_converged"]
    assert np.all(converged[:, 0] == 0) and np.all(converged[:, -1] == 1)
