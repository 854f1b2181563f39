"""The obstacle tracker on hand-made scans: detections of discs in closed form, a disc at
constant velocity, two discs crossing (one hidden behind the other), clutter, purity, scoring
against the truth and bad keys."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from perception_scenes import box_ranges, crossing_discs, disc_ranges, room
from wheelbase.errors import ConfigError, InputError
from wheelbase.perception import (
    TrackErrors,
    TrackerSpec,
    TrackerState,
    Tracks,
    detect,
    track_errors,
    update_tracker,
)
from wheelbase.planning import OccupancyGrid
from wheelbase.world.obstacles import box_polygon

BEAMS = -math.pi + 2.0 * math.pi * np.arange(360) / 360
OPEN = OccupancyGrid(np.zeros((300, 300), bool), 0.05, (-7.5, -7.5))  # nothing mapped


def noisy(ranges: np.ndarray, rng: np.random.Generator, std: float = 0.01) -> np.ndarray:
    """Gaussian range noise on the returns (no-return beams stay at the maximum)."""
    return np.where(ranges < 8.0, ranges + rng.normal(0.0, std, ranges.shape), ranges)


@pytest.mark.parametrize("distance", [0.6, 1.0, 2.0, 4.0, 7.0])
@pytest.mark.parametrize("radius", [0.15, 0.3, 0.5])
def test_a_disc_is_detected_at_its_centre_with_its_radius(distance, radius):
    beams = -math.pi + 2.0 * math.pi * np.arange(720) / 720
    spacing = distance * 2.0 * math.pi / 720  # between beams at that range
    for bearing in (0.0, 0.3, 1.1, -2.5):
        centre = distance * np.array([math.cos(bearing), math.sin(bearing)])
        ranges = disc_ranges(None, np.zeros((1, 3)), beams, 8.0, [[*centre, radius]])[0]
        found = detect(TrackerSpec(), (0.0, 0.0, 0.0), beams, ranges, 8.0, OPEN)
        assert len(found) == 1
        assert math.dist(found.position[0], centre) <= max(spacing, 0.01)
        assert abs(found.radius[0] - radius) <= max(spacing, 0.01)
        assert found.points[0] == np.sum(ranges < 8.0)
        assert not found.occluded[0]


@pytest.mark.parametrize("size", [(0.6, 0.6), (0.8, 0.4), (0.5, 0.7)])
@pytest.mark.parametrize("distance", [0.8, 1.5, 3.0])
def test_a_box_is_detected_at_its_centre_from_any_side(size, distance):
    """A box is no disc: its fitted disc centre moves with the viewpoint. Read as a rectangle
    (L-shape fit), it is found at its centre from every side within 5 cm, plus half the
    difference of its sides when only one face shows (the hidden depth is taken square), and
    its radius is half its longer side (with one face, half that face)."""
    rng = np.random.default_rng(3)
    length, width = size
    for yaw in (0.0, 0.4, 1.0):
        for bearing in (0.2, 1.5, -2.4):
            centre = distance * np.array([math.cos(bearing), math.sin(bearing)])
            corners = box_polygon(*centre, length, width, yaw)
            truth = box_ranges(np.zeros(3), BEAMS, 8.0, corners)
            found = detect(TrackerSpec(), (0.0, 0.0, 0.0), BEAMS, noisy(truth, rng), 8.0, OPEN)
            assert len(found) == 1
            # the faces that show: those that at least 5 beams meet first (fewer, at a grazing
            # angle, lie farther apart than the clusters join)
            faces = sum(
                np.count_nonzero((truth < 8.0) & (box_ranges(np.zeros(3), BEAMS, 8.0,
                                                             corners[[k, (k + 1) % 4]]) == truth))
                >= 5
                for k in range(4)
            )  # fmt: skip
            slack = 0.05 + (0.5 * abs(length - width) if faces < 2 else 0.0)
            assert math.dist(found.position[0], centre) <= slack
            seen = max(size) if faces >= 2 else min(size)
            assert 0.5 * seen - 0.05 <= found.radius[0] <= 0.5 * max(size) + 0.05


def test_a_box_passed_by_a_moving_sensor_keeps_still():
    """A robot drives at 1 m/s past a box 0.5 m to its side: the box's track stays where the
    box is and nearly at rest. Read as a disc, its centre slid with the viewpoint (largest
    speed 0.63 m/s, mean 0.15 m/s, 0.16 m off); as a rectangle 0.50 m/s (a scan or two
    where the face fits a disc nearly as well), 0.08 m/s, 0.07 m."""
    rng = np.random.default_rng(7)
    spec = TrackerSpec()
    corners = box_polygon(4.0, 0.8, 0.6, 0.6, 0.0)
    state = TrackerState.initial(spec)
    speeds, errors = [], []
    for k in range(60):
        t = 0.1 * k
        pose = np.array([0.5 + t, 0.0, 0.0])
        ranges = noisy(box_ranges(pose, BEAMS, 8.0, corners), rng, 0.02)
        state = update_tracker(spec, state, t, pose, BEAMS, ranges, 8.0, OPEN)
        tracks = state.tracks(confirmed_only=True)
        if len(tracks):
            assert len(tracks) == 1
            speeds.append(float(np.hypot(*tracks.velocity[0])))
            errors.append(math.dist(tracks.position[0], (4.0, 0.8)))
    assert len(speeds) >= 55
    assert max(speeds) < 0.55
    assert np.mean(speeds) < 0.1
    assert max(errors) < 0.1


def test_a_disc_partly_hidden_is_flagged_occluded():
    front, back = [2.0, 0.0, 0.3], [4.0, 0.45, 0.3]  # the front disc hides back's right side
    ranges = disc_ranges(None, np.zeros((1, 3)), BEAMS, 8.0, [front, back])[0]
    found = detect(TrackerSpec(), (0.0, 0.0, 0.0), BEAMS, ranges, 8.0, OPEN)
    order = np.argsort(found.position[:, 0])
    assert len(found) == 2 and found.occluded[order].tolist() == [False, True]
    hidden, seen = found.covariance[order[1]], found.covariance[order[0]]
    assert np.all(np.linalg.eigvalsh(hidden - seen) > 0.9 * found.radius[order[1]] ** 2 - 0.01)


def test_the_bare_map_explains_every_return():
    grid = room(10.0, 8.0, 0.05)
    grid = OccupancyGrid(grid.occupied | (np.indices(grid.shape)[1] == 100), 0.05)  # a wall
    rng = np.random.default_rng(4)
    for pose, disc in (([2.0, 2.0, 0.0], [3.0, 5.0, 0.3]), ([7.5, 6.0, 2.0], [6.5, 4.0, 0.2]),
                       ([4.2, 1.1, -1.0], [2.0, 6.5, 0.4])):  # fmt: skip
        ranges = noisy(disc_ranges(grid, np.array([pose]), BEAMS, 8.0, np.empty((0, 3)))[0], rng)
        assert len(detect(TrackerSpec(), pose, BEAMS, ranges, 8.0, grid)) == 0
        with_disc = disc_ranges(grid, np.array([pose]), BEAMS, 8.0, [disc])[0]
        found = detect(TrackerSpec(), pose, BEAMS, with_disc, 8.0, grid)
        assert len(found) == 1 and math.dist(found.position[0], disc[:2]) < 0.05


def test_a_disc_at_constant_velocity_is_tracked():
    grid = room(12.0, 10.0, 0.05)
    spec = TrackerSpec()
    state = TrackerState.initial(spec)
    rng = np.random.default_rng(0)
    sensor = np.array([8.0, 6.0, 0.4])
    velocity = np.array([0.8, 0.5])
    velocity_errors = []
    for k in range(60):  # 6 s at 10 Hz; the disc comes from 7.2 m to 1.6 m of the sensor
        t = 0.1 * k
        centre = np.array([2.0, 2.0]) + t * velocity
        ranges = noisy(disc_ranges(grid, sensor[None], BEAMS, 8.0, [[*centre, 0.3]])[0], rng)
        state = update_tracker(spec, state, t, sensor, BEAMS, ranges, 8.0, grid)
        tracks = state.tracks()
        assert len(tracks) == 1 and tracks.ids[0] == 0  # one track all along, never lost
        assert tracks.confirmed[0] == (k >= spec.hits_to_confirm - 1)
        if t >= 2.0:
            assert math.dist(tracks.position[0], centre) < 0.05
            assert abs(tracks.radius[0] - 0.3) < 0.03
            velocity_errors.append(tracks.velocity[0] - velocity)
    errors = np.array(velocity_errors)
    assert np.max(np.hypot(*errors.T)) < 0.25  # m/s, at every scan after 2 s
    assert math.sqrt(np.mean(np.sum(errors**2, 1))) < 0.12  # m/s, RMSE after 2 s
    # the filter knows how sure it is: the velocity errors are within 3 σ of its covariance
    sigma = np.sqrt(np.diag(state.tracks().covariance[0])[2:])
    assert np.all(np.abs(errors[-1]) < 3.0 * sigma)


def test_two_crossing_discs_keep_their_ids():
    spec = TrackerSpec()
    state = TrackerState.initial(spec)
    rng = np.random.default_rng(1)
    owner: dict[int, int] = {}  # track id -> disc (A = 0, B = 1)
    for k in range(41):  # 4 s: B passes behind A around t = 2 s (hidden ~0.3 s)
        t = 0.1 * k
        discs = crossing_discs(t)
        ranges = noisy(disc_ranges(None, np.zeros((1, 3)), BEAMS, 8.0, discs[:, :3])[0], rng)
        state = update_tracker(spec, state, t, (0.0, 0.0, 0.0), BEAMS, ranges, 8.0, OPEN)
        tracks = state.tracks(confirmed_only=True)
        for track_id, position in zip(tracks.ids, tracks.position, strict=True):
            disc = int(np.argmin(np.hypot(*(discs[:, :2] - position).T)))
            assert math.dist(discs[disc, :2], position) < 0.3
            assert owner.setdefault(int(track_id), disc) == disc, f"id {track_id} switched"
    assert sorted(owner.values()) == [0, 1]  # one id each, all along
    final = state.tracks(confirmed_only=True)
    assert np.allclose(final.velocity, crossing_discs(4.0)[:, 3:], atol=0.25)


def test_clutter_is_not_confirmed():
    grid = room(10.0, 10.0, 0.05)
    spec = TrackerSpec()
    state = TrackerState.initial(spec)
    rng = np.random.default_rng(2)
    sensor = np.array([5.0, 5.0, 0.0])
    clean = disc_ranges(grid, sensor[None], BEAMS, 8.0, np.empty((0, 3)))[0]
    tentative = 0
    for k in range(200):  # 20 s; 5 % of the beams read a random range each scan
        ranges = noisy(clean, rng)
        random = rng.random(360) < 0.05
        ranges[random] = rng.uniform(0.1, 8.0, random.sum())
        state = update_tracker(spec, state, 0.1 * k, sensor, BEAMS, ranges, 8.0, grid)
        assert not state.confirmed.any(), k
        tentative += int((state.ids >= 0).sum())
    assert tentative > 0  # clutter did start tracks: they died unconfirmed


_SPEC = TrackerSpec(max_tracks=8)
_READING = st.one_of(st.floats(0.0, 9.0), st.just(np.nan), st.just(np.inf))


@settings(max_examples=30, deadline=None)
@given(st.lists(_READING, min_size=24, max_size=24), st.floats(0.0, 1.0))
def test_update_is_pure(readings, dt):
    angles = np.linspace(-math.pi, math.pi, 24, endpoint=False)
    pose = np.array([0.5, -0.2, 0.3])
    ranges = disc_ranges(None, pose[None], angles, 8.0, [[2.0, 0.0, 0.4], [-1.0, 2.0, 0.3]])[0]
    state = update_tracker(_SPEC, TrackerState.initial(_SPEC), 0.0, pose, angles, ranges, 8.0,
                           OPEN)  # fmt: skip
    state = update_tracker(_SPEC, state, 0.1, pose, angles, ranges, 8.0, OPEN)
    scan = np.array(readings)
    before = {name: np.copy(getattr(state, name)) for name in ("ids", "mean", "covariance")}
    first = update_tracker(_SPEC, state, 0.1 + dt, pose, angles, scan, 8.0, OPEN)
    second = update_tracker(_SPEC, state, 0.1 + dt, pose, angles, scan, 8.0, OPEN)
    for name, value in before.items():
        assert np.array_equal(getattr(state, name), value)
        assert np.array_equal(getattr(first, name), getattr(second, name))
    assert np.array_equal(scan, np.array(readings), equal_nan=True)
    assert np.all(np.linalg.eigvalsh(first.covariance[first.ids >= 0]) > 0.0)


def test_track_errors_pair_tracks_with_the_truth():
    tracks = Tracks(
        ids=np.array([3, 5, 8, 9]),
        position=np.array([[0.1, 0.0], [5.0, 5.0], [2.0, 2.3], [9.0, 9.0]]),
        velocity=np.array([[1.0, 0.0], [0.0, 0.0], [0.0, 1.0], [0.0, 0.0]]),
        covariance=np.tile(np.eye(4), (4, 1, 1)),
        radius=np.full(4, 0.3),
        confirmed=np.array([True, True, True, False]),
    )
    truth = np.array([[2.0, 2.0], [0.0, 0.0], [-4.0, 0.0]])
    speed = np.array([[0.0, 0.5], [1.0, 0.2], [0.0, 0.0]])
    errors = track_errors(tracks, truth, speed, gate=1.0)
    # track 3 ↔ truth 1 (0.1 m), track 8 ↔ truth 0 (0.3 m); track 5 false; truth 2 missed
    assert (errors.matches, errors.false_tracks, errors.missed) == (2, 1, 1)
    assert errors.position_rmse_m == pytest.approx(math.sqrt((0.01 + 0.09) / 2))
    assert errors.velocity_rmse_m_s == pytest.approx(math.sqrt((0.04 + 0.25) / 2))
    both = errors + track_errors(Tracks.empty(), truth, speed)
    assert (both.matches, both.missed) == (2, 4)
    assert both.position_rmse_m == errors.position_rmse_m
    assert math.isnan(TrackErrors().position_rmse_m)


@pytest.mark.parametrize(
    ("values", "match"),
    [
        ({"gate_probability": 1.0}, r"tracker\.gate_probability must be in \(0, 1\)"),
        ({"hits_to_confirm": 0}, r"tracker\.hits_to_confirm must be an integer >= 1"),
        ({"max_tracks": 10**6}, r"tracker\.max_tracks must be an integer in \[1, 10000\]"),
        ({"process_noise": -1.0}, r"tracker\.process_noise must be > 0 m²/s³"),
        ({"map_tolerance": "far"}, r"tracker\.map_tolerance must be a real number"),
        ({"min_points": 2.5}, r"tracker\.min_points must be an integer >= 1"),
        ({"clusterdistance": 0.3}, r"unknown key tracker\.clusterdistance; allowed: map_tol"),
    ],
)
def test_bad_tracker_keys_name_the_key(values, match):
    with pytest.raises(ConfigError, match=match):
        TrackerSpec.from_mapping(values)


def test_bad_tracker_inputs_are_clear_errors():
    spec = TrackerSpec()
    state = TrackerState.initial(spec, time=1.0)
    args = ((0.0, 0.0, 0.0), BEAMS, np.full(360, 8.0), 8.0, OPEN)
    with pytest.raises(InputError, match=r"time must not go back: 0\.5 s after 1 s"):
        update_tracker(spec, state, 0.5, *args)
    with pytest.raises(InputError, match=r"ranges must have one reading per beam, shape \(360,"):
        update_tracker(spec, state, 2.0, args[0], BEAMS, np.ones(3), 8.0, OPEN)
    with pytest.raises(InputError, match=r"state has 64 track slots, spec\.max_tracks = 8"):
        update_tracker(TrackerSpec(max_tracks=8), state, 2.0, *args)
    with pytest.raises(InputError, match="ranges must be >= 0 m"):
        update_tracker(spec, state, 2.0, args[0], BEAMS, -np.ones(360), 8.0, OPEN)
    assert TrackerSpec.from_mapping(None) == TrackerSpec()
    assert TrackerSpec().gate == pytest.approx(9.2103404)  # χ²(2) at 0.99
