"""Polygon worlds: exact collision and clearance (cross-checked with shapely), files, errors."""

import json
import math

import numpy as np
import pytest
import shapely

from wheelbase.errors import MapError
from wheelbase.planning import (
    Footprint,
    HybridAStar,
    OccupancyGrid,
    PolygonWorld,
    load_map,
)
from wheelbase.planning.maps import load_world
from wheelbase.planning.world_io import world_schema

# a non-convex polygon with a hole, a convex one and two discs
L_SHAPE = [(2.0, 1.0), (6.0, 1.0), (6.0, 2.0), (3.0, 2.0), (3.0, 5.0), (2.0, 5.0)]
RING = (
    [(7.0, 3.0), (11.0, 3.0), (11.0, 7.0), (7.0, 7.0)],
    [[(8.0, 4.0), (10.0, 4.0), (10.0, 6.0), (8.0, 6.0)]],
)
DISCS = [[4.5, 6.5, 0.6], [12.5, 1.5, 0.4]]
BOUNDS = (0.0, 14.0, 0.0, 8.0)


def world() -> PolygonWorld:
    return PolygonWorld([L_SHAPE, RING], DISCS, BOUNDS, 0.1)


def shapely_obstacles():
    parts = [shapely.Polygon(L_SHAPE), shapely.Polygon(*RING)]
    parts += [shapely.Point(x, y).buffer(r, 256) for x, y, r in DISCS]
    return shapely.union_all(parts)


def footprint_shapes(fp: Footprint, poses: np.ndarray):
    c, s = np.cos(poses[:, 2]), np.sin(poses[:, 2])
    px, py = fp.polygon[:, 0], fp.polygon[:, 1]
    wx = poses[:, None, 0] + c[:, None] * px - s[:, None] * py
    wy = poses[:, None, 1] + s[:, None] * px + c[:, None] * py
    return shapely.polygons(np.stack([wx, wy], -1))


def random_poses(n: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return np.column_stack(
        [rng.uniform(1.0, 13.0, n), rng.uniform(1.0, 7.0, n), rng.uniform(-np.pi, np.pi, n)]
    )


def test_collision_is_exact_against_shapely():
    w, fp = world(), Footprint.rectangle(1.2, 0.6, 0.3)
    poses = random_poses(3000, 1)
    shapes = footprint_shapes(fp, poses)
    inside = shapely.contains(shapely.box(0, 0, 14, 8), shapes)
    truth = shapely.intersects(shapes, shapely_obstacles()) | ~inside
    ours = w.in_collision(fp, poses)
    # discs are 256-gons in shapely: disagreement only within 1e-4 m of a disc
    near = np.abs(shapely.distance(shapes, shapely_obstacles())) < 1e-4
    assert np.all((ours == truth) | near)
    assert 300 < truth.sum() < 2700  # both outcomes are well represented


def test_clearance_is_the_exact_polygon_distance():
    w, fp = world(), Footprint.rectangle(1.2, 0.6, 0.3)
    poses = random_poses(400, 2)
    poses = poses[~w.in_collision(fp, poses)]
    truth = shapely.distance(footprint_shapes(fp, poses), shapely_obstacles())
    np.testing.assert_allclose(w.footprint_clearance(fp, poses), truth, atol=2e-4)
    points = poses[:, :2]
    np.testing.assert_allclose(
        w.clearance(points), shapely.distance(shapely.points(points), shapely_obstacles()),
        atol=2e-4,
    )  # fmt: skip


def test_points_in_the_hole_are_free_and_lattice_agrees():
    w = world()
    assert not w.is_occupied([9.0, 5.0]) and w.is_occupied([7.5, 5.0])
    assert w.is_occupied([4.5, 6.5]) and not w.is_occupied([2.5, 5.5])
    fp = Footprint.rectangle(1.0, 0.8)
    poses = random_poses(500, 3)
    lattice = w.lattice_collisions(fp, poses, 0.02)
    assert np.all(~lattice | w.in_collision(fp, poses))  # the lattice never sees more


def test_raster_is_conservative():
    w = world()
    rows, cols = w.shape
    centres = w.raster.cell_to_world(
        np.stack(np.meshgrid(np.arange(rows), np.arange(cols), indexing="ij"), -1)
    ).reshape(-1, 2)
    occupied_truth = w.is_occupied(centres).reshape(rows, cols)
    assert np.all(~occupied_truth | w.occupied)  # every cell centre in an obstacle is marked


def test_a_gap_narrower_than_a_cell_is_exact():
    # two blocks 0.7 m apart; a 0.6 m wide robot fits; rasterised at 0.1 m only 0.5 m is free
    blocks = [[(0, 0), (5, 0), (5, 2.0), (0, 2.0)], [(0, 2.7), (5, 2.7), (5, 5), (0, 5)]]
    w = PolygonWorld(blocks, bounds=(-4.0, 9.0, 0.0, 5.0), resolution=0.1)
    fp = Footprint.rectangle(1.0, 0.6)
    assert not w.in_collision(fp, [2.5, 2.35, 0.0])
    assert w.in_collision(fp, [2.5, 2.29, 0.0])
    assert w.in_collision(fp, [2.5, 2.35, 0.15])  # turning touches a wall
    cells = w.raster.world_to_cell([[2.5, 2.05], [2.5, 2.65]])
    assert w.occupied[cells[:, 0], cells[:, 1]].all()  # the raster closes the gap to 0.5 m
    path = HybridAStar(w, fp, 0.0, xy_resolution=0.1).plan((-2.0, 2.35, 0.0), (7.0, 2.35, 0.0))
    assert path.success
    assert not w.in_collision(fp, path.poses).any()


def test_world_on_a_grid_combines_both():
    occ = np.zeros((60, 100), bool)
    occ[20:40, 10:20] = True
    grid = OccupancyGrid.from_array(occ, 0.1)
    w = PolygonWorld([[(5.0, 2.0), (7.0, 2.0), (6.0, 4.0)]], grid=grid)
    fp = Footprint.rectangle(0.4, 0.4)
    assert w.extent == grid.extent
    assert w.in_collision(fp, [1.5, 3.0, 0.0])  # the grid's block
    assert w.in_collision(fp, [6.0, 3.0, 0.0])  # the triangle
    assert not w.in_collision(fp, [3.5, 3.0, 0.0])
    np.testing.assert_allclose(w.footprint_clearance(fp, [3.5, 3.0, 0.0]), 1.3, atol=1e-9)


@pytest.mark.parametrize(
    ("polygons", "discs", "match"),
    [
        ([[(0, 0), (1, 1), (1, 0), (0, 1)]], [], "polygon 0 is invalid: Self-intersection"),
        ([[(0, 0), (1, 0)]], [], "polygon 0: exterior needs >= 3 distinct vertices"),
        ([[(0, 0), (1, 0), (2, 0)]], [], "polygon 0 has no area"),
        (
            [[(0, 0), (1, 0), (1, 1)], [(2, 2), (np.nan, 2), (3, 3)]],
            [],
            r"polygon 1: exterior vertex 1 is not finite",
        ),
        ([], [[1.0, 1.0, 0.0]], r"disc 0: .*radius > 0"),
        ([], [], "needs bounds"),
        # an empty pair: the fuzz run raised IndexError telling exterior-and-holes apart
        ([([], [])], [], "polygon 0: exterior must have shape"),
        ([((), [[0, 0]])], [], "polygon 0: exterior must be a list of"),
    ],
)
def test_bad_worlds_name_the_polygon(polygons, discs, match):
    with pytest.raises(MapError, match=match):
        PolygonWorld(polygons, discs)


def test_start_in_an_obstacle_is_a_planning_error():
    from wheelbase.errors import PlanningError

    planner = HybridAStar(world(), Footprint.rectangle(1.0, 0.5), 1.0)
    with pytest.raises(PlanningError, match=r"start .* is in collision"):
        planner.plan((2.5, 3.0, 0.0), (12.0, 6.0, 0.0))


def test_yaml_and_geojson_give_the_same_world(tmp_path):
    yaml_text = f"""
bounds: {list(BOUNDS)}
resolution: 0.1
polygons:
  - {[list(p) for p in L_SHAPE]}
  - exterior: {[list(p) for p in RING[0]]}
    holes: [{[list(p) for p in RING[1][0]]}]
discs: {DISCS}
"""
    (tmp_path / "w.yaml").write_text(yaml_text)
    features = [
        _feature("Polygon", [L_SHAPE]),
        _feature("MultiPolygon", [[RING[0], RING[1][0]]]),
    ] + [_feature("Point", [x, y], radius=r) for x, y, r in DISCS]
    doc = {"type": "FeatureCollection", "bbox": [0, 0, 14, 8], "resolution": 0.1}
    doc["features"] = features
    (tmp_path / "w.geojson").write_text(json.dumps(doc))
    fp = Footprint.rectangle(1.2, 0.6, 0.3)
    poses = random_poses(500, 4)
    expected = world().in_collision(fp, poses)
    for name in ("w.yaml", "w.geojson"):
        loaded = load_map(tmp_path / name)
        assert isinstance(loaded, PolygonWorld)
        np.testing.assert_array_equal(loaded.in_collision(fp, poses), expected)
    assert isinstance(load_world("parking_lot"), OccupancyGrid)


def _feature(kind: str, coordinates: list, **properties: float) -> dict:
    geometry = {"type": kind, "coordinates": coordinates}
    return {"type": "Feature", "properties": properties, "geometry": geometry}


def test_world_file_errors_name_the_field(tmp_path):
    (tmp_path / "bad.yaml").write_text("bounds: [0, 1, 0]\npolygons: []\n")
    with pytest.raises(MapError, match="bounds"):
        load_map(tmp_path / "bad.yaml")
    doc = {"type": "FeatureCollection", "features": [_feature("Point", [1, 2])]}
    (tmp_path / "bad.geojson").write_text(json.dumps(doc))
    with pytest.raises(MapError, match=r"feature 0 .*radius"):
        load_map(tmp_path / "bad.geojson")


def test_shipped_schema_matches_the_model():
    from importlib import resources

    shipped = resources.files("wheelbase") / "data" / "schemas" / "world.schema.json"
    assert json.loads(shipped.read_text()) == world_schema()


def test_bundled_worlds_load_and_their_scenarios_are_free():
    from wheelbase.planning import bundled_scenarios

    for sc in bundled_scenarios():
        if not sc.map_name.startswith(("parallel", "perpendicular", "pythonrobotics")):
            continue
        w = load_map(sc.map_name)
        assert isinstance(w, PolygonWorld)
        fp = Footprint.rectangle(*sc.footprint, sc.rear_axle_to_center)
        assert not w.in_collision(fp, np.stack([sc.start, sc.goal])).any(), sc.name
    assert math.isclose(2.8 / math.tan(0.75), 3.006, abs_tol=1e-3)


def test_with_origin_moves_the_world_and_the_plan():
    w, fp = world(), Footprint.rectangle(1.2, 0.6, 0.3)
    shift = np.array([4.5e6 + 0.25, -3.0e6 - 0.75, 0.0])
    far = w.with_origin(np.array(w.origin) + shift[:2])
    assert far.raster.shape == w.raster.shape and far.resolution == w.resolution
    poses = random_poses(2000, 5)
    near_hits = w.in_collision(fp, poses)
    far_hits = far.in_collision(fp, poses + shift)
    # only poses within rounding (1e-9 m at 4.5e6 m) of a contact may differ
    touching = w.footprint_clearance(fp, poses) < 1e-6
    assert np.all((near_hits == far_hits) | touching) and 200 < near_hits.sum() < 1800
    free = poses[~near_hits][:200]
    np.testing.assert_allclose(
        far.footprint_clearance(fp, free + shift), w.footprint_clearance(fp, free), atol=1e-6
    )
    start, goal = np.array([1.0, 1.0, 0.0]), np.array([12.0, 6.0, 0.5])
    here = HybridAStar(w, fp, 1.5).plan(start, goal)
    there = HybridAStar(far, fp, 1.5).plan(start + shift, goal + shift)
    assert here.success and there.success
    np.testing.assert_allclose(there.poses - shift, here.poses, atol=1e-6)


def test_world_raster_is_bounded_by_max_cells(tmp_path):
    with pytest.raises(MapError, match=r"2\.5e\+09 raster cells: more than max_cells"):
        PolygonWorld([], bounds=(0.0, 5000.0, 0.0, 5000.0), resolution=0.1)
    small = PolygonWorld([], bounds=(0.0, 50.0, 0.0, 20.0), resolution=0.1, max_cells=100_000)
    assert small.shape == (200, 500)
    (tmp_path / "big.yaml").write_text("bounds: [0, 100, 0, 100]\nresolution: 0.1\n")
    with pytest.raises(MapError, match="max_cells = 1000"):
        load_map(tmp_path / "big.yaml", max_cells=1000)
    assert load_map(tmp_path / "big.yaml").shape == (1000, 1000)


def test_unreadable_world_files_are_clear_errors(tmp_path):
    from wheelbase.errors import DataError

    (tmp_path / "latin.yaml").write_bytes(b"bounds: [0, 1, 0, 1]\n# caf\xe9\n")
    with pytest.raises(DataError, match="not UTF-8"):
        load_map(tmp_path / "latin.yaml")
    (tmp_path / "deep.yaml").write_text("polygons: " + "[" * 5000 + "]" * 5000 + "\n")
    with pytest.raises(MapError, match="not valid YAML"):
        load_map(tmp_path / "deep.yaml")
    (tmp_path / "bad.geojson").write_text("{")
    with pytest.raises(MapError, match="not valid GEOJSON"):
        load_map(tmp_path / "bad.geojson")


def test_a_scenario_runs_on_a_world_file(tmp_path):
    from wheelbase.report import write_report
    from wheelbase.runner import build_robot, run

    (tmp_path / "world.yaml").write_text(
        "bounds: [0.0, 12.0, 0.0, 6.0]\nresolution: 0.05\n"
        "polygons:\n  - [[5.0, 0.0], [6.0, 0.0], [6.0, 3.5], [5.0, 3.5]]\n"
        "discs:\n  - [9.0, 4.5, 0.4]\n"
    )
    scenario = {
        "name": "world_file",
        "map": str(tmp_path / "world.yaml"),
        "robot": {"model": "diffdrive", "preset": "rm100"},
        "controller": {"law": "kanayama"},
        "start": [2.0, 2.0, 0.0],
        "goal": [10.0, 2.0, 0.0],
        "trajectory": {"max_speed": 0.8, "max_acceleration": 0.8},
        "dt": 0.02,
    }
    result = run(scenario)
    m = result.metrics
    assert m["status"] == "arrived" and not m["collision"]
    # the plan goes round the wall (x in [5, 6], y < 3.5): it climbs above y = 3.5 there
    poses = result.log.true_pose[0]
    at_wall = (poses[:, 0] > 4.8) & (poses[:, 0] < 6.2)
    assert at_wall.any() and poses[at_wall, 1].min() > 3.5
    # the clearance is measured on the exact polygons
    robot = build_robot(result.scenario.robot)
    fp = Footprint.rectangle(*robot.footprint, rear_axle_to_center=robot.center_offset)
    world = load_map(tmp_path / "world.yaml")
    exact = world.footprint_clearance(fp, poses).min()  # every pose, as the metric
    assert isinstance(world, PolygonWorld) and 0 < exact < 1.0
    assert m["min_clearance_m"] == pytest.approx(exact, abs=1e-12)
    written = write_report(result, tmp_path / "report", gif=False)
    assert any(p.suffix == ".png" for p in written)
