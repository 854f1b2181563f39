"""Frontier exploration on the bundled doorway world: it ends with no reachable frontier, the
saved map loads, and AMCL on it navigates (a real run that arrives)."""

import json

import numpy as np
import pytest

from wheelbase.errors import ScenarioError
from wheelbase.exploration import explore, load_exploration


@pytest.fixture(scope="module")
def explored():
    return explore("doorway")


def test_exploration_ends_with_no_reachable_frontier(explored):
    m = explored.metrics
    assert m["status"] == "explored"
    assert m["collisions"] == 0 and m["legs"] == m["legs_arrived"] >= 2
    assert m["explored_fraction"] >= 0.95
    assert m["map_agreement"] >= 0.97
    assert m["position_rmse_m"] < 0.1
    # the same choice again on the final map finds nothing reachable
    from wheelbase.exploration import _distance_field, _free_start, _parts, _planner
    from wheelbase.mapping.frontiers import choose_frontier, find_frontiers

    parts = _parts(explored.scenario, explored.truth)
    grid = explored.grid
    start = _free_start(_planner(grid, parts, explored.scenario), grid,
                        explored.estimated_path[-1])  # fmt: skip
    field, targets = _distance_field(grid, parts, start)
    visited = np.vstack([explored.frontiers, explored.frontiers])
    found = find_frontiers(grid, 10, explored.spec.wall_fringe)
    ranked = choose_frontier(found, field, grid.resolution, targets=targets, blacklist=visited,
                             origin=grid.origin)  # fmt: skip
    assert all(np.min(np.hypot(*(explored.frontiers - f.centroid).T)) < 1.5 for _, f, _ in ranked)


def test_the_saved_map_loads_back_as_it_was(explored, tmp_path):
    # AMCL on it, with the lidar on the true world: the next test
    from wheelbase.planning.map_io import read_ros_yaml, write_ros_yaml

    write_ros_yaml(explored.grid, tmp_path / "map.yaml")
    again = read_ros_yaml(tmp_path / "map.yaml")
    assert np.array_equal(again.occupied, explored.grid.occupied)
    assert np.array_equal(again.unknown, explored.grid.unknown)


def test_amcl_on_the_explored_map_sees_the_true_world(explored, tmp_path):
    # benchmarks/slam.py: the robot's map is the explored one, the lidar and the arrival see
    # the scenario's map; a true world 0.2 m off the one explored puts the robot 0.2 m off
    from slam import amcl_on_explored_map, amcl_route
    from wheelbase.planning import load_map
    from wheelbase.planning.map_io import write_ros_yaml

    scenario = amcl_route("doorway", duration=90.0)
    row = amcl_on_explored_map(explored.grid, [0], scenario)
    assert row["arrived"] == 1 and row["final_position_error_true_max_m"] < 0.1
    truth = load_map("doorway")
    write_ros_yaml(truth.with_origin(np.add(truth.origin, (0.0, 0.2))), tmp_path / "moved.yaml")
    moved = amcl_on_explored_map(
        explored.grid, [0], {**scenario, "map": str(tmp_path / "moved.yaml")}
    )
    assert moved["statuses"] == {"missed_goal": 1}
    assert 0.1 < moved["final_position_error_true_max_m"] < 0.3


def test_a_long_plan_is_cut_at_the_replan_distance():
    from wheelbase.exploration import _cut
    from wheelbase.planning.path import PlannedPath

    x = np.linspace(0.0, 10.0, 201)
    poses = np.stack([x, np.zeros_like(x), np.zeros_like(x)], -1)
    plan = PlannedPath(poses, np.ones(201), np.zeros(201), x)
    cut = _cut(plan, 3.0)
    assert 3.0 <= cut.length < 3.05 and np.array_equal(cut.poses, poses[: len(cut.poses)])
    assert _cut(plan, 0.0) is plan and _cut(plan, 7.0) is plan  # no stop just before the goal


def test_a_cut_plan_stops_where_it_has_most_room_in_the_last_half_of_the_cut():
    from scipy import ndimage

    from wheelbase.exploration import _cut
    from wheelbase.planning import OccupancyGrid
    from wheelbase.planning.path import PlannedPath

    # a plan along y = 1.15 m in a corridor (walls below 0.6 m, above 1.4 m) whose north wall
    # has a 0.3 m deep recess at x 2.0-2.6 m
    occupied = np.zeros((40, 220), bool)
    occupied[:12] = occupied[28:] = True  # walls below y = 0.6 m and above y = 1.4 m
    occupied[28:34, 40:52] = False  # the recess
    grid = OccupancyGrid.from_array(occupied, 0.05)
    room = ndimage.distance_transform_edt(~grid.occupied) * grid.resolution
    x = np.linspace(0.0, 10.0, 201)
    poses = np.stack([x, np.full_like(x, 1.15), np.zeros_like(x)], -1)
    plan = PlannedPath(poses, np.ones(201), np.zeros(201), x)
    cut = _cut(plan, 3.0, room, grid)
    end = cut.poses[-1]
    assert np.array_equal(cut.poses, poses[: len(cut.poses)])
    assert 2.0 <= end[0] <= 2.6  # in the recess, within [1.5, 3.0] m along the plan
    cell = grid.world_to_cell(poses[:, :2])
    along = room[cell[:, 0], cell[:, 1]]
    window = (x >= 1.5) & (x <= 3.0 + 1e-9)
    assert room[tuple(grid.world_to_cell(end[:2]))] == pytest.approx(along[window].max())
    assert end[0] == x[window][along[window] == along[window].max()][-1]  # the farthest
    assert _cut(plan, 7.0, room, grid) is plan


def test_a_start_too_near_a_wall_for_the_margin_moves_to_the_nearest_with_room():
    from types import SimpleNamespace

    from wheelbase.exploration import _free_start
    from wheelbase.planning import Footprint, OccupancyGrid

    res, length, width = 0.05, 0.86, 0.655  # the planning footprint: robot + margins
    occupied = np.zeros((80, 80), bool)
    occupied[:20] = True  # a wall below y = 1.0 m
    grid = OccupancyGrid.from_array(occupied, res)
    planner = SimpleNamespace(footprint=Footprint.rectangle(length, width))
    open_pose = np.array([2.0, 2.5, 0.0])
    assert np.array_equal(_free_start(planner, grid, open_pose), open_pose)  # room all round
    near = np.array([2.0, 1.0 + 0.5 * width - 0.04, 0.0])  # 4 cm into the wall for the margin
    moved = _free_start(planner, grid, near)
    # straight up, to where the footprint clears the wall by a cell (on the 2.5 cm lattice)
    assert moved[0] == pytest.approx(near[0]) and moved[2] == near[2]
    need = 1.0 + 0.5 * width + res
    assert need <= moved[1] < need + 0.5 * res + 1e-9
    assert not grid.in_collision(planner.footprint.inflated(res), moved)
    # a corridor the footprint fits in with less than a cell to spare: the free pose in it
    corridor = np.ones((80, 80), bool)
    corridor[20 : 20 + round((width + 0.04) / res)] = False  # 0.70 m
    tight = OccupancyGrid.from_array(corridor, res)
    inside = _free_start(planner, tight, np.array([2.0, 1.05 + 0.5 * width, 0.0]))
    assert inside is not None and not tight.in_collision(planner.footprint, inside)
    assert tight.in_collision(planner.footprint.inflated(res), inside)
    # too narrow for the footprint anywhere within half its width: no start (status stuck)
    narrow = np.ones((80, 80), bool)
    narrow[20:30] = False
    thin = OccupancyGrid.from_array(narrow, res)
    assert _free_start(planner, thin, np.array([2.0, 1.25, 0.0])) is None


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"map": "doorway"}, "map: an exploration starts without a map"),
        ({"world": None}, "world.map"),
        ({"world": {"map": "doorway", "agents": []}}, "world.agents"),
        ({"goal": [1, 1, 0]}, "goal: the frontiers are the goals"),
        ({"localization": {"method": "amcl"}}, "localization"),
        ({"sensors": {}}, "sensors.lidar"),
        ({"plant": "dynamic"}, "plant"),
        ({"exploration": {"min_frontier_size": -1}}, "exploration: min_frontier_size"),
        ({"exploration": {"bogus": 1}}, "exploration: bogus"),
        ({"exploration": {"replan_distance": -1}}, "exploration: replan_distance"),
        ({"exploration": {"replan_distance": 6e-280}}, "replan_distance.*at least 0.5 m"),
        ({"exploration": 3}, "exploration: a mapping"),
        ({"controller": {"law": "mppi"}}, "controller.law"),
        ({"start": [1.0, float("nan"), 0.0]}, "start"),
    ],
)
def test_bad_input_errors(change, message):
    data = load_exploration.__globals__["yaml"].safe_load(
        (load_exploration.__globals__["bundled_explorations"]()["doorway"]).read_text()
    )
    data.update(change)
    data = {k: v for k, v in data.items() if v is not None}
    with pytest.raises(ScenarioError, match=message):
        if change.get("controller"):
            explore(data)
        else:
            load_exploration(data)


def test_cli_writes_the_map_and_metrics(explored, tmp_path, monkeypatch):
    from typer.testing import CliRunner

    import wheelbase.exploration
    from wheelbase.cli import app

    seen = []

    def reuse(loaded, progress=None):  # the module's exploration of the same scenario
        seen.append(loaded)
        return explored

    monkeypatch.setattr(wheelbase.exploration, "explore", reuse)
    out = tmp_path / "out"
    result = CliRunner().invoke(app, ["explore", "doorway", "--out", str(out), "--frames", "3"])
    assert result.exit_code == 0, result.output
    assert seen[0][0] == explored.scenario and seen[0][1] == explored.spec
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["status"] == "explored" and metrics["collisions"] == 0
    assert metrics["explored_fraction"] == explored.metrics["explored_fraction"]
    for name in ("map.yaml", "map.pgm", "map.png", "map.gif"):
        assert (out / name).stat().st_size > 0


def test_the_turn_on_the_spot_at_the_end_of_a_plan_is_dropped():
    from wheelbase.exploration import _without_final_turn
    from wheelbase.planning.path import PlannedPath

    x = np.array([0.0, 0.5, 1.0, 1.0, 1.0])
    poses = np.stack([x, np.zeros(5), [0.0, 0.0, 0.0, 0.5, 1.0]], -1)
    curvatures = np.array([0.0, 0.0, 0.0, np.inf, np.inf])
    plan = PlannedPath(poses, np.ones(5), curvatures, x)
    dropped = _without_final_turn(plan)
    assert np.array_equal(dropped.poses, poses[:3])
    assert _without_final_turn(dropped) is dropped
