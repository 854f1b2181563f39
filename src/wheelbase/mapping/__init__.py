"""Mapping and SLAM: occupancy mapping, scan matching, pose graphs, lidar and landmark SLAM."""

from typing import TYPE_CHECKING

from wheelbase._lazy import attach

if TYPE_CHECKING:  # the names, for type checkers and IDEs; imported on first use
    from wheelbase.mapping.evaluation import (
        absolute_trajectory_error,
        map_agreement,
        relation_pairs,
        relative_errors,
    )
    from wheelbase.mapping.landmark_slam import LandmarkSlamResult, landmark_slam
    from wheelbase.mapping.lidar_slam import LidarSlam, SlamResult
    from wheelbase.mapping.occupancy import LogOddsMap, OccupancyMapper
    from wheelbase.mapping.posegraph import (
        PoseGraphResult,
        chordal_initialization,
        graph_chi2,
        optimize_pose_graph,
    )
    from wheelbase.mapping.scan_matching import LikelihoodTable, PointReference, ScanMatcher

_EXPORTS = {
    "LandmarkSlamResult": "wheelbase.mapping.landmark_slam",
    "LidarSlam": "wheelbase.mapping.lidar_slam",
    "LikelihoodTable": "wheelbase.mapping.scan_matching",
    "LogOddsMap": "wheelbase.mapping.occupancy",
    "OccupancyMapper": "wheelbase.mapping.occupancy",
    "PointReference": "wheelbase.mapping.scan_matching",
    "PoseGraphResult": "wheelbase.mapping.posegraph",
    "ScanMatcher": "wheelbase.mapping.scan_matching",
    "SlamResult": "wheelbase.mapping.lidar_slam",
    "absolute_trajectory_error": "wheelbase.mapping.evaluation",
    "chordal_initialization": "wheelbase.mapping.posegraph",
    "graph_chi2": "wheelbase.mapping.posegraph",
    "landmark_slam": "wheelbase.mapping.landmark_slam",
    "map_agreement": "wheelbase.mapping.evaluation",
    "optimize_pose_graph": "wheelbase.mapping.posegraph",
    "relation_pairs": "wheelbase.mapping.evaluation",
    "relative_errors": "wheelbase.mapping.evaluation",
}
__getattr__, __dir__ = attach(__name__, _EXPORTS)

__all__ = [
    "LandmarkSlamResult",
    "LidarSlam",
    "LikelihoodTable",
    "LogOddsMap",
    "OccupancyMapper",
    "PointReference",
    "PoseGraphResult",
    "ScanMatcher",
    "SlamResult",
    "absolute_trajectory_error",
    "chordal_initialization",
    "graph_chi2",
    "landmark_slam",
    "map_agreement",
    "optimize_pose_graph",
    "relation_pairs",
    "relative_errors",
]
