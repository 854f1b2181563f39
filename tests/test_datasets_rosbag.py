"""ROS 2 bags: a simulated run written with rosbags reads back the same, and SLAM agrees."""

import json

import numpy as np
import pytest
from typer.testing import CliRunner

pytest.importorskip("rosbags")

import wheelbase
from wheelbase.datasets.rosbag import read_bag, write_bag
from wheelbase.datasets.scans import ScanLog
from wheelbase.datasets.simulated import scans_from_log
from wheelbase.errors import DataError
from wheelbase.mapping.lidar_slam import LidarSlam
from wheelbase.sensors import Lidar

SCENARIO = {
    "name": "slam_bag", "map": "warehouse", "robot": {"model": "diffdrive", "preset": "rm100"},
    "plant": "kinematic", "controller": {"law": "kanayama"},
    "odometry": {"mode": "encoders", "pulses_per_revolution": 2048,
                 "wheel_radius_scale": [1.01, 1.01]},
    "sensors": {"lidar": {"beams": 180, "fov_deg": 360, "max_range": 8.0, "range_std": 0.01,
                          "rate_hz": 5}},
    "start": [3.0, 2.0, 0.0], "goal": [8.0, 2.5, 0.0],
    "trajectory": {"max_speed": 0.8, "max_acceleration": 0.5, "max_yaw_rate": 1.0},
    "dt": 0.05, "duration": 30,
}  # fmt: skip


@pytest.fixture(scope="module")
def run_log():
    result = wheelbase.run(SCENARIO)
    return scans_from_log(result.log, Lidar(beams=180, max_range=8.0))


@pytest.mark.parametrize("storage", ["mcap", "sqlite3"])
def test_a_run_round_trips_through_a_bag(tmp_path, run_log, storage):
    bag = write_bag(run_log, tmp_path / "bag", storage=storage)
    back = read_bag(bag, reference_topic="/ground_truth")
    np.testing.assert_allclose(back.t, run_log.t, atol=1e-9)  # ROS time: integer ns
    np.testing.assert_array_equal(back.ranges, run_log.ranges)
    # float32 angle_min and angle_increment: the beam k is within k·6e-8 rad
    np.testing.assert_allclose(back.angles, run_log.angles, atol=1e-6)
    np.testing.assert_allclose(back.odometry, run_log.odometry, atol=1e-12)
    np.testing.assert_allclose(back.reference, run_log.reference, atol=1e-12)
    with pytest.raises(FileExistsError):
        write_bag(run_log, bag)


def test_slam_on_the_bag_equals_slam_on_the_run(tmp_path, run_log):
    slam = LidarSlam(use_odometry=True)
    direct = slam.run(run_log)
    bag = read_bag(write_bag(run_log, tmp_path / "bag"), reference_topic="/ground_truth")
    # the bag stores the angles as float32 increments: the same record to 1e-7 rad
    from_bag = slam.run(ScanLog(bag.t, bag.ranges, run_log.angles, bag.max_range, bag.odometry,
                                bag.reference, bag.mount))  # fmt: skip
    np.testing.assert_allclose(from_bag.poses, direct.poses, atol=1e-9)
    err = np.hypot(*(direct.poses[:, :2] - run_log.reference[:, :2]).T)
    drift = np.hypot(*(run_log.odometry[:, :2] - run_log.reference[:, :2]).T)
    assert err.max() < 0.1 and err.max() < drift.max()


def test_bad_bags(tmp_path, run_log):
    bag = write_bag(run_log, tmp_path / "bag")
    with pytest.raises(DataError, match=r"no topic '/laser'.*/scan \(sensor_msgs/msg/LaserScan\)"):
        read_bag(bag, scan_topic="/laser")
    with pytest.raises(DataError, match="holds sensor_msgs/msg/LaserScan, not nav_msgs"):
        read_bag(bag, odom_topic="/scan")
    with pytest.raises(DataError, match="not found"):
        read_bag(tmp_path / "none")
    (tmp_path / "folder").mkdir()
    with pytest.raises(DataError, match=r"metadata\.yaml"):
        read_bag(tmp_path / "folder")


def test_invalid_readings_follow_rep_117(tmp_path):
    ranges = np.array([[1.0, np.nan, np.inf, -np.inf, 0.01, 2.0]])
    log = ScanLog(np.array([1.0]), ranges, np.linspace(-1, 1, 6), 5.0)
    back = read_bag(write_bag(ScanLog(log.t, np.where(np.isinf(ranges), ranges, ranges),
                                      log.angles, 5.0), tmp_path / "b"))  # fmt: skip
    assert back.invalid_readings == 2  # NaN and −inf (range_min is 0 in the written bag)
    assert back.ranges[0, 2] == 5.0  # +inf: no return, at range_max


def test_slam_and_map_commands_on_a_bag(tmp_path, run_log):
    from wheelbase.cli import app

    bag = write_bag(run_log, tmp_path / "bag")
    runner = CliRunner()
    result = runner.invoke(app, ["slam", str(bag), "--out", str(tmp_path / "s"), "--odometry",
                                 "--frames", "3"])  # fmt: skip
    assert result.exit_code == 0, result.output
    metrics = json.loads((tmp_path / "s" / "metrics.json").read_text())
    assert {"processing_time_s", "real_time_factor"} <= set(metrics)
    for name in ("map.yaml", "map.pgm", "map.png", "error.png", "map.gif", "graph.g2o"):
        assert (tmp_path / "s" / name).is_file()
    mapped = runner.invoke(app, ["map", str(bag), "--out", str(tmp_path / "m"), "--poses",
                                 "odometry"])  # fmt: skip
    assert mapped.exit_code == 0, mapped.output
    grid = wheelbase.planning.read_ros_yaml(tmp_path / "m" / "map.yaml")
    assert grid.resolution == 0.05 and grid.occupied.any()
    none = runner.invoke(app, ["map", str(bag), "--out", str(tmp_path / "n")])
    assert none.exit_code == 2 and "no reference poses" in none.output
