"""Hybrid A*: exact end poses, continuous collision freedom, curvature limits, failures."""

import itertools
import math

import numpy as np
import pytest

from wheelbase.errors import ConfigError, PlanningError
from wheelbase.geometry import se2_exp, transform_points, wrap_angle
from wheelbase.planning import (
    Footprint,
    HybridAStar,
    OccupancyGrid,
    PlannedPath,
    PolygonWorld,
    smooth_path,
    write_ros_yaml,
)
from wheelbase.planning.collision import _scratch
from wheelbase.planning.escape import _arc, _move, escape
from wheelbase.planning.maps import BUNDLED_MAPS, bundled_scenarios, load_map


def densify(poses, spacing=0.02):
    """Linear interpolation in (x, y, θ) between samples (sagitta < 0.1 mm here)."""
    out = [poses[:1]]
    for a, b in itertools.pairwise(poses):
        dth = float(wrap_angle(b[2] - a[2]))
        n = max(1, math.ceil(max(math.dist(a[:2], b[:2]), abs(dth) * 3.0) / spacing))
        t = np.arange(1, n + 1)[:, None] / n
        seg = a + t * np.array([b[0] - a[0], b[1] - a[1], dth])
        out.append(seg)
    return np.concatenate(out)


def independent_collisions(grid, footprint, poses, spacing=0.02):
    """Poses whose footprint, sampled as a point lattice, touches an occupied cell."""
    return int(grid.lattice_collisions(footprint, poses, spacing).sum())


def check_path(grid, planner, path, start, goal, spacing=0.05):
    assert path.success
    np.testing.assert_allclose(path.poses[0], start, atol=1e-9)
    assert abs(path.poses[-1, 0] - goal[0]) < 1e-6 and abs(path.poses[-1, 1] - goal[1]) < 1e-6
    assert abs(float(wrap_angle(path.poses[-1, 2] - goal[2]))) < 1e-6
    assert not planner.grid.in_collision(planner.footprint, path.poses).any()
    dense = densify(path.poses, spacing)
    assert independent_collisions(grid, planner.footprint, dense, spacing) == 0
    ds = np.diff(path.arc_length)
    chords = np.hypot(*np.diff(path.poses[:, :2], axis=0).T)
    assert np.all(chords <= ds + 1e-9)
    assert path.length == pytest.approx(path.arc_length[-1])
    moving = ds > 0
    if planner.turning_radius > 0:
        assert np.all(np.abs(path.curvatures) <= 1 / planner.turning_radius + 1e-12)
        dth = wrap_angle(np.diff(path.poses[:, 2]))
        expected = path.curvatures[1:] * path.directions[1:] * ds
        np.testing.assert_allclose(dth, expected, atol=1e-9)
    assert set(np.unique(path.directions)) <= {-1, 1}
    changes = np.count_nonzero(np.diff(path.directions[1:][moving]) != 0)
    assert path.cusps == changes


def test_open_space_car_reaches_goal_exactly():
    grid = OccupancyGrid.from_array(np.zeros((150, 200), bool), 0.1)
    planner = HybridAStar(grid, (0.9, 0.5), 1.2, rear_axle_to_center=0.25)
    start, goal = np.array([3.0, 3.0, 0.0]), np.array([15.0, 10.0, math.pi / 2])
    path = planner.plan(start, goal)
    check_path(grid, planner, path, start, goal)
    assert path.stats.expanded_nodes >= 1 and path.stats.message == "goal reached"
    # in free space the analytic shot is the Reeds-Shepp path itself
    from wheelbase.planning import reeds_shepp_length

    assert path.length >= reeds_shepp_length(start, goal, 1.2) - 1e-9


def test_wall_forces_detour_and_forward_only_has_no_reverse():
    occ = np.zeros((120, 160), bool)
    occ[0:90, 78:82] = True  # a wall with a gap at the top
    grid = OccupancyGrid.from_array(occ, 0.1)
    start, goal = np.array([2.0, 2.0, 0.0]), np.array([14.0, 2.0, -math.pi / 2])
    planner = HybridAStar(grid, (0.9, 0.5), 1.0, reverse=False, rear_axle_to_center=0.25)
    path = planner.plan(start, goal)
    check_path(grid, planner, path, start, goal)
    assert np.all(path.directions == 1) and path.cusps == 0
    assert path.poses[:, 1].max() > 9.0  # went over the wall through the gap
    assert path.length > 2 * math.hypot(6.0, 7.0)  # via the gap (x = 8, y >= 9)


def test_differential_drive_turns_in_place():
    occ = np.zeros((60, 60), bool)
    occ[25:35, 0:40] = True
    grid = OccupancyGrid.from_array(occ, 0.1)
    planner = HybridAStar(grid, (0.6, 0.4), 0.0)
    start, goal = np.array([1.0, 1.0, math.pi / 2]), np.array([1.0, 5.0, -math.pi / 2])
    path = planner.plan(start, goal)
    check_path(grid, planner, path, start, goal)
    rotating = np.isinf(path.curvatures)
    assert rotating.any()
    # a turn in place does not move the reference point
    idx = np.nonzero(rotating[1:])[0] + 1
    np.testing.assert_allclose(path.poses[idx, :2], path.poses[idx - 1, :2], atol=1e-12)


@pytest.mark.parametrize("name", BUNDLED_MAPS)
def test_bundled_scenarios_all_succeed_collision_free(name):
    grid = load_map(name)
    for sc in [s for s in bundled_scenarios() if s.map_name == name]:
        planner = HybridAStar(
            grid,
            sc.footprint,
            sc.turning_radius,
            rear_axle_to_center=sc.rear_axle_to_center,
            **sc.planner,
        )
        path = planner.plan(sc.start, sc.goal)
        check_path(grid, planner, path, sc.start, sc.goal)


CAR = {"footprint": (4.69, 1.94), "rear_axle_to_center": 1.415, "turning_radius": 3.006}


def street_slot(ratio, curb=True):
    """A parallel slot ``ratio`` car lengths long between two parked 4.7 m cars 0.2 m off the
    road's edge (a curb behind them, or open pavement), a 5.5 m lane; the poses in the middle
    of the slot and in the lane past it (the rule of benchmarks/parking.py)."""
    length, r2c = CAR["footprint"][0], CAR["rear_axle_to_center"]
    s0 = 1.0 + 4.7
    s1 = s0 + ratio * length
    x_max = s1 + 4.7 + 6.0
    polygons = [
        [(1.0, 0.2), (s0, 0.2), (s0, 2.1), (1.0, 2.1)],
        [(s1, 0.2), (s1 + 4.7, 0.2), (s1 + 4.7, 2.1), (s1, 2.1)],
    ]
    if curb:
        polygons.append([(0.0, -0.3), (x_max, -0.3), (x_max, 0.0), (0.0, 0.0)])
    world = PolygonWorld(polygons, bounds=(0.0, x_max, -0.3 if curb else -3.0, 7.6),
                         resolution=0.05)  # fmt: skip
    parked = np.array([(s0 + s1) / 2 - r2c, 1.15, 0.0])
    lane = np.array([s1 + 1.0 + length / 2 - r2c, 2.1 + 0.5 + 0.97, 0.0])
    return world, parked, lane


def test_defaults_leave_and_enter_a_tight_slot():
    """A slot 1.3 car lengths long behind a curb, with the planner's defaults: out of the slot
    to the lane (a tight start, a free goal) and into it (the reverse). The automatic end is
    the slot, which the lattice of whole primitives cannot leave (exhausted after one
    expansion); the plan must not do worse than either end: it goes on with moves to contact
    from the slot, and without them (moves_to_contact=False) from the lane."""
    world, parked, lane = street_slot(1.3)
    for start, goal in ((parked, lane), (lane, parked)):
        for options in ({}, {"moves_to_contact": False}):
            planner = HybridAStar(world, **CAR, smooth=False, **options)
            path = planner.plan(start, goal)
            check_path(world, planner, path, start, goal)
        # either end alone, with whole primitives only: the slot's fails, the lane's succeeds
        ends = {
            side: HybridAStar(world, **CAR, search_from=side, moves_to_contact=False).plan(
                start, goal
            )
            for side in ("start", "goal")
        }
        slot = "start" if start is parked else "goal"
        assert ends[slot].stats.message == "search space exhausted"
        assert ends["goal" if slot == "start" else "start"].success


def test_defaults_leave_a_slot_1_10_car_lengths_long():
    """0.47 m to spare behind a curb: the default lattice (0.485 m bins) is exhausted from
    both ends, cut moves too; the escape by moves to contact takes the car out and in."""
    world, parked, lane = street_slot(1.1)
    for start, goal in ((parked, lane), (lane, parked)):
        planner = HybridAStar(world, **CAR)
        path = planner.plan(start, goal)
        check_path(world, planner, path, start, goal)
        assert path.cusps >= 10


def test_moves_to_contact_leaves_what_the_lattice_solves_unchanged():
    """Moves to contact run only where the lattice of whole primitives found nothing: where it
    finds a path, the path and the expansions are the same with them on or off."""
    world, parked, lane = street_slot(1.6, curb=False)
    sc = next(s for s in bundled_scenarios() if s.name == "reverse_into_bay")
    lot = load_map(sc.map_name)
    lot_car = {"footprint": sc.footprint, "rear_axle_to_center": sc.rear_axle_to_center,
               "turning_radius": sc.turning_radius}  # fmt: skip
    for grid, car, start, goal in (
        (world, CAR, parked, lane),
        (world, CAR, lane, parked),
        (lot, lot_car, sc.start, sc.goal),
    ):
        on, off = (
            HybridAStar(grid, **car, moves_to_contact=flag).plan(start, goal)
            for flag in (True, False)
        )
        assert on.success and off.success
        np.testing.assert_array_equal(on.poses, off.poses)
        assert on.stats.expanded_nodes == off.stats.expanded_nodes


def test_a_move_to_contact_keeps_its_margin_and_ends_at_contact():
    """The escape's moves (sphere tracing on the exact clearance, then samples): every pose of a
    move keeps the margin less half a sample's sweep, and one step past its end does not."""
    world, parked, _ = street_slot(1.1)
    fp = Footprint.rectangle(*CAR["footprint"], CAR["rear_axle_to_center"])
    radius, step, margin = CAR["turning_radius"], 0.005, 0.006
    rho = fp.max_radius
    box = np.array(world.bounds)
    scratch = _scratch(world._kernel_world, fp.polygon)
    shape = (world._kernel_world, fp.polygon, fp.circles, fp.circle_radius)
    rng = np.random.default_rng(3)
    stopped = 0
    for _ in range(12):
        pose = parked + np.array([rng.uniform(-0.2, 0.2), rng.uniform(-0.1, 0.1),
                                  rng.uniform(-0.1, 0.1)])  # fmt: skip
        if world.footprint_clearance(fp, pose) < margin:
            continue
        for d, k in itertools.product((1, -1), (1, 0, -1)):
            kappa = k / radius
            length, free = _move(*shape, box, *pose, d, kappa, 2.0, margin, rho, step, *scratch)
            s = np.linspace(0.0, length, 400)
            clear = world.footprint_clearance(fp, _arc(pose, kappa, d * s))
            assert clear.min() >= margin - step * (1 + rho * abs(kappa)) / 2 - 1e-9
            if not free:
                stopped += 1
                beyond = _arc(pose, kappa, d * (length + np.linspace(0.0, step, 50)))
                assert world.footprint_clearance(fp, beyond).min() < margin + 1e-9
    assert stopped > 20


def test_moves_to_contact_park_in_a_slot_1_15_car_lengths_long():
    """Out of a 1.15-car-length slot takes 13 moves, most shorter than a motion primitive: cut
    at contact. Without them the search runs out of states; with them the path is exact at
    the ends and collision-free (an independent point-lattice check at 2 cm)."""
    sc = next(s for s in bundled_scenarios() if s.name == "parallel_115_out")
    world = load_map(sc.map_name)
    options = {**sc.planner, "smooth": False}
    assert options.pop("moves_to_contact") is True
    kwargs = {"rear_axle_to_center": sc.rear_axle_to_center, **options}
    # the lattice of whole primitives from the slot (from the lane it explores the whole map
    # for seconds before it exhausts)
    without = HybridAStar(
        world, sc.footprint, sc.turning_radius, moves_to_contact=False, search_from="start",
        **kwargs,
    )  # fmt: skip
    assert without.plan(sc.start, sc.goal).stats.message == "search space exhausted"
    planner = HybridAStar(world, sc.footprint, sc.turning_radius, **kwargs)  # the default
    path = planner.plan(sc.start, sc.goal)
    check_path(world, planner, path, sc.start, sc.goal, spacing=0.02)
    assert path.cusps >= 9
    # moves (between cusps) shorter than one primitive: only cut moves are that short
    bounds = [0, *path.cusp_indices, len(path.poses) - 1]
    moves = np.diff(path.arc_length[bounds])
    assert np.sum(moves < planner.primitive_length - 1e-9) >= 3


def test_a_slot_1_10_car_lengths_long_is_left_by_moves_to_contact():
    """The lattice cannot hold the centimetre moves out of a 1.10 slot (0.47 m to spare): the
    escape searches them on continuous poses, each certified clear of the obstacles and of the
    map's edge by the planner's margin, and the lattice goes on from outside, into the slot
    (driven backwards) as out of it."""
    sc = next(s for s in bundled_scenarios() if s.name == "parallel_110_out")
    world = load_map(sc.map_name)
    footprint = Footprint.rectangle(*sc.footprint, sc.rear_axle_to_center)
    margin = 0.015
    exits, expanded = escape(
        world, footprint, sc.turning_radius, np.array(sc.start), np.array(sc.goal),
        step=0.02, margin=margin,
    )  # fmt: skip
    way_out = exits[0]
    np.testing.assert_array_equal(way_out.poses[0], sc.start)
    assert np.all(world.footprint_clearance(footprint, way_out.poses[1:]) >= margin - 1e-12)
    assert not world.in_collision(footprint, way_out.poses).any()
    assert np.all(np.diff(way_out.arc_length) <= 0.02 + 1e-12)
    assert way_out.cusps >= 30 and expanded > 100
    # out: the footprint at the end reaches past the parked cars into the lane
    corners = transform_points(way_out.poses[-1], footprint.polygon)
    assert corners[:, 1].max() > 0.2 + sc.footprint[1] + 0.5
    options = {k: v for k, v in sc.planner.items() if k != "moves_to_contact"}
    # into the slot: the escape from the goal, driven backwards (the bundled-scenario test
    # plans both cases with smoothing)
    for name in ("parallel_110_in",):
        case = next(s for s in bundled_scenarios() if s.name == name)
        planner = HybridAStar(
            world, case.footprint, case.turning_radius, moves_to_contact=True, smooth=False,
            rear_axle_to_center=case.rear_axle_to_center, **options,
        )  # fmt: skip
        path = planner.plan(case.start, case.goal)
        check_path(world, planner, path, case.start, case.goal, spacing=0.02)
        assert path.cusps >= 30
        without = HybridAStar(
            world, case.footprint, case.turning_radius, moves_to_contact=False,
            search_from="goal", rear_axle_to_center=case.rear_axle_to_center, **options,
        )  # fmt: skip
        assert without.plan(case.start, case.goal).stats.message == "search space exhausted"
        # the one time limit covers the lattice, the escape and the lattice after it
        hurried = HybridAStar(
            world, case.footprint, case.turning_radius, moves_to_contact=True, time_limit=0.05,
            rear_axle_to_center=case.rear_axle_to_center, **options,
        )  # fmt: skip
        assert hurried.plan(case.start, case.goal).stats.message == "time limit reached"


def test_escape_in_the_open_is_the_start_and_bad_settings_are_clear_errors():
    # its arcs are se2_exp's, written out for one pose and one curvature
    s = np.linspace(-2.0, 2.0, 41)
    for kappa in (0.0, 0.33, -1.2):
        pose = np.array([1.0, -2.0, 2.9])
        exact = se2_exp(pose, np.stack([s, 0 * s, kappa * s], -1), 1.0)
        arc = _arc(pose, kappa, s)
        np.testing.assert_allclose(arc[:, :2], exact[:, :2], atol=1e-12)
        np.testing.assert_allclose(wrap_angle(arc[:, 2] - exact[:, 2]), 0.0, atol=1e-12)
    grid = OccupancyGrid.from_array(np.zeros((50, 50), bool), 0.1)
    footprint = Footprint.rectangle(1.0, 0.5, 0.2)
    exits, expanded = escape(grid, footprint, 1.0, [2.0, 2.0, 0.0], [4.0, 4.0, 0.0],
                             step=0.02, margin=0.01)  # fmt: skip
    assert expanded == 1 and exits[0].poses.tolist() == [[2.0, 2.0, 0.0]]
    for bad, words in (
        ({"step": 1e-12}, "samples per move"),
        ({"spacing": 1e-12}, "spacing 1e-12 m asks"),
        ({"margin": -1.0}, "margin"),
        ({"turning_radius": 0.0}, "turning_radius"),
        ({"exits": 0}, "exits"),
    ):
        kwargs = {"turning_radius": 1.0, "step": 0.02, "margin": 0.01, **bad}
        radius = kwargs.pop("turning_radius")
        with pytest.raises(ConfigError, match=words):
            escape(grid, footprint, radius, [2.0, 2.0, 0.0], [4.0, 4.0, 0.0], **kwargs)


def test_search_from_goal_returns_the_same_kind_of_path():
    """Searching from the goal and driving the result backwards gives a valid path from the
    start with the same cost model (the gears' costs swapped in the search)."""
    sc = next(s for s in bundled_scenarios() if s.name == "reverse_into_bay")
    grid = load_map(sc.map_name)
    costs = {}
    for side in ("start", "goal"):
        planner = HybridAStar(
            grid, sc.footprint, sc.turning_radius, rear_axle_to_center=sc.rear_axle_to_center,
            search_from=side, smooth=False,
        )  # fmt: skip
        path = planner.plan(sc.start, sc.goal)
        check_path(grid, planner, path, sc.start, sc.goal)
        ds = np.diff(path.arc_length)
        backward = path.directions[1:] < 0
        costs[side] = float(np.sum(ds * np.where(backward, 2.0, 1.0)))
    # both searches are optimal on nearly the same lattice: similar costs, neither much worse
    assert costs["goal"] == pytest.approx(costs["start"], rel=0.15)


def test_holonomic_heuristic_never_exceeds_the_path_found():
    """The heuristic at the start is a lower bound on the length of any path (here the path
    that the length objective finds); the 8-connected distance it replaced was not."""
    grid = load_map("warehouse")
    fp = Footprint.rectangle(1.6, 1.0, 0.5)
    planner = HybridAStar(
        grid, fp, 1.5, reverse_penalty=1.0, non_straight_penalty=1.0, switch_penalty=0.0,
        time_limit=2.0,
    )  # fmt: skip
    rng = np.random.default_rng(5)
    checked = 0
    while checked < 15:
        poses = np.column_stack(
            [rng.uniform(0, 30, 2), rng.uniform(0, 20, 2), rng.uniform(-np.pi, np.pi, 2)]
        )
        if grid.in_collision(fp, poses).any():
            continue
        path = planner.plan(poses[0], poses[1])
        if not path.success:
            continue
        hgrid, hres = planner._holonomic_heuristic(poses[1])
        cell = (
            ((poses[0, 1:2] - grid.origin[1]) // hres).astype(int),
            ((poses[0, 0:1] - grid.origin[0]) // hres).astype(int),
        )
        assert hgrid[cell[0][0], cell[1][0]] <= path.length + 1e-9
        checked += 1


def test_full_heuristic_never_exceeds_the_cost_of_the_path_found():
    """With the default costs (arcs ×1.2, reverse ×2, 2 m a cusp) the heuristic, heading term
    included, is below the cost of every path found: it is admissible there too."""
    from wheelbase.planning.hybrid_heuristic import _MODE_RS, _heuristic
    from wheelbase.planning.reeds_shepp import _FAMILIES

    sc = next(s for s in bundled_scenarios() if s.name == "bay_to_bay")
    grid = load_map(sc.map_name)
    fp = Footprint.rectangle(*sc.footprint, sc.rear_axle_to_center)
    planner = HybridAStar(grid, fp, sc.turning_radius, smooth=False, search_from="start")
    rng = np.random.default_rng(7)
    checked = 0
    while checked < 6:
        poses = np.column_stack(
            [rng.uniform(2, 38, 2), rng.uniform(2, 28, 2), rng.uniform(-np.pi, np.pi, 2)]
        )
        if grid.in_collision(fp, poses).any():
            continue
        path = planner.plan(poses[0], poses[1])
        if not path.success:
            continue
        ds = np.diff(path.arc_length)
        arcs = np.isfinite(path.curvatures[1:]) & (path.curvatures[1:] != 0)
        cost = np.sum(ds * np.where(arcs, 1.2, 1.0) * np.where(path.directions[1:] < 0, 2, 1))
        cost += 2.0 * path.cusps
        hgrid, hres = planner._holonomic_heuristic(poses[1])
        h = _heuristic(
            *poses[0], *poses[1], _MODE_RS, sc.turning_radius, _FAMILIES, hgrid, hres,
            *grid.origin, planner._turn_cost,
        )  # fmt: skip
        assert planner._turn_cost == pytest.approx(0.2 * sc.turning_radius)
        assert 0 < h <= cost + 1e-9
        checked += 1


def test_reeds_shepp_length_is_at_most_the_distance_plus_pi_r():
    """The bound that lets the search skip the curve length where the obstacle distance is
    larger: turn to face the goal (or away), drive straight, turn to its heading; each turn in
    place costs |angle|·R (L+R−L+) and the two add up to at most π."""
    from wheelbase.planning import reeds_shepp_length

    rng = np.random.default_rng(3)
    worst = 0.0
    for _ in range(3000):
        xy = rng.uniform(-6, 6, 2) * rng.choice([0.01, 0.3, 1.0])
        heads = rng.uniform(-np.pi, np.pi, 2)
        excess = reeds_shepp_length((0, 0, heads[0]), (*xy, heads[1]), 1.0) - np.hypot(*xy)
        worst = max(worst, excess)
    assert worst <= math.pi + 1e-9
    assert worst > 2.5  # the bound is nearly reached: it is not loose by much
    # a turn in place costs exactly |angle|·R
    assert reeds_shepp_length((0, 0, 0), (0, 0, 2.0), 1.5) == pytest.approx(3.0)


def test_random_queries_independent_collision_check():
    """A few seconds' worth of the 1,000-query benchmark (benchmarks/planning.py)."""
    grid = load_map("warehouse")
    fp = Footprint.rectangle(1.6, 1.0, 0.5)
    planner = HybridAStar(grid, fp, 1.5, rear_axle_to_center=0.5, time_limit=1.0)
    rng = np.random.default_rng(11)
    found = 0
    while found < 25:
        poses = np.column_stack(
            [rng.uniform(1, 29, 2), rng.uniform(1, 19, 2), rng.uniform(-np.pi, np.pi, 2)]
        )
        if grid.in_collision(fp, poses).any():
            continue
        path = planner.plan(poses[0], poses[1])
        if path.success:
            found += 1
            assert independent_collisions(grid, fp, densify(path.poses, 0.03), 0.03) == 0


def test_unreachable_goal_returns_failure_with_statistics():
    occ = np.zeros((60, 60), bool)
    occ[35:37, 30:60] = True
    occ[35:60, 30:32] = True  # the goal corner is walled off
    grid = OccupancyGrid.from_array(occ, 0.1)
    planner = HybridAStar(grid, (0.6, 0.4), 0.8)
    path = planner.plan((1.0, 1.0, 0.0), (4.5, 4.8, 0.0))
    assert not path.success and len(path) == 0 and math.isinf(path.length)
    assert path.stats.message == "search space exhausted"
    walled = np.zeros((60, 60), bool)
    walled[0:50, 20:22] = True
    limited = HybridAStar(OccupancyGrid.from_array(walled, 0.1), (0.6, 0.4), 0.8, max_iterations=5)
    result = limited.plan((1.0, 1.0, math.pi / 2), (3.5, 1.0, -math.pi / 2))
    assert not result.success and result.stats.message == "iteration limit reached"


def test_start_goal_and_parameter_errors():
    occ = np.zeros((50, 50), bool)
    occ[20:30, 20:30] = True
    grid = OccupancyGrid.from_array(occ, 0.1)
    planner = HybridAStar(grid, (0.6, 0.4), 1.0)
    with pytest.raises(PlanningError, match=r"start .* in collision"):
        planner.plan((2.5, 2.5, 0.0), (1.0, 1.0, 0.0))
    with pytest.raises(PlanningError, match=r"goal .* outside the map"):
        planner.plan((1.0, 1.0, 0.0), (9.0, 1.0, 0.0))
    with pytest.raises(PlanningError, match=r"goal .* in collision"):
        planner.plan((1.0, 1.0, 0.0), (4.8, 1.0, 0.0))  # the footprint leaves the map
    with pytest.raises(ConfigError, match="turning_radius"):
        HybridAStar(grid, (0.6, 0.4), -1.0)
    with pytest.raises(ConfigError, match="footprint"):
        HybridAStar(grid, (0.6, 0.4, 1.0), 1.0)
    with pytest.raises(ConfigError, match="curvatures"):
        HybridAStar(grid, (0.6, 0.4), 1.0, curvatures=4)
    with pytest.raises(ConfigError, match="reverse_penalty"):
        HybridAStar(grid, (0.6, 0.4), 1.0, reverse_penalty=0.5)


@pytest.mark.parametrize(
    ("options", "match"),
    [
        ({"headings": math.inf}, r"headings must be an integer >= 8 \(got inf\)"),
        ({"headings": math.nan}, r"headings must be an integer >= 8 \(got nan\)"),
        ({"headings": "abc"}, r"headings must be an integer >= 8 \(got 'abc'\)"),
        ({"headings": 72.5}, r"headings must be an integer >= 8 \(got 72.5\)"),
        ({"curvatures": math.inf}, r"curvatures must be an odd integer >= 3 \(got inf\)"),
        ({"max_iterations": math.inf}, r"max_iterations must be an integer >= 1 \(got inf\)"),
        ({"max_iterations": "x"}, r"max_iterations must be an integer >= 1 \(got 'x'\)"),
        ({"reverse": "no"}, r"reverse must be true or false \(got 'no'\)"),
        ({"smooth": 1}, r"smooth must be true or false \(got 1\)"),
        ({"time_limit": "abc"}, r"time_limit must be a real number s \(got 'abc'\)"),
        ({"footprint": "abc"}, r"footprint must be \(length, width\) \[m\] \(got 'abc'\)"),
        ({"footprint": (1e9, 1e6)}, r"footprint reaches 5e\+08 m from its reference point.*"),
        ({"footprint": (1e9, 0.5)}, r"covering it needs more than 10000 circles"),
        ({"xy_resolution": 1e-3}, r"1.8e\+09 state bins.*max_state_bins = 50000000"),
        ({"max_state_bins": 0}, r"max_state_bins must be an integer >= 1"),
        ({"headings": 10**400}, r"1e\+400 headings give 2.5e\+403 state bins"),
        (
            {"headings": 4.49423283715579e305},
            r"4.49e\+305 headings give 1.12e\+309 state bins",
        ),  # int too large for :g
    ],
)
def test_constructor_errors_name_the_option(options, match):
    grid = OccupancyGrid.from_array(np.zeros((50, 50), bool), 0.1)
    arguments = {"footprint": (0.6, 0.4), "turning_radius": 1.0, **options}
    with pytest.raises(ConfigError, match=match):
        HybridAStar(grid, **arguments)


def test_state_bin_limit_can_be_raised():
    grid = OccupancyGrid.from_array(np.zeros((50, 50), bool), 0.1)
    planner = HybridAStar(grid, (0.6, 0.4), 1.0, xy_resolution=0.02, max_state_bins=10**7)
    assert planner._nx * planner._ny * planner.headings == 250 * 250 * 72


def test_huge_turning_radius_builds_primitives_no_longer_than_the_map():
    # R = 1e9 m asked for 1.7e9 collision samples per primitive (a hang, then MemoryError);
    # a primitive longer than the map's diagonal can never stay in it: they are cut there.
    grid = OccupancyGrid.from_array(np.zeros((50, 50), bool), 0.1)
    planner = HybridAStar(grid, (0.6, 0.4), 1e9)
    assert planner.primitive_length == pytest.approx(math.hypot(5.0, 5.0))
    path = planner.plan((1.0, 2.5, 0.0), (4.0, 2.5, 0.0))  # a straight line still works
    assert path.success and path.poses[-1, 0] == pytest.approx(4.0)


def _roughness(path):
    k = path.curvatures[np.isfinite(path.curvatures)]
    return float(np.sum(np.diff(k) ** 2))


def test_smoothing_keeps_ends_cusps_curvature_and_reduces_roughness():
    grid = load_map("parking_lot")
    sc = next(s for s in bundled_scenarios() if s.name == "bay_to_bay")
    raw_planner = HybridAStar(
        grid,
        sc.footprint,
        sc.turning_radius,
        rear_axle_to_center=sc.rear_axle_to_center,
        smooth=False,
    )
    raw = raw_planner.plan(sc.start, sc.goal)
    smooth = smooth_path(raw, grid, raw_planner.footprint, sc.turning_radius)
    check_path(grid, raw_planner, smooth, sc.start, sc.goal)
    assert smooth.cusps == raw.cusps
    np.testing.assert_array_equal(smooth.cusp_indices, raw.cusp_indices)
    np.testing.assert_allclose(smooth.poses[raw.cusp_indices], raw.poses[raw.cusp_indices])
    assert _roughness(smooth) < 0.5 * _roughness(raw)
    assert np.abs(smooth.poses[:, :2] - raw.poses[:, :2]).max() > 0.01  # it did move
    # the planner's default applies the same smoothing
    planned = HybridAStar(
        grid, sc.footprint, sc.turning_radius, rear_axle_to_center=sc.rear_axle_to_center
    ).plan(sc.start, sc.goal)
    np.testing.assert_allclose(planned.poses, smooth.poses, atol=1e-12)


def test_smoothing_leaves_turns_in_place_and_failures_alone():
    grid = load_map("maze")
    sc = next(s for s in bundled_scenarios() if s.name == "maze_middle")
    planner = HybridAStar(grid, sc.footprint, 0.0, smooth=False)
    raw = planner.plan(sc.start, sc.goal)
    smooth = smooth_path(raw, grid, planner.footprint, 0.0)
    np.testing.assert_allclose(smooth.poses, raw.poses)
    failed = PlannedPath.failure(raw.stats)
    assert smooth_path(failed, grid, planner.footprint, 1.0) is failed
    with pytest.raises(ConfigError, match="window"):
        smooth_path(raw, grid, planner.footprint, 1.0, window=0.0)


def test_goal_tolerance_accepts_a_nearby_state():
    occ = np.zeros((80, 80), bool)
    occ[40:42, 0:60] = True
    grid = OccupancyGrid.from_array(occ, 0.1)
    goal = np.array([2.0, 6.0, math.pi])
    exact = HybridAStar(grid, (0.6, 0.4), 0.8, smooth=False, search_from="start")
    exact = exact.plan((2.0, 2.0, 0.0), goal)
    loose = HybridAStar(
        grid, (0.6, 0.4), 0.8, xy_goal_tolerance=0.6, yaw_goal_tolerance=0.4, smooth=False
    ).plan((2.0, 2.0, 0.0), goal)
    assert exact.success and loose.success
    end = loose.poses[-1]
    assert math.dist(end[:2], goal[:2]) <= 0.6 + 1e-9
    assert abs(float(wrap_angle(end[2] - goal[2]))) <= 0.4 + 1e-9
    assert loose.stats.expanded_nodes <= exact.stats.expanded_nodes


def test_load_map_by_name_and_path(tmp_path):
    grid = load_map("parking_lot")
    assert grid.shape == (300, 400) and grid.resolution == pytest.approx(0.1)
    write_ros_yaml(grid, tmp_path / "copy.yaml")
    np.testing.assert_array_equal(load_map(tmp_path / "copy.yaml").occupied, grid.occupied)
    with pytest.raises(ConfigError, match="map"):
        load_map("atlantis")
    names = {s.map_name for s in bundled_scenarios()}
    assert names == set(BUNDLED_MAPS)


def test_search_kernel_takes_no_int_of_infinity(monkeypatch):
    # Compiled, int(inf) is undefined behaviour (LLVM's fptosi of inf is poison); run the
    # kernel's Python code, where it raises OverflowError, on a start boxed in away from the
    # goal: its heuristic is inf, and the search must still end cleanly. (The planner does
    # not even start the search there: the holonomic bound already says no path exists.)
    from wheelbase.planning import hybrid_astar
    from wheelbase.planning.hybrid_heuristic import _MODE_POINT

    monkeypatch.setattr(hybrid_astar, "_search", hybrid_astar._search.py_func)
    occ = np.zeros((40, 40), bool)
    occ[5:15, 5] = occ[5:15, 15] = occ[5, 5:16] = occ[15, 5:16] = True  # a closed box
    planner = HybridAStar(OccupancyGrid.from_array(occ, 0.1), (0.3, 0.2), 0.0)
    start, goal = np.array([1.0, 1.0, 0.0]), np.array([3.0, 3.0, 0.0])
    hgrid, hres = planner._holonomic_heuristic(goal)
    assert np.isinf(hgrid[int(start[1] // hres), int(start[0] // hres)])
    out = planner._lattice(start, goal, hgrid, hres, planner._prims, _MODE_POINT, 5.0, 10**6, True)
    assert out.status == 1 and out.expanded == 1
    path = planner.plan(start, goal)
    assert not path.success and path.stats.message == "search space exhausted"


FAR = 4.5e9  # m; start and goal below are exact in float64 there (multiples of 2^-20 m)


@pytest.mark.parametrize(("radius", "reverse"), [(1.0, True), (1.0, False), (0.0, True)])
def test_same_path_at_a_4_5e9_m_offset(radius, reverse):
    # Coordinates up to 1e10 m (UTM-like and beyond): the plan, smoothing included, at 4.5e9 m
    # is the plan at the origin moved there (to 1e-6 of its length).
    occ = np.zeros((60, 80), bool)
    occ[20:45, 35:40] = True
    near_grid = OccupancyGrid.from_array(occ, 0.1)
    far_grid = OccupancyGrid.from_array(occ, 0.1, origin=(FAR, FAR))
    start, goal = np.array([1.5, 1.5, 0.0]), np.array([6.5, 4.5, math.pi / 2])
    if radius > 0:  # goals whose plan the smoother changes (it keeps paths that hug the block)
        goal = np.array([6.5, 5.0, -math.pi / 2] if reverse else [6.5, 2.0, math.pi])
    shift = np.array([FAR, FAR, 0.0])
    paths = []
    for grid, offset in ((near_grid, 0.0), (far_grid, 1.0)):
        planner = HybridAStar(grid, (0.6, 0.4), radius, reverse=reverse)
        path = planner.plan(start + offset * shift, goal + offset * shift)
        assert path.success
        paths.append(path)
    near, far = paths
    assert far.poses.shape == near.poses.shape
    tolerance = 1e-6 * near.length
    np.testing.assert_allclose(far.poses[:, :2] - FAR, near.poses[:, :2], atol=tolerance)
    np.testing.assert_allclose(wrap_angle(far.poses[:, 2] - near.poses[:, 2]), 0.0, atol=1e-6)
    np.testing.assert_allclose(far.arc_length, near.arc_length, atol=tolerance)
    np.testing.assert_array_equal(far.directions, near.directions)
    # smoothing happened far away too (it needed a 1e-9 m end match, and skipped at 4.5e9 m)
    raw = HybridAStar(near_grid, (0.6, 0.4), radius, reverse=reverse, smooth=False)
    if radius > 0:
        assert not np.allclose(raw.plan(start, goal).poses, near.poses)


def test_smoothing_is_the_same_at_a_4_5e9_m_offset():
    # smooth_path on its own (a user's raw path far from the origin): its end match works in
    # the segment's frame with a tolerance relative to the segment's length.
    occ = np.zeros((60, 80), bool)
    occ[20:45, 35:40] = True
    near_grid = OccupancyGrid.from_array(occ, 0.1)
    far_grid = OccupancyGrid.from_array(occ, 0.1, origin=(FAR, FAR))
    planner = HybridAStar(near_grid, (0.6, 0.4), 1.0, smooth=False)
    raw = planner.plan((1.5, 1.5, 0.0), (6.5, 5.0, -math.pi / 2))
    shift = np.array([FAR, FAR, 0.0])
    moved = PlannedPath(raw.poses + shift, raw.directions, raw.curvatures, raw.arc_length, True)
    near = smooth_path(raw, near_grid, planner.footprint, 1.0)
    far = smooth_path(moved, far_grid, planner.footprint, 1.0)
    assert not np.allclose(near.poses, raw.poses)  # smoothing did something
    np.testing.assert_allclose(far.poses[:, :2] - FAR, near.poses[:, :2], atol=1e-6 * raw.length)
    # float64 keeps 5e-7 m at 4.5e9 m: matching a 0.2 m segment's end to that turns headings
    # by up to ~1e-5 rad
    np.testing.assert_allclose(wrap_angle(far.poses[:, 2] - near.poses[:, 2]), 0.0, atol=1e-4)
    np.testing.assert_allclose(far.curvatures, near.curvatures, atol=1e-4)  # 1/m, likewise


def test_xy_resolution_larger_than_the_map():
    # 1.8e9 m bins: the heuristic's coarse grid padded the map to 1.8e10 cells a side
    grid = OccupancyGrid.from_array(np.zeros((40, 40), bool), 0.1)
    planner = HybridAStar(grid, (0.4, 0.3), 0.5, xy_resolution=1834191526.0, time_limit=1.0)
    path = planner.plan((1.0, 1.0, 0.0), (3.0, 2.0, 1.0))
    assert path.success  # one bin: the analytic shot from the start


@pytest.mark.parametrize(
    ("options", "match"),
    [
        ({"curvatures": 34247999}, r"68495998 motion primitives .* more than 1e\+07"),
        ({"collision_step": 1e-9}, r"samples: more than 1e\+07; use fewer curvatures or a larger"),
    ],
)
def test_primitive_table_is_bounded(options, match):
    # curvatures = 3.4e7 hung in the constructor (found by tests/test_fuzz.py)
    grid = OccupancyGrid.from_array(np.zeros((40, 40), bool), 0.1)
    with pytest.raises(ConfigError, match=match):
        HybridAStar(grid, (0.4, 0.3), 0.5, **options)
