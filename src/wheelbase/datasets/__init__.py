"""Readers of recorded data, each returning plain records: g2o pose graphs, CARMEN logs,
ROS 2 bags, MRCLAM folders and the simulator's runs (:class:`ScanLog`)."""

from typing import TYPE_CHECKING

from wheelbase._lazy import attach

if TYPE_CHECKING:  # the names, for type checkers and IDEs; imported on first use
    from wheelbase.datasets.carmen import read_carmen
    from wheelbase.datasets.g2o import PoseGraph, odometry_guess, read_g2o, write_g2o
    from wheelbase.datasets.mrclam import (
        MrclamData,
        MrclamLandmarks,
        MrclamMeasurements,
        find_mrclam_files,
        load_landmarks,
        load_measurements,
        load_mrclam,
    )
    from wheelbase.datasets.open import read_scans
    from wheelbase.datasets.rosbag import read_bag, write_bag
    from wheelbase.datasets.scans import ScanLog
    from wheelbase.datasets.simulated import scans_from_log

_EXPORTS = {
    "MrclamData": "wheelbase.datasets.mrclam",
    "MrclamLandmarks": "wheelbase.datasets.mrclam",
    "MrclamMeasurements": "wheelbase.datasets.mrclam",
    "find_mrclam_files": "wheelbase.datasets.mrclam",
    "load_landmarks": "wheelbase.datasets.mrclam",
    "load_measurements": "wheelbase.datasets.mrclam",
    "load_mrclam": "wheelbase.datasets.mrclam",
    "PoseGraph": "wheelbase.datasets.g2o",
    "ScanLog": "wheelbase.datasets.scans",
    "odometry_guess": "wheelbase.datasets.g2o",
    "read_bag": "wheelbase.datasets.rosbag",
    "read_carmen": "wheelbase.datasets.carmen",
    "read_g2o": "wheelbase.datasets.g2o",
    "read_scans": "wheelbase.datasets.open",
    "scans_from_log": "wheelbase.datasets.simulated",
    "write_bag": "wheelbase.datasets.rosbag",
    "write_g2o": "wheelbase.datasets.g2o",
}
__getattr__, __dir__ = attach(__name__, _EXPORTS)

__all__ = [
    "MrclamData",
    "MrclamLandmarks",
    "MrclamMeasurements",
    "PoseGraph",
    "ScanLog",
    "find_mrclam_files",
    "load_landmarks",
    "load_measurements",
    "load_mrclam",
    "odometry_guess",
    "read_bag",
    "read_carmen",
    "read_g2o",
    "read_scans",
    "scans_from_log",
    "write_bag",
    "write_g2o",
]
