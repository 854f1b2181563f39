"""Generate the bundled planning maps (ROS ``map_server`` YAML + PNG) and their scenarios.

Run ``python src/wheelbase/data/maps/make_maps.py`` to rebuild them; the output is
deterministic. Each map is drawn with axis-aligned rectangles in world coordinates [m]:

* ``parking_lot``: 40 × 30 m at 0.1 m, three rows of 5 m bays with parked cars and free bays,
  7 m aisles; a car drives from the entrance into a bay (forward and reverse parking).
* ``corridor_uturn``: 30 × 14 m, two 4 m corridors joined by a 12 m turning area; a car drives
  out along one and back along the other.
* ``maze``: 20 × 20 m at 0.1 m with 2 m corridors for a differential-drive robot (RM100
  size, turning in place).
* ``warehouse``: 30 × 20 m at 0.1 m, racks with 2.4 m aisles for a small car-like tug.
* ``room20``: an empty walled 20 × 20 m room at 0.05 m (the crowd-crossing benchmark's).
* ``doorway``: 12 × 6 m at 0.05 m, two rooms joined by a 1.2 m door in a 0.2 m wall.
* ``corridor_bay``: a 1.2 m corridor 16 m long at 0.05 m with one passing bay (2.5 m long,
  1.4 m deeper on one side) in the middle: two robots 0.7 m wide cannot pass elsewhere.

and the polygon worlds (world YAML, :mod:`wheelbase.planning.world_io`):

* ``parallel_110`` … ``parallel_150``: parallel parking between two parked cars with a curb
  behind, slots 1.1 to 1.5 car lengths, into the slot and out again;
* ``perpendicular_bay``: reversing into a bay 0.5 m wider than the car from a 5.5 m aisle, and
  out again;
* ``pythonrobotics_maze``: the 60 × 60 m map of the PythonRobotics Hybrid A* demo with its car.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import yaml

from wheelbase.planning import OccupancyGrid, write_ros_yaml

HERE = Path(__file__).resolve().parent


def _canvas(width: float, height: float, res: float) -> np.ndarray:
    occ = np.zeros((round(height / res), round(width / res)), bool)
    occ[0, :] = occ[-1, :] = occ[:, 0] = occ[:, -1] = True
    return occ


def _box(occ: np.ndarray, res: float, x0: float, y0: float, x1: float, y1: float) -> None:
    occ[round(y0 / res) : round(y1 / res), round(x0 / res) : round(x1 / res)] = True


def parking_lot() -> tuple[np.ndarray, float, list[dict]]:
    res = 0.1
    occ = _canvas(40.0, 30.0, res)
    bay_w, car_l, car_w = 2.6, 4.6, 1.9
    # rows of 5 m deep bays: A (y 0.5-5.5) faces aisle 1 (y 5.5-12.5); B (12.5-17.5) and C
    # (17.5-22.5) are back to back, B facing aisle 1 and C facing aisle 2 (22.5-29.5)
    rows = {"A": (0.5, 5.5), "B": (12.5, 17.5), "C": (17.5, 22.5)}
    free_bays = {("A", 2), ("A", 9), ("B", 3), ("C", 5), ("C", 10)}
    for row, (y0, y1) in rows.items():
        for k in range(12):
            if (row, k) in free_bays:
                continue
            x = 6.0 + k * bay_w + (bay_w - car_w) / 2
            yc = (y0 + y1) / 2
            _box(occ, res, x, yc - car_l / 2, x + car_w, yc + car_l / 2)
    _box(occ, res, 6.0, 17.4, 37.2, 17.6)  # kerb between rows B and C
    car = {"footprint": [4.5, 1.8], "rear_axle_to_center": 1.35, "turning_radius": 5.0}

    def bay(k: int) -> float:
        return 6.0 + k * bay_w + bay_w / 2

    scenarios = [
        {
            "name": "enter_and_park_forward",
            "start": [2.5, 9.0, 0.0],
            "goal": [bay(9), 4.5, -90.0],
            **car,
        },
        {
            "name": "reverse_into_bay",
            "start": [2.5, 9.0, 0.0],
            "goal": [bay(3), 16.3, -90.0],
            **car,
        },
        {"name": "bay_to_bay", "start": [bay(5), 21.5, -90.0], "goal": [bay(2), 1.5, 90.0], **car},
    ]
    return occ, res, scenarios


def corridor_uturn() -> tuple[np.ndarray, float, list[dict]]:
    res = 0.1
    occ = _canvas(30.0, 14.0, res)
    _box(occ, res, 0.0, 5.0, 18.0, 9.0)  # the divider between the two 4 m corridors
    car = {"footprint": [4.5, 1.8], "rear_axle_to_center": 1.35, "turning_radius": 5.0}
    scenarios = [
        {"name": "u_turn", "start": [3.0, 3.0, 0.0], "goal": [5.0, 11.0, 180.0], **car},
    ]
    return occ, res, scenarios


def maze() -> tuple[np.ndarray, float, list[dict]]:
    res = 0.1
    occ = _canvas(20.0, 20.0, res)
    t = 0.3  # wall thickness
    for i, y in enumerate((4.0, 8.0, 12.0, 16.0)):
        if i % 2 == 0:
            _box(occ, res, 0.0, y, 17.0, y + t)  # gap on the right
        else:
            _box(occ, res, 3.0, y, 20.0, y + t)  # gap on the left
    # a stub in every corridor: each corridor, its gaps at opposite ends, is otherwise the same
    # turned by a half turn about its centre, and a lidar inside could not tell a pose from its
    # twin (kidnapped robots carried into the fourth corridor, which had none, settled there)
    stubs = (
        (8.0, 0.0, 2.0),
        (12.0, 6.3, 8.0),
        (8.0, 8.3, 10.0),
        (16.0, 14.3, 16.0),
        (14.0, 16.3, 18.0),
    )
    for x, y0, y1 in stubs:
        _box(occ, res, x, y0, x + t, y1)
    robot = {"footprint": [0.66, 0.5], "rear_axle_to_center": 0.0, "turning_radius": 0.0}
    scenarios = [
        {
            "name": "maze_bottom_to_top",
            "start": [2.0, 2.0, 0.0],
            "goal": [18.0, 18.0, 90.0],
            **robot,
        },
        {"name": "maze_middle", "start": [10.0, 6.0, 180.0], "goal": [4.0, 14.0, 0.0], **robot},
    ]
    return occ, res, scenarios


def warehouse() -> tuple[np.ndarray, float, list[dict]]:
    res = 0.1
    occ = _canvas(30.0, 20.0, res)
    for k in range(6):
        x = 4.0 + k * 3.6
        _box(occ, res, x, 4.0, x + 1.2, 16.0)
    _box(occ, res, 0.0, 9.0, 1.5, 11.0)  # a dock
    tug = {"footprint": [1.6, 1.0], "rear_axle_to_center": 0.5, "turning_radius": 1.5}
    scenarios = [
        {"name": "aisle_to_aisle", "start": [6.2, 6.0, 90.0], "goal": [16.9, 14.0, 270.0], **tug},
        {"name": "dock_to_far_aisle", "start": [3.0, 2.0, 0.0], "goal": [24.2, 10.0, 90.0], **tug},
    ]
    return occ, res, scenarios


def room20() -> tuple[np.ndarray, float, list[dict]]:
    res = 0.05
    occ = _canvas(20.0, 20.0, res)
    robot = {"footprint": [0.66, 0.455], "rear_axle_to_center": 0.0, "turning_radius": 0.0}
    return occ, res, [{"name": "diagonal", "start": [2.0, 2.0, 45.0], "goal": [18.0, 18.0, 45.0],
                       **robot}]  # fmt: skip


def doorway() -> tuple[np.ndarray, float, list[dict]]:
    res = 0.05
    occ = _canvas(12.0, 6.0, res)
    _box(occ, res, 5.9, 0.0, 6.1, 2.4)  # the wall, a 1.2 m door between y 2.4 and 3.6
    _box(occ, res, 5.9, 3.6, 6.1, 6.0)
    robot = {"footprint": [0.66, 0.455], "rear_axle_to_center": 0.0, "turning_radius": 0.0}
    return occ, res, [{"name": "through_the_door", "start": [2.0, 3.0, 0.0],
                       "goal": [10.0, 3.0, 0.0], **robot}]  # fmt: skip


def corridor_bay() -> tuple[np.ndarray, float, list[dict]]:
    res = 0.05
    occ = np.ones((round(3.0 / res), round(16.0 / res)), bool)
    occ[round(0.2 / res) : round(1.4 / res), round(0.2 / res) : round(15.8 / res)] = False
    occ[round(1.4 / res) : round(2.8 / res), round(6.75 / res) : round(9.25 / res)] = False
    robot = {"footprint": [0.7, 0.7], "rear_axle_to_center": 0.0, "turning_radius": 0.0}
    return occ, res, [{"name": "end_to_end", "start": [1.0, 0.8, 0.0],
                       "goal": [15.0, 0.8, 0.0], **robot}]  # fmt: skip


# the tight-manoeuvre car of the planning benchmark: wheelbase 2.8 m, width 1.94 m, overhangs
# 0.96 m (front) and 0.93 m (rear), steering up to 0.75 rad: R = 2.8 / tan(0.75)
TIGHT_CAR = {
    "footprint": [4.69, 1.94],
    "rear_axle_to_center": round(4.69 / 2 - 0.93, 3),
    "turning_radius": round(2.8 / math.tan(0.75), 3),
}
PARALLEL_SLOTS = (1.5, 1.4, 1.3, 1.25, 1.2, 1.15, 1.1)
# tight spaces need short moves: 0.1 m position bins, 2.5 degree heading bins (13 cm arcs)
TIGHT_PLANNER = {"planner": {"xy_resolution": 0.1, "headings": 144}}
# a parallel slot below 1.25 car lengths takes 7 to 13 moves shorter than a primitive: moves
# cut at contact, checked every 2 cm (the continuous-collision margin shrinks with the step)
SLOT_PLANNER = {"planner": {**TIGHT_PLANNER["planner"], "collision_step": 0.02,
                            "moves_to_contact": True}}  # fmt: skip


def _rect(x0: float, y0: float, x1: float, y1: float) -> list[list[float]]:
    return [[x0, y0], [x1, y0], [x1, y1], [x0, y1]]


def parallel_slot(ratio: float) -> tuple[dict, list[dict]]:
    """A slot ``ratio`` car lengths long between two parked cars, a curb behind, a 5.5 m lane."""
    length, width = TIGHT_CAR["footprint"]
    slot = round(ratio * length, 3)
    a0 = 1.0
    s0 = a0 + length
    s1 = s0 + slot
    x_max = round(s1 + length + 6.0, 3)
    lane_y = 0.2 + width
    world = {
        "bounds": [0.0, x_max, -0.3, round(lane_y + 5.5, 3)],
        "resolution": 0.05,
        "polygons": [
            _rect(0.0, -0.3, x_max, 0.0),  # the curb
            _rect(a0, 0.2, s0, lane_y),  # parked car behind the slot
            _rect(s1, 0.2, s1 + length, lane_y),  # parked car ahead of it
        ],
    }
    rear = TIGHT_CAR["rear_axle_to_center"] - length / 2  # rear axle to the rear bumper (<0)
    parked = [round(s0 + (slot - length) / 2 - rear, 3), round(0.2 + width / 2, 3), 0.0]
    lane = [round(s1 + 1.0 - rear, 3), round(lane_y + 0.5 + width / 2, 3), 0.0]
    name = f"parallel_{round(ratio * 100)}"
    scenarios = [
        {"name": f"{name}_in", "start": lane, "goal": parked, **TIGHT_CAR, **SLOT_PLANNER},
        {"name": f"{name}_out", "start": parked, "goal": lane, **TIGHT_CAR, **SLOT_PLANNER},
    ]
    return world, scenarios


def perpendicular_bay() -> tuple[dict, list[dict]]:
    """A bay 0.5 m wider than the car between two parked cars (at the bay lines), off a 5.5 m
    aisle whose far side is a wall; the back of the bays is a wall too."""
    length, width = TIGHT_CAR["footprint"]
    bay = width + 0.5
    b0 = 10.0
    b1 = b0 + bay
    depth = 5.5
    cars = [
        _rect(b0 - width, 0.3, b0, 0.3 + length),
        _rect(b1, 0.3, b1 + width, 0.3 + length),
        _rect(b0 - 2 * bay + 0.25, 0.3, b0 - 2 * bay + 0.25 + width, 0.3 + length),
        _rect(b1 + bay + 0.25, 0.3, b1 + bay + 0.25 + width, 0.3 + length),
    ]
    world = {
        "bounds": [0.0, 24.0, 0.0, depth + 5.5],
        "resolution": 0.05,
        "polygons": [[[round(v, 3) for v in p] for p in c] for c in cars],
    }
    rear = TIGHT_CAR["rear_axle_to_center"] - length / 2
    parked = [round((b0 + b1) / 2, 3), round(0.3 - rear, 3), 90.0]
    aisle = [3.0, round(depth + 2.75, 3), 0.0]
    scenarios = [
        {
            "name": "perpendicular_reverse_in",
            "start": aisle,
            "goal": parked,
            **TIGHT_CAR,
            **TIGHT_PLANNER,
        },
        {"name": "perpendicular_out", "start": parked, "goal": aisle, **TIGHT_CAR, **TIGHT_PLANNER},
    ]
    return world, scenarios


def pythonrobotics_maze() -> tuple[dict, list[dict]]:
    """The 60 × 60 m map of the PythonRobotics Hybrid A* demo (walls at x = 20 m from the bottom
    and x = 40 m from the top), with its car: wheelbase 3.0 m, 1.0 m behind and 3.3 m ahead of
    the rear axle, 2.0 m wide, steering up to 0.6 rad."""
    world = {
        "bounds": [0.0, 60.0, 0.0, 60.0],
        "resolution": 0.1,
        "polygons": [_rect(19.9, 0.0, 20.1, 39.0), _rect(39.9, 21.0, 40.1, 60.0)],
    }
    car = {
        "footprint": [4.3, 2.0],
        "rear_axle_to_center": 1.15,
        "turning_radius": round(3.0 / math.tan(0.6), 3),
    }
    scenarios = [
        {"name": "maze_car", "start": [10.0, 10.0, 90.0], "goal": [50.0, 50.0, -90.0], **car}
    ]
    return world, scenarios


WORLDS = {
    **{f"parallel_{round(r * 100)}": (lambda r=r: parallel_slot(r)) for r in PARALLEL_SLOTS},
    "perpendicular_bay": perpendicular_bay,
    "pythonrobotics_maze": pythonrobotics_maze,
}


MAPS = {
    "parking_lot": parking_lot,
    "corridor_uturn": corridor_uturn,
    "maze": maze,
    "warehouse": warehouse,
    "room20": room20,
    "doorway": doorway,
    "corridor_bay": corridor_bay,
}


class _NoAliases(yaml.SafeDumper):
    def ignore_aliases(self, data: object) -> bool:
        return True


def main() -> None:
    # keep the entries of maps made elsewhere (make_cluttered.py)
    old = yaml.safe_load((HERE / "scenarios.yaml").read_text()) or {}
    scenarios: dict[str, list[dict]] = {}
    for name, build in MAPS.items():
        occ, res, scen = build()
        grid = OccupancyGrid.from_array(occ, res)
        write_ros_yaml(grid, HERE / f"{name}.yaml", image=f"{name}.png")
        scenarios[name] = [
            {
                k: ([round(v, 3) for v in val] if isinstance(val, list) else val)
                for k, val in item.items()
            }
            for item in scen
        ]
    for name, build in WORLDS.items():
        world, scen = build()
        doc = " ".join((build.__doc__ or parallel_slot.__doc__ or "").split())
        header = "# " + doc.replace("``ratio`` car lengths", f"{name.split('_')[-1]} % of the car")
        (HERE / f"{name}.yaml").write_text(
            header + "\n" + yaml.safe_dump(world, sort_keys=False, default_flow_style=None)
        )
        scenarios[name] = scen
    for name, items in old.items():
        scenarios.setdefault(name, items)
    text = "# start/goal: [x m, y m, heading deg] of the reference point (rear-axle centre)\n"
    text += yaml.dump(scenarios, Dumper=_NoAliases, sort_keys=False, default_flow_style=None)
    (HERE / "scenarios.yaml").write_text(text)


if __name__ == "__main__":
    main()
