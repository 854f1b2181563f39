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
