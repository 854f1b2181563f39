"""Lidar SLAM on the first scans of the Intel log (no odometry) and on bad logs."""

import math

import numpy as np
import pytest

from shared_data import DATA, absent
from wheelbase.datasets.carmen import read_carmen
from wheelbase.datasets.scans import ScanLog
from wheelbase.errors import DataError
from wheelbase.mapping.evaluation import relation_pairs, relative_errors
from wheelbase.mapping.lidar_slam import LidarSlam

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
