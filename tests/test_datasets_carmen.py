"""CARMEN logs: the Intel and ACES corrected logs, both line formats, and bad files."""

import gzip
import math

import numpy as np
import pytest

from shared_data import DATA, absent
from wheelbase.datasets.carmen import read_carmen
from wheelbase.errors import DataError

CARMEN = DATA / "carmen"
needs_logs = pytest.mark.skipif(
    not (CARMEN / "intel-corrected.log.gz").is_file(), reason=absent(CARMEN)
)


@needs_logs
@pytest.mark.parametrize(("name", "scans"), [("intel", 910), ("aces", 440)])
def test_the_corrected_logs(name, scans):
    log = read_carmen(CARMEN / f"{name}-corrected.log.gz")
    assert log.n_scans == scans and log.ranges.shape == (scans, 180)
    assert log.angles[0] == pytest.approx(-math.pi / 2)
    np.testing.assert_allclose(np.diff(log.angles), math.radians(1.0))
    assert np.all(np.diff(log.t) >= 0) and log.invalid_readings == 0
    np.testing.assert_array_equal(log.odometry, log.reference)  # the "corrected" logs repeat it


def _flaser(n, ranges, pose=(1.0, 2.0, 0.5), t=10.0):
    return f"FLASER {n} {' '.join(map(str, ranges))} {' '.join(map(str, pose))} " \
           f"{' '.join(map(str, pose))} {t} host {t}\n"  # fmt: skip


def test_flaser_and_robotlaser_lines(tmp_path):
    text = "# comment\nPARAM robot_x 0 host 0\nODOM 0 0 0 0 0 0 1 h 1\n"
    text += _flaser(4, [1.0, "nan", -1.0, 81.83], t=2.0) + _flaser(4, [1.0, 2.0, 3.0, 4.0], t=1.0)
    path = tmp_path / "log.clf"
    path.write_text(text)
    log = read_carmen(path)
    assert log.n_scans == 2 and log.invalid_readings == 2
    assert log.t.tolist() == [1.0, 2.0]  # sorted by time
    assert np.isnan(log.ranges[1, 1:3]).all() and log.ranges[1, 3] == 81.83
    assert log.extra == {"skipped_messages": 1, "odom_messages": 1}
    gz = tmp_path / "log.gz"
    gz.write_bytes(gzip.compress(text.encode()))
    np.testing.assert_array_equal(read_carmen(gz).ranges, log.ranges)
    robot = ("ROBOTLASER1 0 -1.5 3.0 1.0 20.0 0.01 0 4 1 2 3 4 0 "
             "1.1 2.0 0.5 1.0 2.0 0.5 0 0 0 0 0 5.0 host 5.0\n")  # fmt: skip
    (tmp_path / "r.log").write_text(robot)
    rl = read_carmen(tmp_path / "r.log")
    assert rl.max_range == 20.0 and rl.angles.tolist() == [-1.5, -0.5, 0.5, 1.5]
    assert rl.mount[0] == pytest.approx(0.1 / math.cos(0.5) * math.cos(0.5), abs=0.11)


@pytest.mark.parametrize(
    ("text", "match"),
    [
        ("", "no laser scan"),
        ("ODOM 0 0 0 0 0 0 1 h 1\n", "no laser scan"),
        ("FLASER 3 1 2\n", "cut short"),
        ("FLASER x 1 2\n", "non-number"),
        ("FLASER 1e9 1\n", "beam count"),
        (_flaser(2, [1, 2]) + _flaser(3, [1, 2, 3]), "geometry"),
    ],
)
def test_bad_logs(tmp_path, text, match):
    path = tmp_path / "bad.log"
    path.write_text(text)
    with pytest.raises(DataError, match=match):
        read_carmen(path)


def test_missing_file(tmp_path):
    with pytest.raises(DataError, match="not found"):
        read_carmen(tmp_path / "none.log")


def test_stamps_that_are_not_times_keep_the_order_recorded(tmp_path):
    # CSAIL's corrected log holds one stamp for nearly every scan, the MIT infinite corridor's
    # jumps to 2^32 s: sorting by them would shuffle the scans
    poses = [(float(k), 0.0, 0.0) for k in range(5)]
    text = "".join(_flaser(3, [1.0, 2.0, 3.0], pose=p, t=7.0) for p in poses)
    path = tmp_path / "flat.log"
    path.write_text(text)
    log = read_carmen(path)
    assert not log.timed and log.duration == 0.0
    np.testing.assert_array_equal(log.reference[:, 0], np.arange(5.0))
    stamps = [-0.4, -0.9, -1.3, 4.29497e9, 4.29497e9, 4.29497e9]
    text = "".join(_flaser(3, [1.0, 2.0, 3.0], pose=(float(k), 0.0, 0.0), t=t)
                   for k, t in enumerate(stamps))  # fmt: skip
    path.write_text(text)
    log = read_carmen(path)
    assert not log.timed
    np.testing.assert_array_equal(log.reference[:, 0], np.arange(6.0))


def test_loop_relations_fall_back_to_the_distance_along_the_reference():
    from wheelbase.mapping.evaluation import relation_pairs

    # a 20 m square driven twice, 0.5 m a scan
    side = np.arange(0.0, 5.0, 0.5)
    square = np.vstack([np.column_stack([side, 0 * side]),
                        np.column_stack([5 + 0 * side, side]),
                        np.column_stack([5 - side, 5 + 0 * side]),
                        np.column_stack([0 * side, 5 - side])])  # fmt: skip
    xy = np.vstack([square, square])
    heading = np.arctan2(*np.diff(np.vstack([xy, xy[:1]]), axis=0).T[::-1])
    reference = np.column_stack([xy, heading])
    timed = relation_pairs(reference, np.arange(len(xy)) * 2.0)  # 40 s a lap
    untimed = relation_pairs(reference, np.zeros(len(xy)))
    np.testing.assert_array_equal(timed[0], untimed[0])
    assert len(timed[1]) == len(untimed[1]) == 40  # each scan of the second lap: the first's
    np.testing.assert_array_equal(untimed[1][:, 1] - untimed[1][:, 0], 40)
