"""AMCL: resampling, KLD bound, clusters, likelihoods, tracking, global localisation, kidnapping."""

import math

import numpy as np
import pytest

from amcl_trials import kidnapped_run, noisy_odometry, run_amcl, wander
from wheelbase.errors import ConfigError, InputError, MapError, PlanningError
from wheelbase.localization import (
    AMCL,
    GLOBAL_LOCALIZATION,
    OdometryMotion,
    kld_particles,
    low_variance_resample,
    odometry_delta,
)
from wheelbase.localization.likelihood import likelihood_field, scan_log_likelihood
from wheelbase.localization.particles import _bin_keys, _kld_bound, clusters
from wheelbase.planning import OccupancyGrid, load_map
from wheelbase.sensors import Lidar

BINS = (0.5, 0.5, math.radians(10))


def test_low_variance_resampling_is_proportional_to_the_weights():
    rng = np.random.default_rng(0)
    w = rng.random(50)
    w /= w.sum()
    idx = low_variance_resample(w, 1000, rng)
    counts = np.bincount(idx, minlength=50)
    # systematic resampling: each count is floor or ceil of n·w
    assert np.all(np.abs(counts - 1000 * w) < 1.0 + 1e-9)
    np.testing.assert_array_equal(low_variance_resample(np.full(7, 1 / 7), 7, rng), np.arange(7))


def test_kld_bound_grows_with_the_occupied_bins():
    rng = np.random.default_rng(1)
    one = np.tile([1.2, 3.4, 0.5], (1000, 1))
    assert kld_particles(one, np.full(1000, 1e-3), BINS, 0.05, 0.01, 100, 5000) == 100
    # 200 equally weighted, well separated bins: the expected bins of n draws are almost all
    # 200, so the answer is the bound for k ≈ 200: 1990·(1 − 2/1791 + √(2/1791)·2.33)³ ≈ 2,483
    spread = np.column_stack([np.arange(200) * 1.0 + 0.25, np.full(200, 0.25), np.zeros(200)])
    n = kld_particles(spread, np.full(200, 1 / 200), BINS, 0.05, 0.01, 10, 100000)
    expected_bins = 200 * (1 - (1 - 1 / 200) ** n)
    assert n == pytest.approx(float(_kld_bound(expected_bins, 0.05, 2.3263478740408408)), abs=1)
    assert 2470 < n < 2500
    assert kld_particles(spread, np.full(200, 1 / 200), BINS, 0.05, 0.01, 10, 2000) == 2000
    # more bins → more particles
    wide = np.column_stack(
        [rng.uniform(0, 50, 3000), rng.uniform(0, 50, 3000), rng.uniform(-3, 3, 3000)]
    )
    assert kld_particles(wide, np.full(3000, 1 / 3000), BINS, 0.05, 0.01, 10, 10**6) > n


def test_kld_bound_counts_the_bins_of_injected_random_poses():
    # Fox's sampling counts every bin the drawn particles fill: random poses spread over F bins
    # fill F·(1 − exp(−n·p/F)) of them, so an injection grows the set (augmented MCL).
    rng = np.random.default_rng(1)
    particles = rng.normal([1.0, 1.0, 0.0], [0.05, 0.05, 0.02], (3000, 3))
    weights = np.full(3000, 1.0 / 3000)
    base = kld_particles(particles, weights, BINS, 0.05, 0.01, 100, 100000)
    assert kld_particles(particles, weights, BINS, 0.05, 0.01, 100, 100000, 0.0, 5e4) == base
    grown = [kld_particles(particles, weights, BINS, 0.05, 0.01, 100, 100000, p, 5e4)
             for p in (0.01, 0.05, 0.2)]  # fmt: skip
    assert base < grown[0] < grown[1] < grown[2]
    # the fixed point: n is the bound for the bins that n draws are expected to fill
    n, p, F = grown[1], 0.05, 5e4
    _, counts = np.unique(_bin_keys(particles, BINS), axis=0, return_counts=True)
    w = counts / 3000
    expected = np.sum(1.0 - (1.0 - w * (1.0 - p)) ** n) + F * -math.expm1(-n * p / F)
    assert abs(_kld_bound(expected, 0.05, 2.3263478740408408) - n) <= 0.01 * n


def test_clusters_split_separate_groups_and_join_across_the_angle_cut():
    rng = np.random.default_rng(2)
    a = np.column_stack(
        [rng.normal(1.0, 0.05, 300), rng.normal(1.0, 0.05, 300), rng.normal(math.pi, 0.03, 300)]
    )
    a[:, 2] = np.arctan2(np.sin(a[:, 2]), np.cos(a[:, 2]))  # straddles ±π
    b = np.column_stack(
        [rng.normal(6.0, 0.05, 100), rng.normal(2.0, 0.05, 100), rng.normal(0.0, 0.03, 100)]
    )
    found = clusters(np.vstack([a, b]), np.full(400, 1 / 400), BINS)
    assert len(found) == 2
    assert found[0].weight == pytest.approx(0.75) and found[0].count == 300
    assert abs(abs(found[0].mean[2]) - math.pi) < 0.02
    np.testing.assert_allclose(found[1].mean[:2], [6.0, 2.0], atol=0.02)
    assert found[1].cov[0, 0] == pytest.approx(0.05**2, rel=0.3)


def test_odometry_motion_noise_has_the_nav2_variances():
    rng = np.random.default_rng(3)
    particles = np.zeros((20000, 3))
    delta = np.array([0.3, 1.0, -0.2])
    exact = OdometryMotion(0.0, 0.0, 0.0, 0.0).sample(particles, delta, rng)
    np.testing.assert_allclose(exact[0], [math.cos(0.3), math.sin(0.3), 0.1], atol=1e-12)
    motion = OdometryMotion(0.1, 0.02, 0.05, 0.01)
    moved = motion.sample(particles, delta, rng)
    trans = np.hypot(moved[:, 0], moved[:, 1])  # |δtrans + noise| (δtrans = 1 >> noise)
    expected = math.sqrt(0.05 * 1.0 + 0.01 * (0.09 + 0.04))
    assert trans.std() == pytest.approx(expected, rel=0.03)
    assert odometry_delta([0.0, 0.0, 0.0], [1.0, 0.0, 0.0]).tolist() == [0.0, 1.0, 0.0]


def test_likelihood_field_is_highest_at_the_true_pose():
    grid = load_map("warehouse")
    lidar = Lidar(beams=180, max_range=10.0)
    truth = np.array([6.2, 6.0, 1.2])
    scan = lidar.scan(grid, truth, noise=False)
    amcl = AMCL(grid=grid, lidar=lidar)
    offsets = np.array([[0, 0, 0], [0.2, 0, 0], [0, 0.3, 0], [0, 0, 0.1], [1.0, 1.0, 0.5]])
    idx = amcl._beam_index
    keep = scan[idx] < lidar.max_range
    for product in (False, True):
        log_p = scan_log_likelihood(
            amcl._field, grid, truth + offsets, np.zeros(3), scan[idx][keep],
            lidar.beam_angles[idx][keep], amcl._outside, product,
        )  # fmt: skip
        assert np.argmax(log_p) == 0 and np.all(np.diff(log_p[[0, 4]]) < 0)


def test_likelihood_field_is_the_distance_to_the_surface_the_same_on_every_side_of_a_wall():
    """One beam's p_z is z_hit·exp(−d²/2σ²) + z_rand/max_range with d the end point's distance
    to the wall's surface, outside or inside it, tabulated on cells 4 times finer than the
    map's: exact at their centres, within half a fine cell elsewhere, and the same for a wall
    below, above, left and right (the cell-centre look-up of Nav2 charged half a cell on two
    sides only, and d = 0 inside, which biased the closed-loop estimate)."""
    occupied = np.zeros((21, 21), bool)
    occupied[10, 10] = True  # one occupied square [1.0, 1.1] x [1.0, 1.1] m
    grid = OccupancyGrid.from_array(occupied, 0.1)
    field = likelihood_field(grid, 0.9, 0.1, 0.05, 2.0, 8.0)
    assert field.resolution == 0.025 and field.table.shape == (84, 84)
    beam = np.array([0.5]), np.array([0.0])  # one beam 0.5 m straight ahead

    def p_z(gap):
        """p_z of an end point ``gap`` outside (negative: inside) each face of the square."""
        sides = np.array([
            [1.05, 1.0 - gap - 0.5, math.pi / 2],  # end point below the square
            [1.05, 1.1 + gap + 0.5, -math.pi / 2],  # above
            [1.0 - gap - 0.5, 1.05, 0.0],  # left
            [1.1 + gap + 0.5, 1.05, math.pi],  # right
        ])  # fmt: skip
        log_p = scan_log_likelihood(field.log(), grid, sides, np.zeros(3), *beam, -10.0, True)
        return np.exp(log_p)

    def exact(d):
        return 0.9 * math.exp(-(d**2) / (2 * 0.05**2)) + 0.1 / 8.0

    for centre in (-0.0375, -0.0125, 0.0125, 0.0375, 0.2125):  # fine-cell centres
        np.testing.assert_allclose(p_z(centre), exact(abs(centre)), rtol=1e-12)
    for gap in (-0.03, -0.013, 0.001, 0.013, 0.04, 0.19):  # off the fine-cell edges
        sides = p_z(gap)
        assert np.all(sides == sides[0])
        d = math.sqrt(-2 * 0.05**2 * math.log((sides[0] - 0.1 / 8.0) / 0.9))
        assert abs(d - abs(gap)) <= 0.0125 + 1e-12


def tracking_setup(seed):
    grid = load_map("warehouse")
    lidar = Lidar(beams=180, max_range=10.0, range_std=0.02)
    rng = np.random.default_rng(seed)
    truth = wander(grid, 12.0, rng, start=np.array([3.0, 2.0, 0.0]))
    odometry = noisy_odometry(truth, rng)
    return grid, lidar, truth, odometry, rng


@pytest.mark.parametrize("sensor_model", ["likelihood_field", "beam"])
def test_tracking_from_a_known_pose_stays_within_ten_centimetres(sensor_model):
    grid, lidar, truth, odometry, rng = tracking_setup(4)
    amcl = AMCL(grid=grid, lidar=lidar, sensor_model=sensor_model, max_particles=1000,
                min_particles=200)  # fmt: skip
    state = amcl.initial_state(truth[0], np.diag([0.1, 0.1, 0.05]) ** 2, odometry[0], rng)
    run = run_amcl(amcl, lidar, truth, odometry, state, rng)
    assert run.error.size > 40
    assert run.error.max() < 0.15 and np.sqrt(np.mean(run.error**2)) < 0.08
    drift = np.hypot(*(odometry[-1, :2] - odometry[0, :2] - (truth[-1, :2] - truth[0, :2])))
    assert drift > 0.1  # the odometry alone would have drifted
    assert run.particles[-1] < 1000  # KLD shrank the set once it had converged


GLOBAL = {**GLOBAL_LOCALIZATION, "max_particles": 5000}  # the tests' routes need no more


def test_global_localisation_on_the_maze_converges_within_ten_metres():
    # The 20-seed figure is a benchmark key (benchmarks/sensors.py, global_localization); two
    # routes here.
    grid = load_map("maze")
    lidar = Lidar(beams=360, max_range=30.0, range_std=0.02)
    amcl = AMCL(grid=grid, lidar=lidar, **GLOBAL)
    for seed in (0, 6):
        rng = np.random.default_rng(seed)
        truth = wander(grid, 10.0, rng)
        odometry = noisy_odometry(truth, rng)
        state = amcl.global_state(odometry[0], rng)
        assert len(amcl.estimate(state).clusters) > 100  # spread over the free space
        run = run_amcl(amcl, lidar, truth, odometry, state, rng)
        assert run.converged_after(0.2) <= 10.0, seed
        assert run.heading_error[-1] < math.radians(5)


def test_kidnapped_robot_recovers():
    # Carried into a corridor with a stub, every route recovers (10 of 10 in the benchmark, 20
    # of 20 on seeds 10-29); before the fourth corridor had its stub, 3 of 10 settled on its
    # half-turn twin.
    grid = load_map("maze")
    lidar = Lidar(beams=360, max_range=30.0, range_std=0.02)
    amcl = AMCL(grid=grid, lidar=lidar, **GLOBAL)
    recovered_s = []
    for seed in (0, 1, 2):
        tracked, kidnapped = kidnapped_run(amcl, lidar, seed)
        assert tracked.error[-1] < 0.1
        assert kidnapped.error[0] > 5.0
        assert kidnapped.injected.sum() > 0  # augmented MCL noticed and brought in fresh guesses
        assert kidnapped.particles.max() > 2 * tracked.particles[-1]  # the injection grew the set
        recovered_s.append(kidnapped.converged_at_tick(0.2) * 0.1)  # ticks of 0.1 s: 0.5 m/s
    assert max(recovered_s) <= 30.0, recovered_s


def test_an_ambiguous_map_gives_several_clusters_not_a_confident_wrong_pose():
    # Six identical racks: from the middle of an aisle with a 3 m lidar every aisle looks alike.
    grid = load_map("warehouse")
    lidar = Lidar(beams=360, max_range=3.0, range_std=0.02)
    amcl = AMCL(grid=grid, lidar=lidar, **GLOBAL)
    rng = np.random.default_rng(7)
    truth = np.array([[9.8, 8.0 + 0.05 * k, math.pi / 2] for k in range(41)])
    odometry = truth - truth[0]
    state = amcl.global_state(odometry[0], rng)
    run = run_amcl(amcl, lidar, truth, odometry, state, rng)
    estimate = amcl.estimate(run.state)
    assert estimate.ambiguous
    # no confident pose: the weight is split over several clusters
    assert estimate.clusters[0].weight < 0.5
    assert sum(c.weight >= 0.05 for c in estimate.clusters) >= 2


def test_update_rules_and_bad_input():
    grid = load_map("maze")
    lidar = Lidar(beams=36, max_range=10.0)
    amcl = AMCL(grid=grid, lidar=lidar, max_particles=300, min_particles=100)
    state = amcl.initial_state([2.0, 2.0, 0.0], np.eye(3) * 1e-4, (0, 0, 0), 0)
    scan = lidar.scan(grid, [2.0, 2.0, 0.0], noise=False)
    same, info = amcl.update(state, [0.1, 0.0, 0.0], 0, scan=scan)
    assert same is state and not info.updated  # 0.1 m < update_min_d
    scan[:5] = np.nan
    scan[5] = -1.0
    _, info = amcl.update(state, [0.3, 0.0, 0.0], 0, scan=scan)
    # skipped: the 6 bad readings and the max-range ones (no return: the likelihood field
    # skips them); with every beam chosen, used + skipped = 36
    assert info.updated and info.beams_skipped == 6 + np.sum(scan[6:] >= lidar.max_range)
    assert info.beams_used + info.beams_skipped == 36 and info.beams_used > 0
    with pytest.raises(ConfigError, match="max_particles"):
        AMCL(grid=grid, max_particles=0)
    with pytest.raises(ConfigError, match="min_particles"):
        AMCL(grid=grid, min_particles=10, max_particles=5)
    with pytest.raises(ConfigError, match="sigma_hit"):
        AMCL(grid=grid, sigma_hit=-1.0)
    with pytest.raises(ConfigError, match="sensor_model"):
        AMCL(grid=grid, lidar=lidar, sensor_model="sonar")
    with pytest.raises(ConfigError, match="lidar needs a grid"):
        AMCL(lidar=lidar)
    with pytest.raises(MapError, match="no free cell"):
        AMCL(grid=OccupancyGrid.from_array(np.ones((4, 4), bool), 1.0)).global_state()
    with pytest.raises(InputError, match="scan must have 36"):
        amcl.update(state, [1.0, 0, 0], 0, scan=np.ones(10))
    marks = AMCL(landmarks=[[1.0, 0.0]], max_particles=100, min_particles=100)
    s0 = marks.initial_state([0, 0, 0], np.eye(3) * 1e-3, (0, 0, 0), 0)
    _, info = marks.update(
        s0,
        [0, 0, 0],
        0,
        landmark_ids=[0, 7, 0],
        landmark_z=[[1.0, 0.0], [1.0, 0.0], [np.nan, 0.0]],
        force=True,
    )
    assert info.landmarks_used == 1 and info.landmarks_skipped == 2


def test_wander_stops_with_an_error_where_every_heading_is_blocked():
    import signal

    def too_long(signum, frame):
        raise TimeoutError("wander still turning after 20 s: it loops forever")

    room = np.ones((19, 19), dtype=bool)
    room[2:-2, 2:-2] = False  # a 1.5 m walled room of 0.1 m cells
    grid = OccupancyGrid.from_array(room, 0.1)
    previous = signal.signal(signal.SIGALRM, too_long)
    signal.alarm(20)
    try:
        with pytest.raises(PlanningError, match=r"every heading .* blocked within clearance"):
            wander(grid, 5.0, 0, start=np.array([0.95, 0.95, 0.0]))
        with pytest.raises(PlanningError, match=r"every heading .* blocked within clearance"):
            wander(grid, 5.0, 0)  # a start drawn in the middle, 0.75 m from the walls
        closet = OccupancyGrid.from_array(np.pad(np.zeros((10, 10), bool), 2, constant_values=True),
                                          0.1)  # fmt: skip
        with pytest.raises(MapError, match=r"more than clearance = 0\.6 m"):
            wander(closet, 5.0, 0)  # 1 m wide: no cell 0.6 m from the walls to start from
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, previous)
    # where there is room, it wanders the distance asked for
    free = np.zeros((60, 60), dtype=bool)
    free[[0, -1], :] = free[:, [0, -1]] = True
    truth = wander(OccupancyGrid.from_array(free, 0.1), 3.0, 1, start=np.array([3.0, 3.0, 0.0]))
    assert np.sum(np.hypot(*np.diff(truth[:, :2], axis=0).T)) >= 3.0 - 1e-9


def corridor() -> OccupancyGrid:
    """A 10 m × 2 m corridor (0.1 m cells) closed at both ends."""
    cells = np.zeros((22, 102), bool)
    cells[[0, -1], :] = cells[:, [0, -1]] = True
    return OccupancyGrid.from_array(cells, 0.1, origin=(-0.1, -0.1))


def weigh(amcl, particles, scan):
    """Weights of ``particles`` after one update with ``scan`` (no motion, no resampling)."""
    from wheelbase.localization import AMCLState

    n = particles.shape[0]
    state = AMCLState(particles, np.full(n, 1.0 / n), np.zeros(3))
    new, info = amcl.update(state, np.zeros(3), 0, scan=scan, force=True)
    return new.weights, info


def test_the_beam_model_scores_max_range_readings_with_z_max():
    # Beam 0 looks down the corridor (no return within 3 m: it reads 3 m), beam 1 at the side
    # wall 1 m away. A particle near the end wall expects a return on beam 0: the missed
    # return must count against it (Nav2's z_max), not be thrown away.
    grid = corridor()
    lidar = Lidar(beams=4, fov=2 * math.pi, max_range=3.0)  # 0°, 90°, 180°, 270°
    truth = np.array([5.0, 1.0, 0.0])
    scan = lidar.scan(grid, truth, noise=False)
    assert scan[0] == 3.0 and scan[2] == 3.0 and abs(scan[1] - 1.0) < 0.06
    near_end = np.array([8.8, 1.0, 0.0])  # beam 0 would hit the end wall 1.2 m ahead
    amcl = AMCL(grid=grid, lidar=lidar, sensor_model="beam", motion=OdometryMotion(0, 0, 0, 0),
                resample_interval=1000, min_particles=2, max_particles=2)  # fmt: skip
    weights, info = weigh(amcl, np.array([truth, near_end]), scan)
    assert info.beams_used == 4 and info.beams_skipped == 0
    assert weights[0] > 0.9  # the missed return counts against the particle near the end
    # z_max is the probability of the missed return: the log-ratio of the two particles is
    # that of z_hit + z_max (nothing to hit) against z_max alone, on beam 0
    total = amcl.z_hit + amcl.z_short + amcl.z_max + amcl.z_rand
    expected = math.log((amcl.z_hit + amcl.z_max) / total) - math.log(amcl.z_max / total)
    assert math.log(weights[0] / weights[1]) == pytest.approx(expected, rel=1e-9)
    # the likelihood field skips the max-range readings, as Nav2's does, and says so
    field = AMCL(grid=grid, lidar=lidar, motion=OdometryMotion(0, 0, 0, 0),
                 resample_interval=1000, min_particles=2, max_particles=2)  # fmt: skip
    _, info = weigh(field, np.array([truth, near_end]), scan)
    assert info.beams_used == 2 and info.beams_skipped == 2


def test_beams_skipped_counts_only_the_chosen_beams_left_unused():
    grid = corridor()
    lidar = Lidar(beams=360, max_range=3.0)
    amcl = AMCL(grid=grid, lidar=lidar, max_beams=60, motion=OdometryMotion(0, 0, 0, 0),
                resample_interval=1000, min_particles=2, max_particles=2)  # fmt: skip
    truth = np.array([5.0, 1.0, 0.0])
    scan = lidar.scan(grid, truth, noise=False)
    chosen = np.unique(np.round(np.linspace(0, 359, 60)).astype(int))
    others = np.setdiff1d(np.arange(360), chosen)
    scan[others[:100]] = np.nan  # beams the filter never looks at
    scan[chosen[:3]] = np.nan  # three it chose
    _, info = weigh(amcl, np.array([truth, truth]), scan)
    unused = np.sum(~(scan[chosen] < 3.0))  # NaN or max range: no use to the likelihood field
    assert info.beams_skipped == unused >= 3
    assert info.beams_used + info.beams_skipped == chosen.size == 60
