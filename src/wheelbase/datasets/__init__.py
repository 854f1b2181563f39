"""Readers of recorded data, each returning plain records: g2o pose graphs, CARMEN logs."""

from typing import TYPE_CHECKING

from wheelbase._lazy import attach

if TYPE_CHECKING:  # the names, for type checkers and IDEs; imported on first use
    from wheelbase.datasets.g2o import PoseGraph, odometry_guess, read_g2o, write_g2o

_EXPORTS = {
    "PoseGraph": "wheelbase.datasets.g2o",
    "odometry_guess": "wheelbase.datasets.g2o",
    "read_g2o": "wheelbase.datasets.g2o",
    "write_g2o": "wheelbase.datasets.g2o",
}
__getattr__, __dir__ = attach(__name__, _EXPORTS)

__all__ = ["PoseGraph", "odometry_guess", "read_g2o", "write_g2o"]
