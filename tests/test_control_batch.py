"""Every control law takes a batch: poses (N, 3) in, commands (N, k) out, robot i as alone."""

import numpy as np
import pytest

from control_cases import figure_eight_reference, three_point_turn_path
from wheelbase.control import (
    POSE_LAWS,
    ComputedTorquePID,
    GoToGoal,
    Kanayama,
    LinearTracker,
    PurePursuit,
    RearWheelFeedback,
    SegmentFollower,
    Stanley,
    TwistTorqueLoop,
    make_pose_law,
)
from wheelbase.control.torque import TimedRows
from wheelbase.dynamics import RM100
from wheelbase.trajectory import feasible_trajectory

POSES = np.array([[0.1, 0.2, 0.0], [1.0, -0.5, 1.0], [-1.0, 1.0, -2.0], [0.3, 0.3, 3.0]])
EIGHT = figure_eight_reference(30.0, 0.01)
CUSPS = three_point_turn_path()
LAWS = {
    **{name: (lambda name=name: make_pose_law(name), [0.0, 0.0, 0.0]) for name in POSE_LAWS},
    "kanayama": (Kanayama, EIGHT),
    "linear": (LinearTracker, EIGHT),
    **{
        cls.__name__: (lambda cls=cls: cls(speed=0.3), CUSPS)
        for cls in (PurePursuit, Stanley, RearWheelFeedback, SegmentFollower)
    },
    "go_to_goal": (GoToGoal, [1.0, 1.0]),
}


@pytest.mark.parametrize("name", sorted(LAWS))
def test_a_batch_equals_its_robots_alone(name):
    make, reference = LAWS[name]
    batch = np.asarray(make()(0.5, POSES, reference))
    assert batch.shape == (len(POSES), 2)
    for i, pose in enumerate(POSES):
        np.testing.assert_allclose(batch[i], make()(0.5, pose, reference), rtol=1e-12, atol=1e-12)


def test_torque_laws_take_batches():
    states = np.column_stack([POSES, np.tile([0.1, 0.0, 0.05], (len(POSES), 1))])
    reference = feasible_trajectory([[0, 0], [2, 0]], 0.2)
    rows = TimedRows.from_pose_trajectory(reference, [0.0, 0.5, 1.0])
    for make in (
        lambda: ComputedTorquePID(RM100),
        lambda: TwistTorqueLoop(make_pose_law("polar"), RM100, bandwidth=10.0),
    ):
        ref = rows if "Computed" in type(make()).__name__ else [0.0, 0.0, 0.0]
        batch = make()(0.5, states, ref)
        assert batch.shape == (len(POSES), 2)
        for i, state in enumerate(states):
            np.testing.assert_allclose(batch[i], make()(0.5, state, ref), rtol=1e-12, atol=1e-12)
