"""Lidar SLAM on the first scans of the Intel log (no odometry) and on bad logs."""

import math

import numpy as np
import pytest

from shared_data import DATA, absent
from wheelbase.datasets.carmen import read_carmen
from wheelbase.datasets.scans import ScanLog
from wheelbase.errors import DataError
from wheelbase.mapping.evaluation import relation_pairs, relative_errors
from wheelbase.mapping.lidar_slam import LidarSlam, _fuse

INTEL = DATA / "carmen" / "intel-corrected.log.gz"
needs_intel = pytest.mark.skipif(not INTEL.is_file(), reason=absent(INTEL))


@needs_intel
def test_the_first_seventy_scans_of_intel():
    log = read_carmen(INTEL).subset(slice(12, 82))  # after the turn on the spot at the start
    result = LidarSlam().run(log)
    local, _ = relation_pairs(log.reference, log.t)
    et, er = relative_errors(result.poses, log.reference, local)
    assert np.median(et) < 0.04 and np.median(er) < math.radians(1.0)
    assert result.stats["failed_matches"] == 0
    assert result.graph.n_vertices == result.keyframes.size
    # the rendered map holds the walls: occupied cells next to where the reference says
    grid = LidarSlam().render(log, result.poses).to_grid()
    assert (grid.occupied & ~grid.unknown).sum() > 500


def test_bad_logs_are_refused():
    angles = np.linspace(-1, 1, 20)
    empty = ScanLog(np.zeros(0), np.zeros((0, 20)), angles, 10.0, source="empty.log")
    with pytest.raises(DataError, match="no scan"):
        LidarSlam().run(empty)
    blind = ScanLog(np.arange(3.0), np.full((3, 20), np.nan), angles, 10.0, source="b.log")
    with pytest.raises(DataError, match="no scan has 10 returns"):
        LidarSlam().run(blind)


@needs_intel
@pytest.mark.parametrize("use_odometry", [False, True])
def test_a_session_fed_in_batches_equals_the_batch_run(use_odometry):
    log = read_carmen(INTEL).subset(slice(12, 72))
    slam = LidarSlam(use_odometry=use_odometry)
    batch = slam.run(log)
    session = slam.session(log.angles, log.max_range, mount=log.mount)
    for a, b in [(0, 1), (1, 25), (25, 26), (26, 60)]:
        session.add(log.ranges[a:b], log.odometry[a:b], log.t[a:b])
        partial = session.result()
        assert partial.poses.shape == (b, 3)
    assert np.array_equal(partial.poses, batch.poses)
    assert np.array_equal(partial.graph.poses, batch.graph.poses)
    assert partial.stats == batch.stats and np.array_equal(partial.keyframes, batch.keyframes)
    assert partial.duration_s == pytest.approx(batch.duration_s)
    if use_odometry:
        with pytest.raises(DataError, match="odometry with every batch or none"):
            session.add(log.ranges[:1])


def test_an_empty_session_is_refused():
    session = LidarSlam().session(np.linspace(-1, 1, 20), 10.0, source="s")
    with pytest.raises(DataError, match="no scan"):
        session.result()
    session.add(np.full((2, 20), np.nan))
    with pytest.raises(DataError, match="no scan has 10 returns"):
        session.result()


def _drifted_loop():
    """Keyframes around a 10 m × 4 m loop driven twice; the odometry edges (σ 5 cm, as the
    loop edges) hide a 2 m slide along the first long side (two scans matched a metre short
    in a corridor); four true closures join the start of the second lap to the first."""
    from wheelbase.geometry import compose, relative_pose

    side = [(1.0, 0.0, 0.0)] * 10 + [(0.0, 0.0, math.pi / 2)] + [(1.0, 0.0, 0.0)] * 4
    steps = np.array([*side, (0.0, 0.0, math.pi / 2)] * 4, float)[:-1]
    truth = [np.zeros(3)]
    for s in steps:
        truth.append(compose(truth[-1], s))
    truth = np.array(truth)
    odometry = relative_pose(truth[:-1], truth[1:])
    odometry[3:5, 0] -= 1.0  # two scans that matched a metre short in a corridor
    chain = [np.zeros(3)]
    for z in odometry:
        chain.append(compose(chain[-1], z))
    n_lap = len(truth) // 2
    edges = [(i, i + 1) for i in range(len(truth) - 1)]
    loops = [(i, i + n_lap) for i in (0, 1, 2, 3)]
    meas = list(odometry) + [relative_pose(truth[a], truth[b]) for a, b in loops]
    info = [np.diag([400, 400, 3300])] * len(odometry) + [np.diag([400, 400, 3300])] * len(loops)
    flags = [False] * len(odometry) + [True] * len(loops)
    return truth, np.array(chain), edges + loops, meas, info, flags, loops


def test_true_closures_survive_a_slide_that_the_robust_kernel_alone_would_not_forgive():
    from wheelbase.datasets.g2o import PoseGraph
    from wheelbase.geometry import relative_pose
    from wheelbase.mapping.posegraph import optimize_pose_graph

    truth, chain, edges, meas, info, flags, loops = _drifted_loop()
    graph = PoseGraph(np.arange(len(chain)), chain, np.array(edges), np.array(meas),
                      np.array(info))  # fmt: skip
    # dynamic covariance scaling alone from the slid estimate: the closures lose
    alone = optimize_pose_graph(graph, robust="dcs", robust_edges=np.array(flags),
                                max_iterations=20, tolerance=1e-6)  # fmt: skip
    a, b = np.array(loops).T
    resid = relative_pose(
        relative_pose(alone.poses[a], alone.poses[b]), np.array(meas)[-len(loops) :]
    )
    assert np.hypot(resid[:, 0], resid[:, 1]).max() > 1.0
    poses = list(chain)
    LidarSlam(two_stage=True)._optimize(poses, edges, meas, info, flags)
    poses = np.array(poses)
    resid = relative_pose(relative_pose(poses[a], poses[b]), np.array(meas)[-len(loops) :])
    assert np.hypot(resid[:, 0], resid[:, 1]).max() < 0.1
    # the second lap lies on the first, as in the truth
    err = relative_pose(relative_pose(truth[a], truth[b]), relative_pose(poses[a], poses[b]))
    assert np.hypot(err[:, 0], err[:, 1]).max() < 0.1


ACES = DATA / "carmen" / "aces-corrected.log.gz"


def _frontend_steps(log):
    """The front end's errors (x, y, θ) between consecutive scans against the log's
    reference poses, and the result (loop closures off)."""
    from wheelbase.geometry import relative_pose

    result = LidarSlam.without_odometry(loop_every=10**9).run(log)  # the front end alone
    ref, est = log.reference, result.frontend_poses
    return relative_pose(relative_pose(ref[:-1], ref[1:]), relative_pose(est[:-1], est[1:])), result


@pytest.mark.skipif(not ACES.is_file(), reason=absent(ACES))
def test_the_front_end_does_not_slide_along_the_first_corridor_of_aces():
    log = read_carmen(ACES).subset(slice(0, 45))
    err, _ = _frontend_steps(log)
    # with a 12-keyframe submap scans 25 and 26 matched 1.0 m and 1.1 m short
    assert np.hypot(err[:, 0], err[:, 1]).max() < 0.3


@needs_intel
def test_identical_scans_along_a_corridor_are_not_matched_in_place():
    log = read_carmen(INTEL).subset(slice(95, 125))
    # scans 108, 109 and 110 of the log: 1 m apart along a corridor, their ranges equal to 1-4 cm
    # (median) as the side walls look the same from everywhere; from the returns alone the
    # next scan matched 1.0-1.3 m short, on the samples of the last keyframe's walls
    err, _ = _frontend_steps(log)
    along = np.hypot(err[13:, 0], err[13:, 1])  # from scan 108 on: in the corridor
    assert along.max() < 0.15
    assert np.median(along) < 0.04


@needs_intel
def test_a_submap_bent_by_drift_does_not_break_the_chain_where_the_last_keyframe_disagrees():
    # scans 793-794 of the log: the 30-keyframe submap, its oldest keyframes drifted, ranked a
    # pose 0.45 m across the true one first (7 % of the scan within 5 cm of scan 793 there)
    log = read_carmen(INTEL).subset(slice(740, 830))
    err, result = _frontend_steps(log)
    steps = np.hypot(err[:, 0], err[:, 1])
    assert steps.max() < 0.2 and steps.mean() < 0.035  # without the check: 0.45 m, 0.046 m
    assert result.stats["last_checks"] >= 1


@pytest.mark.skipif(not ACES.is_file(), reason=absent(ACES))
def test_the_front_end_holds_its_steps_where_aces_waits_in_a_corridor():
    from wheelbase.geometry import relative_pose

    # scans 252-253 of the log: 1 m apart along a corridor, 21 s between them; matched 0.35 m
    # short from the returns alone (1.0 m in the whole log's run)
    log = read_carmen(ACES).subset(slice(230, 260))
    result = LidarSlam.without_odometry(loop_every=10**9).run(log)
    ref, est = log.reference, result.frontend_poses
    err = relative_pose(relative_pose(ref[:-1], ref[1:]), relative_pose(est[:-1], est[1:]))
    steps = np.hypot(err[:, 0], err[:, 1])
    assert steps.max() < 0.2 and steps.mean() < 0.045


def test_fusing_a_match_with_the_prediction_is_the_product_of_the_gaussians():
    cov = np.diag([0.02, 0.01, 0.001]) ** 2
    # equal covariances: the midpoint (across the ±π seam too), half the covariance
    pose, fused = _fuse(np.array([1.0, 2.0, 3.1]), cov, np.array([1.2, 2.0, -3.1]), cov)
    np.testing.assert_allclose(pose[:2], [1.1, 2.0])
    assert abs(abs(pose[2]) - math.pi) < 1e-9
    np.testing.assert_allclose(fused, cov / 2)
    # a match unsure along x (a corridor) takes x from the prediction, y from itself
    along = np.diag([1.0, 1e-4, 1e-6])
    pose, fused = _fuse(np.zeros(3), along, np.array([0.3, 0.05, 0.0]), np.diag([1e-4] * 3))
    assert pose[0] == pytest.approx(0.3, abs=1e-3) and pose[1] == pytest.approx(0.025)
    assert np.all(np.linalg.eigvalsh(np.linalg.inv(fused) - np.linalg.inv(along)) > 0)


@needs_intel
def test_closures_leave_the_front_end_alone():
    # local_frontend: the sequential edges with closures are those of a run without them,
    # bit for bit (Intel's odometry fields are its corrected poses: a log with odometry)
    log = read_carmen(INTEL).subset(slice(12, 82))
    slam = LidarSlam(use_odometry=True, loop_min_separation=8, loop_gate=16.27)
    closed = slam.run(log)
    alone = LidarSlam(use_odometry=True, loop_min_separation=8, loop_every=10**9).run(log)
    loops = closed.loop_edges
    assert closed.stats["loops_accepted"] >= 1 and closed.stats["optimizations"] >= 1
    assert np.array_equal(closed.keyframes, alone.keyframes)
    assert np.array_equal(closed.graph.measurements[~loops], alone.graph.measurements)
    assert np.array_equal(closed.graph.information[~loops], alone.graph.information)


def _composed(steps):
    from wheelbase.geometry import compose

    out = np.zeros(3)
    for step in steps:
        out = compose(out, step)
    return out


def test_the_chain_covariance_is_that_of_the_composed_edges():
    from wheelbase.geometry import compose, inverse_pose
    from wheelbase.mapping.lidar_slam import _chain_covariance
    from wheelbase.mapping.se2 import se2_exp_map, se2_log

    rng = np.random.default_rng(0)
    meas = [np.array([0.3, 0.05, 0.2]) + rng.normal(0.0, 0.05, 3) for _ in range(12)]
    sigma = np.diag([0.01, 0.02, 0.03]) ** 2
    info = [np.linalg.inv(sigma)] * 12 + [np.eye(3)]  # a loop edge at the end: not summed
    flags = [False] * 12 + [True]
    c, j = 2, 10
    cov = _chain_covariance(meas, info, flags, c, j)
    mean = _composed(meas[c:j])
    noise = rng.multivariate_normal(np.zeros(3), sigma, size=(j - c, 20000))
    drawn = np.zeros((20000, 3))
    for m, e in zip(meas[c:j], noise, strict=True):  # each edge perturbed on its right
        drawn = compose(drawn, compose(np.broadcast_to(m, e.shape), se2_exp_map(e)))
    samples = se2_log(compose(np.broadcast_to(inverse_pose(mean), drawn.shape), drawn))
    assert np.allclose(np.cov(samples.T), cov, rtol=0.03, atol=1e-5)


def test_the_gate_keeps_a_true_closure_and_rejects_an_aisle_away():
    from wheelbase.geometry import compose, relative_pose
    from wheelbase.mapping.lidar_slam import _closure_chi2

    # 60 keyframes 0.2 m apart down an aisle and back (a U-turn in the middle), edges with
    # the errors measured in simulation (3 mm along, 1.5 mm across, 0.06°)
    steps = [np.array([0.2, 0.0, 0.0])] * 30 + [np.array([0.0, 0.0, math.pi])]
    steps += [np.array([0.2, 0.0, 0.0])] * 29
    sigma = np.diag([0.003, 0.0015, math.radians(0.06)]) ** 2
    info = [np.linalg.inv(sigma)] * len(steps)
    poses = [np.zeros(3)]
    for step in steps:
        poses.append(compose(poses[-1], step))
    c, j = 5, len(poses) - 6  # the same place, 50 keyframes apart
    loop_info = np.linalg.inv(np.diag([0.005, 0.003, math.radians(0.08)]) ** 2)
    truth = relative_pose(poses[c], poses[j])
    true_closure = truth + np.array([0.006, -0.003, math.radians(0.05)])
    flags = [False] * len(steps)
    kept = _closure_chi2(poses, steps, info, flags, c, j, true_closure, loop_info)
    assert kept < 16.27
    aliased = compose(truth, np.array([2.7, 0.0, 0.0]))  # the next aisle's twin
    assert _closure_chi2(poses, steps, info, flags, c, j, aliased, loop_info) > 1e3


@needs_intel
def test_relocalisation_puts_a_misplaced_scan_back_and_leaves_the_others():
    log = read_carmen(INTEL).subset(slice(12, 82))
    slam = LidarSlam.without_odometry()
    session = slam.session(log.angles, log.max_range, mount=log.mount)
    session.add(log.ranges, log.odometry, log.t)
    result = session.result()
    assert result.stats["relocalized"] == 0  # a consistent map: nothing moves
    estimate = result.poses.copy()
    misplaced = 40
    estimate[misplaced, :2] += [0.3, -0.2]  # beyond ICP's reach of the true spot, in the window
    moved = session._relocalize(estimate, result.graph.poses)
    assert moved == 1
    assert np.hypot(*(estimate[misplaced, :2] - result.poses[misplaced, :2])) < 0.03
    others = np.arange(log.n_scans) != misplaced
    assert np.array_equal(estimate[others], result.poses[others])


def test_relocalisation_needs_the_keyframes_own_references():
    from wheelbase.errors import ConfigError

    with pytest.raises(ConfigError, match="relocalize needs keyframe_normals"):
        LidarSlam(relocalize=True)
    with pytest.raises(ConfigError, match="relocalize_gain"):
        LidarSlam.without_odometry(relocalize_gain=-1.0)
    with pytest.raises(ConfigError, match="relocalize_window must be"):
        LidarSlam.without_odometry(relocalize_window=0.6)
    with pytest.raises(ConfigError, match="turn_prior must be true or false"):
        LidarSlam(turn_prior="no")


@needs_intel
def test_a_log_without_times_has_no_real_time_factor():
    import dataclasses

    log = read_carmen(INTEL).subset(slice(12, 30))
    flat = dataclasses.replace(log, t=np.zeros(log.n_scans))
    result = LidarSlam().run(flat)
    assert result.duration_s == 0.0 and math.isnan(result.real_time_factor)
    np.testing.assert_array_equal(result.poses, LidarSlam().run(log).poses)
    session = LidarSlam().session(log.angles, log.max_range, mount=log.mount)
    session.add(flat.ranges, None, flat.t)  # a session fed the stamps says the same
    assert session.result().duration_s == 0.0


def test_the_turn_prior_is_at_least_the_last_turn():
    from wheelbase.mapping.lidar_slam import turn_prior

    base = (0.2, math.radians(15.0))
    assert turn_prior(base, math.radians(5.0)) == base  # small turns: the prior as given
    assert turn_prior(base, -1.1) == (0.2, 1.1)  # a 63° turn back: no surer than the turn
    assert LidarSlam.without_odometry().turn_prior and not LidarSlam().turn_prior
