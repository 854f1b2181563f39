"""Mapping and SLAM: pose graphs on SE(2)."""

from typing import TYPE_CHECKING

from wheelbase._lazy import attach

if TYPE_CHECKING:  # the names, for type checkers and IDEs; imported on first use
    from wheelbase.mapping.posegraph import (
        PoseGraphResult,
        chordal_initialization,
        graph_chi2,
        optimize_pose_graph,
    )

_EXPORTS = {
    "PoseGraphResult": "wheelbase.mapping.posegraph",
    "chordal_initialization": "wheelbase.mapping.posegraph",
    "graph_chi2": "wheelbase.mapping.posegraph",
    "optimize_pose_graph": "wheelbase.mapping.posegraph",
}
__getattr__, __dir__ = attach(__name__, _EXPORTS)

__all__ = ["PoseGraphResult", "chordal_initialization", "graph_chi2", "optimize_pose_graph"]
