"""Hostile inputs for the fuzz suite (``tests/test_fuzz.py``) and its counter
(``benchmarks/fuzz.py``): hypothesis strategies over scenario fields, map files of every format,
CLI flags and public constructors, and :func:`outcome`, which runs one case within a time budget.

The rule every case must keep: it runs, or it raises a :class:`~wheelbase.WheelbaseError` (or
the CLI exits with code 2 and one line); never another exception, never past its budget.
Resource limits keep legitimate cases small: the base scenarios cap steps, map cells and MPPI
samples (``resources``, ``max_sample_steps``), so a case that takes longer than its budget is a
hang, not a big problem.
"""

from __future__ import annotations

import copy
import inspect
import io
import json
import math
import signal
import tempfile
import time
import traceback
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import yaml
from hypothesis import strategies as st

from shared_data import DATA
from wheelbase.errors import WheelbaseError

__all__ = [
    "BUDGET_S",
    "Outcome",
    "array_map_cases",
    "call_constructor",
    "cli_cases",
    "constructor_cases",
    "exploration_cases",
    "grid_from_array",
    "load_map_file",
    "map_file_cases",
    "outcome",
    "run_cli",
    "run_exploration",
    "run_scenario",
    "run_scenario_file",
    "run_world",
    "scenario_cases",
    "scenario_file_cases",
    "slam_file",
    "slam_file_cases",
    "warm_up",
    "world_cases",
]

BUDGET_S = {
    "slam_file": 30.0,
    "exploration": 30.0,
    "scenario": 30.0,
    "scenario_file": 30.0,
    "map_file": 10.0,
    "cli": 60.0,
    "constructor": 60.0,
    "world": 20.0,
}
"""Seconds one case of each kind may take. Typical cases take milliseconds; the budgets cover the
largest work the limits allow (a NumPy MPPI call at 5e6 samples × 10 steps: 19 s on 2 cores)."""

# Values a careless or hostile user can put anywhere.
HOSTILE: list[Any] = [
    math.nan,
    math.inf,
    -math.inf,
    0,
    0.0,
    -1,
    -1.0,
    1e300,
    -1e300,
    1e-300,
    2**70,
    -(2**70),
    2**63,
    "abc",
    "",
    None,
    True,
    False,
    [],
    {},
    [1, 2, 3],
    [0.5, 0.5],
    0.5,
    3,
    1e10,
    -6.12,
    1e9,
    "1e3",
    [math.nan, 1.0],
    [[1.0]],
]
HOSTILE_TEXT = [
    "nan",
    "inf",
    "-inf",
    "0",
    "-1",
    "1e300",
    "1e-300",
    "abc",
    "",
    "90deg",
    "-6.12",
    "1e10",
    "1e9",
    "2",
    "0.5",
    "1e-9",
    "99999999999999999999",
    "°",
    "rad",
    "3",
    "-0",
    "1,2",
    "NaNdeg",
]


class Hang(BaseException):
    """Raised by the alarm when a case runs past its budget (a BaseException, so that no
    ``except Exception`` in the code under test swallows it)."""


@dataclass(frozen=True)
class Outcome:
    """What one case did: ``"ok"``, ``"error"`` (a WheelbaseError), ``"raw"`` (any other
    exception) or ``"hang"`` (past its budget); ``detail`` says which and where."""

    kind: str
    detail: str
    seconds: float


def outcome(call: Callable[[], Any], budget_s: float) -> Outcome:
    """Run ``call`` and classify it; a SIGALRM stops Python code at the budget, and a compiled
    kernel that cannot be stopped is still a hang when it returns late."""

    def alarm(signum, frame):
        raise Hang()

    previous = signal.signal(signal.SIGALRM, alarm)
    signal.setitimer(signal.ITIMER_REAL, budget_s)
    start = time.perf_counter()
    try:
        call()
        kind, detail = "ok", ""
    except Hang:
        kind, detail = "hang", f"stopped after {budget_s:g} s"
    except WheelbaseError as error:
        kind, detail = "error", f"{type(error).__name__}: {error}"
        if not str(error).strip():
            kind, detail = "raw", f"{type(error).__name__} with an empty message"
    except Exception as error:  # the point: anything else is a defect
        kind, detail = "raw", f"{type(error).__name__}: {error} at {_where(error)}"
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)
    seconds = time.perf_counter() - start
    if kind != "hang" and seconds > budget_s:
        kind, detail = "hang", f"returned after {seconds:.1f} s > {budget_s:g} s"
    return Outcome(kind, detail, seconds)


def warm_up() -> None:
    """Compile (or load from the cache) the Numba kernels the cases use, outside any budget: a
    first call that compiles under a loaded machine can take longer than a case may."""
    for base in BASES:
        outcome(lambda base=base: run_scenario(base), 600.0)
    outcome(lambda: run_world(WORLD_BASE), 600.0)


def _where(error: BaseException) -> str:
    frames = [f for f in traceback.extract_tb(error.__traceback__) if "/wheelbase/" in f.filename]
    return f"{Path(frames[-1].filename).name}:{frames[-1].lineno}" if frames else "?"


# =========================================================================== scenarios
_FUZZ_RESOURCES = {"max_steps": 20_000, "max_map_cells": 1_000_000}
BASES: list[dict[str, Any]] = [
    {
        "name": "fuzz",
        "map": "empty",
        "robot": {"model": "unicycle"},
        "controller": {"law": "kanayama"},
        "odometry": {"mode": "perfect"},
        "start": [0.0, 0.0, 0.0],
        "goal": [1.0, 0.5, 0.0],
        "dt": 0.05,
        "duration": 10.0,
    },
    {
        "name": "fuzz",
        "map": "empty",
        "robot": {"model": "diffdrive", "wheel_radius": 0.05},
        "controller": {"law": "pure_pursuit", "gains": {"min_lookahead": 0.3}},
        "odometry": {"mode": "encoders", "tick_noise_std": 0.5},
        "planner": {"margin": 0.05},
        "start": [0.0, 0.0, 0.0],
        "goal": [1.5, 0.0, 90.0],
        "dt": 0.05,
        "duration": 15.0,
    },
    {
        "name": "fuzz",
        "map": "empty",
        "robot": {"model": "rear_bicycle", "wheel_base": 0.3},
        "controller": {"law": "stanley"},
        "odometry": {"mode": "perfect"},
        "start": [0.0, 0.0, 0.0],
        "goal": [2.0, 1.0, 0.0],
        "dt": 0.05,
        "duration": 15.0,
    },
    {
        "name": "fuzz",
        "map": "empty",
        "robot": {"model": "unicycle", "footprint": [0.3, 0.3]},
        "controller": {
            "law": "mppi",
            "gains": {"samples": 64, "horizon_steps": 10, "max_sample_steps": 4000},
        },
        "odometry": {"mode": "perfect"},
        "start": [0.0, 0.0, 0.0],
        "goal": [1.0, 0.0, 0.0],
        "dt": 0.1,
        "duration": 10.0,
    },
    {
        "name": "fuzz",
        "map": "empty",
        "robot": {"model": "diffdrive", "preset": "rm100"},
        "plant": "dynamic",
        "controller": {"law": "computed_torque"},
        "start": [0.0, 0.0, 0.0],
        "goal": [1.0, 0.0, 0.0],
        "dt": 0.02,
        "duration": 10.0,
    },
    {
        "name": "fuzz",
        "map": "empty",
        "robot": {
            "model": "diffdrive",
            "preset": "rm100",
            "payload": {"mass": 10.0, "position": [0.1, 0.0], "inertia": 0.2},
            "contacts": {"drive_load_share": 0.6},
        },
        "plant": "dynamic",
        "controller": {
            "law": "adaptive_computed_torque",
            "model_payload": False,
            "traction_control": {"friction": "map", "slow_down": True},
        },
        "sensors": {"imu": {}},
        "odometry": {"mode": "encoders", "gyro": True},
        "terrain": {
            "surface": "dry_concrete",
            "regions": [
                {
                    "polygon": [[0.3, -1.0], [0.8, -1.0], [0.8, 1.0], [0.3, 1.0]],
                    "surface": "ice",
                    "grade_percent": 5.0,
                    "uphill_deg": 0.0,
                },
                {
                    "polygon": [[1.0, -1.0], [1.4, -1.0], [1.4, 1.0], [1.0, 1.0]],
                    "surface": {"like": "grass", "peak_friction": 0.3},
                },
            ],
        },
        "start": [0.0, 0.0, 0.0],
        "goals": [[0.8, 0.0, 0.0], {"pose": [1.5, 0.0, 0.0], "payload": None}],
        "dt": 0.02,
        "duration": 10.0,
    },
]
BASES.append(
    {  # among obstacles the map does not show (issue 22): a lidar, a costmap, walkers, a box
        "name": "fuzz",
        "map": "empty",
        "robot": {"model": "unicycle", "footprint": [0.3, 0.3]},
        "controller": {"law": "pure_pursuit"},
        "control_rate_hz": 5.0,
        "odometry": {"mode": "perfect"},
        "sensors": {"lidar": {"beams": 24, "max_range": 4.0, "rate_hz": 5.0}},
        "world": {
            "obstacles": [{"box": [1.5, 0.0, 0.3, 0.3, 10.0]}],
            "agents": [{"count": 2, "radius": 0.2, "behaviour": "wander", "region": [0, 1, 3, 2]}],
            "path_boxes": {"count": [0, 1], "size": [0.2, 0.3], "clear": 0.5},
        },
        "costmap": {"inflation_radius": 0.3},
        "tracker": {},
        "replanning": {"rate_hz": 1.0},
        "recovery": {"max_retries": 2, "wait_time": 0.5},
        "start": [0.0, 0.0, 0.0],
        "goal": [3.0, 0.0, 0.0],
        "dt": 0.1,
        "duration": 6.0,
    }
)
BASES.append(
    {  # a fleet of two robots that see each other
        "name": "fuzz",
        "map": "empty",
        "robot": {"model": "unicycle", "footprint": [0.3, 0.3]},
        "controller": {"law": "pure_pursuit"},
        "odometry": {"mode": "perfect"},
        "sensors": {"lidar": {"beams": 24, "max_range": 4.0, "rate_hz": 5.0}},
        "fleet": [
            {"start": [0.0, 0.0, 0.0], "goal": [3.0, 0.0, 0.0]},
            {"start": [3.0, 1.0, 180.0], "goal": [0.0, 1.0, 180.0]},
        ],
        "dt": 0.1,
        "duration": 6.0,
    }
)
for _base in BASES:
    _base["resources"] = dict(_FUZZ_RESOURCES)
    _base.setdefault("planner", {})["options"] = {"time_limit": 2.0}


def _scenario_paths() -> list[tuple[str, ...]]:
    """Every field of the scenario schema, and the gains and planner options a file can set."""
    from dataclasses import fields

    from pydantic import BaseModel

    from wheelbase.control import DWA, MPPI, DWACritics, Kanayama, PurePursuit, Stanley
    from wheelbase.control.mppi_critics import MPPICritics
    from wheelbase.planning import HybridAStar
    from wheelbase.scenario import Scenario

    paths: list[tuple[str, ...]] = []

    def walk(model: type[BaseModel], prefix: tuple[str, ...]) -> None:
        for name, field in model.model_fields.items():
            paths.append((*prefix, name))
            annotation = field.annotation
            if isinstance(annotation, type) and issubclass(annotation, BaseModel):
                walk(annotation, (*prefix, name))

    walk(Scenario, ())
    paths.append(("goal",))
    gains = set(inspect.signature(MPPI).parameters) | {f.name for f in fields(MPPICritics)}
    gains |= {f.name for f in fields(DWACritics)} - {"extra"}
    for cls in (Kanayama, PurePursuit, Stanley, DWA):
        gains |= set(inspect.signature(cls).parameters)
    gains |= {"bandwidth", "speed", "max_torque", "model_error", "max_speed", "max_yaw_rate"}
    paths += [("controller", "gains", name) for name in sorted(gains - {"model", "limits"})]
    options = set(inspect.signature(HybridAStar).parameters)
    paths += [("planner", "options", name) for name in sorted(options)]
    paths += _ground_paths()
    paths += _navigation_paths()
    return paths


def _navigation_paths() -> list[tuple[str, ...]]:
    """The keys of the world, fleet, costmap and tracker sections (issue 22), optional
    sections that the schema walk does not enter."""
    from dataclasses import fields

    from wheelbase.perception import CostmapSpec, TrackerSpec
    from wheelbase.scenario_world import FleetRobotSpec, PathBoxesSpec, WorldSpec
    from wheelbase.world.spec import AGENT_KEYS, OBSTACLE_KINDS

    return [
        *[("world", name) for name in WorldSpec.model_fields],
        *[("world", "path_boxes", name) for name in PathBoxesSpec.model_fields],
        *[("world", "agents", 0, name) for name in AGENT_KEYS],
        *[("world", "obstacles", 0, name) for name in OBSTACLE_KINDS],
        *[("fleet", k, name) for k in (0, 1) for name in (*FleetRobotSpec.model_fields, "goal")],
        *[("costmap", f.name) for f in fields(CostmapSpec)],
        *[("tracker", f.name) for f in fields(TrackerSpec)],
        ("fleet",),
        ("control_rate_hz",),
    ]


def _ground_paths() -> list[tuple[str, ...]]:
    """The keys of the terrain, payload and coping-control sections (issue 24), whose
    sections are optional (``X | None``) and so not walked from the schema."""
    from pydantic import BaseModel

    from wheelbase.runner import ADAPTIVE_GAINS
    from wheelbase.scenario import ImuSpec
    from wheelbase.scenario_terrain import (
        ContactsSpec,
        PayloadSpec,
        RasterSpec,
        RegionSpec,
        SlopeFeedForwardSpec,
        SoilSpec,
        SurfaceSpec,
        TerrainSpec,
        TractionSpec,
    )

    def keys(model: type[BaseModel], prefix: tuple[str, ...]) -> list[tuple[str, ...]]:
        return [(*prefix, name) for name in model.model_fields]

    region = ("terrain", "regions", 0)
    return [
        *keys(TerrainSpec, ("terrain",)),
        *keys(SurfaceSpec, ("terrain", "surface")),
        *keys(SoilSpec, ("terrain", "surface", "soil")),
        *keys(RegionSpec, region),
        *keys(RasterSpec, ("terrain", "raster")),
        *keys(SurfaceSpec, (*region, "surface")),
        *keys(PayloadSpec, ("robot", "payload")),
        *keys(ContactsSpec, ("robot", "contacts")),
        *keys(TractionSpec, ("controller", "traction_control")),
        *keys(ImuSpec, ("sensors", "imu")),
        *keys(SlopeFeedForwardSpec, ("controller", "slope_feedforward")),
        ("controller", "model_payload"),
        ("goal_payloads",),
        *[("controller", "gains", name) for name in ADAPTIVE_GAINS],
    ]


_PATHS: list[tuple[str, ...]] = []


def scenario_paths() -> list[tuple[str, ...]]:
    """The field paths a mutation can touch (computed once)."""
    if not _PATHS:
        _PATHS.extend(_scenario_paths())
    return _PATHS


# numbers for tuples (poses, footprints, scales): wide, with the extremes and non-finite ones
_NUMBER = st.one_of(
    st.floats(min_value=-20.0, max_value=20.0),
    st.floats(min_value=-1e11, max_value=1e11),
    st.sampled_from([math.nan, math.inf, 1e300, 1e-300, 0.0, -6.12, 4.5e9, 1e10]),
)
_TUPLES = st.one_of(
    st.lists(_NUMBER, min_size=0, max_size=4),
    st.lists(st.lists(_NUMBER, min_size=2, max_size=4), min_size=0, max_size=4),
)


def _mutation(paths: list[tuple[str, ...]]) -> st.SearchStrategy:
    value = st.one_of(
        _TUPLES,
        st.sampled_from(HOSTILE),
        st.floats(allow_nan=True, allow_infinity=True),
        st.integers(min_value=-(2**80), max_value=2**80),
        st.text(max_size=8),
        st.sampled_from(
            [
                "empty",
                "warehouse",
                "maze",
                "mppi",
                "segment",
                "linear",
                "rear_wheel_feedback",
                "ackermann",
                "bicycle",
                "dynamic",
                "rm100",
                "numba",
                "numpy",
                "exact",
                "encoders",
                "trinary",
                "ice",
                "dry_sand",
                "map",
                "adaptive_computed_torque",
            ]
        ),
    )
    return st.tuples(
        st.sampled_from(paths),
        st.sampled_from(["set", "set", "set", "delete", "unknown"]),
        value,
    )


def _apply(data: dict[str, Any], mutation: tuple) -> None:
    path, action, value = mutation
    node: Any = data
    for key in path[:-1]:
        if isinstance(node, list) and isinstance(key, int):  # a list entry (terrain regions)
            if key >= len(node):
                return
            node = node[key]
            continue
        if not isinstance(node, dict):
            return
        node = node.setdefault(key, {}) if action == "set" else node.get(key)
    if not isinstance(node, dict):
        return
    if action == "set":
        node[path[-1]] = copy.deepcopy(value)
    elif action == "delete":
        node.pop(path[-1], None)
    else:
        node[f"{path[-1]}_typo"] = copy.deepcopy(value)


@st.composite
def scenario_cases(draw) -> dict[str, Any]:
    """A base scenario with one to three fields set to hostile values, deleted or misspelt."""
    data = copy.deepcopy(draw(st.sampled_from(BASES)))
    for mutation in draw(st.lists(_mutation(scenario_paths()), min_size=1, max_size=3)):
        _apply(data, mutation)
    return data


def run_scenario(data: dict[str, Any]) -> Any:
    """Run a scenario case from its mapping, as ``wheelbase.run`` does."""
    from wheelbase.runner import run

    return run(copy.deepcopy(data))


def run_scenario_file(content: bytes) -> Any:
    """Write a scenario file case and run it by path."""
    from wheelbase.runner import run

    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "scenario.yaml"
        path.write_bytes(content)
        return run(path)


@st.composite
def scenario_file_cases(draw) -> bytes:
    """The bytes of a scenario file: a valid one cut, re-encoded or with bytes flipped."""
    text = yaml.safe_dump(draw(st.sampled_from(BASES)), sort_keys=False)
    raw = text.encode(draw(st.sampled_from(["utf-8", "utf-16", "latin-1"])))
    return _damage(draw, raw)


def _damage(draw, raw: bytes) -> bytes:
    how = draw(st.sampled_from(["keep", "cut", "flip", "insert", "append"]))
    if how == "cut" and raw:
        return raw[: draw(st.integers(0, len(raw) - 1))]
    if how == "flip" and raw:
        at = draw(st.integers(0, len(raw) - 1))
        return raw[:at] + bytes([draw(st.integers(0, 255))]) + raw[at + 1 :]
    if how == "insert":
        at = draw(st.integers(0, len(raw)))
        return raw[:at] + draw(st.binary(min_size=1, max_size=16)) + raw[at:]
    if how == "append":
        return raw + draw(
            st.sampled_from(
                [
                    b"\n: :\n",
                    b"\x00",
                    b"\n- [",
                    b"\nkey: &a [*a]\n",
                    b"\n" + b"[" * 200,
                    b"\xff\xfe",
                ]
            )
        )
    return raw


# =========================================================================== map files
def _pgm(width: Any, height: Any, body: bytes, maxval: Any = 255) -> bytes:
    return f"P5\n{width} {height}\n{maxval}\n".encode() + body


@st.composite
def _image_bytes(draw) -> tuple[str, bytes]:
    kind = draw(st.sampled_from(["pgm", "png", "bmp", "jpg", "header", "random"]))
    if kind == "random":
        return ".png", draw(st.binary(max_size=64))
    if kind == "header":
        dims = st.one_of(
            st.sampled_from([0, 1, 3, -1, 10**8, 2**31, "abc", "1e3", ""]), st.integers(0, 50)
        )
        maxval = draw(st.sampled_from([255, 65535, 0, 1, 70000, "x"]))
        body = draw(st.binary(max_size=64))
        return ".pgm", _pgm(draw(dims), draw(dims), body, maxval)
    from PIL import Image

    rows, cols = draw(st.integers(1, 12)), draw(st.integers(1, 12))
    mode = draw(st.sampled_from(["L", "RGB", "RGBA", "LA", "1", "P", "I", "F", "I;16"]))
    pixels = np.asarray(
        draw(st.lists(st.integers(0, 255), min_size=rows * cols, max_size=rows * cols)), np.uint8
    ).reshape(rows, cols)
    image = Image.fromarray(pixels, "L").convert(mode if mode != "I;16" else "I")
    if mode == "I;16":
        image = Image.fromarray(pixels.astype(np.uint16) * 257)
    fmt = {"pgm": "PPM", "png": "PNG", "bmp": "BMP", "jpg": "JPEG"}[kind]
    buffer = io.BytesIO()
    try:
        image.save(buffer, fmt)
    except (OSError, ValueError, KeyError):
        image.convert("L").save(buffer, fmt)
    return f".{kind}", _damage(draw, buffer.getvalue())


@st.composite
def _ros_yaml(draw) -> tuple[str, bytes, dict[str, bytes]]:
    suffix, image = draw(_image_bytes())
    fields: dict[str, Any] = {
        "image": f"m{suffix}",
        "resolution": 0.1,
        "origin": [0.0, 0.0, 0.0],
        "negate": 0,
        "occupied_thresh": 0.65,
        "free_thresh": 0.196,
        "mode": "trinary",
    }
    for key in draw(st.lists(st.sampled_from(sorted(fields)), max_size=3)):
        choice = draw(st.sampled_from(["set", "delete"]))
        if choice == "delete":
            fields.pop(key, None)
        else:
            fields[key] = draw(
                st.one_of(
                    st.sampled_from(HOSTILE),
                    st.sampled_from(
                        ["scale", "raw", "m.pgm", "missing.png", "yes", "no", [1, "a"], [0, 0]]
                    ),
                )
            )
    text = yaml.safe_dump(fields).encode()
    return ".yaml", _damage(draw, text), {f"m{suffix}": image}


@st.composite
def _movingai(draw) -> tuple[str, bytes, dict[str, bytes]]:
    height = draw(
        st.one_of(st.integers(0, 12), st.sampled_from([-1, "abc", 10**6, "1e3", "", "²", "9" * 30]))
    )
    width = draw(st.one_of(st.integers(0, 12), st.sampled_from([-1, "x", 10**6, ""])))
    rows = draw(st.lists(st.text(alphabet=".@TGSWO \t", max_size=14), max_size=14))
    header = draw(st.sampled_from(["type octile\n", "", "type\n", "type octile extra\n"]))
    text = f"{header}height {height}\nwidth {width}\nmap\n" + "\n".join(rows)
    encoding = draw(st.sampled_from(["utf-8", "utf-8", "latin-1", "utf-16"]))
    return ".map", _damage(draw, text.encode(encoding, errors="replace")), {}


@st.composite
def _scen(draw) -> tuple[str, bytes, dict[str, bytes]]:
    field = st.one_of(st.integers(-5, 100), st.sampled_from(["x", "1e3", "nan", "inf", ""]))
    lines = ["version 1"]
    for _ in range(draw(st.integers(0, 4))):
        values = [draw(field) for _ in range(draw(st.sampled_from([9, 9, 9, 8, 10])))]
        lines.append("\t".join(map(str, values)))
    return ".scen", _damage(draw, "\n".join(lines).encode()), {}


@st.composite
def _world(draw) -> tuple[str, bytes, dict[str, bytes]]:
    """A polygon world (YAML or GeoJSON): bounds, polygons with holes, discs, odd numbers."""
    number = st.one_of(
        st.floats(min_value=-5.0, max_value=25.0),
        st.sampled_from([math.nan, math.inf, -math.inf, 1e300, 1e-300, 0.0, 1e10, "a", None]),
    )
    ring = st.lists(st.lists(number, min_size=2, max_size=3), min_size=0, max_size=6)
    fields: dict[str, Any] = {"bounds": [0.0, 20.0, 0.0, 20.0], "resolution": 0.5}
    for key in draw(
        st.lists(
            st.sampled_from(["bounds", "resolution", "polygons", "discs", "grid", "extra"]),
            max_size=4,
        )
    ):
        fields[key] = draw(
            st.one_of(
                st.sampled_from(HOSTILE),
                st.lists(number, min_size=0, max_size=5),
                st.lists(ring, max_size=3),
                st.lists(
                    st.fixed_dictionaries({"exterior": ring, "holes": st.lists(ring, max_size=2)}),
                    max_size=2,
                ),
                st.lists(st.lists(number, min_size=2, max_size=4), max_size=3),
                st.sampled_from(["maze", "missing.map", "m.pgm", "world.yaml", 1e-4]),
            )
        )
    if draw(st.booleans()):
        return ".yaml", _damage(draw, yaml.safe_dump(fields).encode()), {}
    features = [
        {
            "type": "Feature",
            "properties": {"radius": draw(number)},
            "geometry": {
                "type": draw(
                    st.sampled_from(["Point", "Polygon", "MultiPolygon", "LineString", "Bogus"])
                ),
                "coordinates": draw(
                    st.one_of(ring, st.lists(ring, max_size=2), st.lists(number, max_size=3))
                ),
            },
        }
        for _ in range(draw(st.integers(0, 3)))
    ]
    collection = {
        "type": draw(st.sampled_from(["FeatureCollection", "Feature", "Polygon", 3])),
        "features": features,
        "bbox": fields.get("bounds"),
        "resolution": fields.get("resolution"),
    }
    text = json.dumps(collection, allow_nan=True).encode()
    return draw(st.sampled_from([".geojson", ".json"])), _damage(draw, text), {}


@st.composite
def map_file_cases(draw) -> tuple[str, bytes, dict[str, bytes]]:
    """(suffix, bytes, side files) of a map file of any format, possibly damaged."""
    return draw(
        st.one_of(
            _world(),
            _ros_yaml(),
            _movingai(),
            _scen(),
            _image_bytes().map(lambda pair: (pair[0], pair[1], {})),
        )
    )


def load_map_file(case: tuple[str, bytes, dict[str, bytes]]) -> Any:
    """Write a map case into a fresh folder and read it the way a user would."""
    from wheelbase.planning import read_movingai_scenarios
    from wheelbase.planning.maps import load_map

    suffix, content, side = case
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / f"map{suffix}"
        path.write_bytes(content)
        for name, data in side.items():
            (Path(folder) / name).write_bytes(data)
        if suffix == ".scen":
            return read_movingai_scenarios(path)
        if suffix in (".png", ".pgm", ".bmp", ".jpg"):  # a bare image needs its resolution
            return load_map(path, resolution=0.1)
        return load_map(path)


@st.composite
def array_map_cases(draw) -> dict[str, Any]:
    """Arguments of ``OccupancyGrid.from_array``: odd arrays, resolutions, origins, thresholds."""
    rows, cols = draw(st.integers(0, 6)), draw(st.integers(0, 6))
    element = st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.integers(-2, 2))
    values = draw(st.lists(element, min_size=rows * cols, max_size=rows * cols))
    dtype = draw(st.sampled_from([float, bool, int, object, str]))
    try:
        array = np.asarray(values, dtype=dtype).reshape(rows, cols)
    except (ValueError, OverflowError):
        array = np.zeros((rows, cols))
    return {
        "occupied": draw(st.one_of(st.just(array), st.sampled_from(HOSTILE))),
        "resolution": draw(st.one_of(st.just(0.1), st.sampled_from(HOSTILE))),
        "origin": draw(st.one_of(st.just((0.0, 0.0)), st.sampled_from(HOSTILE))),
        "occupied_thresh": draw(st.one_of(st.just(0.5), st.sampled_from(HOSTILE))),
    }


def grid_from_array(kwargs: dict[str, Any]) -> Any:
    """Build a grid from an array case."""
    from wheelbase.planning import OccupancyGrid

    return OccupancyGrid.from_array(**kwargs)


# =========================================================================== world section
WORLD_BASE: dict[str, Any] = {
    "obstacles": [{"box": [6.0, 3.0, 0.6, 0.6, 30]}, {"disc": [8.0, 7.0, 0.3]},
                  {"polygon": [[2.0, 6.0], [3.0, 6.0], [2.5, 7.0]]}],
    "agents": [
        {"count": 3, "radius": 0.3, "speed": 0.5, "behaviour": "straight",
         "region": [3, 3, 9, 9], "reacts_to_robot": False},
        {"count": 3, "behaviour": "wander"},
        {"count": 2, "behaviour": "waypoints", "waypoints": [[2.0, 2.0], [8.0, 2.0]]},
        {"count": 3, "behaviour": "social_force", "reacts_to_robot": True},
        {"count": 3, "behaviour": "orca", "reacts_to_robot": True},
    ],
    "social_force": {"relaxation_time": 0.5},
    "orca": {"time_horizon": 5.0},
}  # fmt: skip
"""A valid ``world`` section on a 10 m room (:func:`run_world`); cases damage it."""


def _world_paths() -> list[tuple]:
    from dataclasses import fields

    from wheelbase.world import ORCA, SocialForce
    from wheelbase.world.spec import AGENT_KEYS, OBSTACLE_KINDS, WORLD_KEYS

    paths: list[tuple] = [(key,) for key in WORLD_KEYS]
    paths += [("obstacles", i, kind) for i in range(3) for kind in OBSTACLE_KINDS]
    paths += [("obstacles", i) for i in range(4)]
    paths += [("agents", i, key) for i in range(5) for key in AGENT_KEYS]
    paths += [("agents", i) for i in range(6)]
    paths += [("social_force", f.name) for f in fields(SocialForce)]
    paths += [("orca", f.name) for f in fields(ORCA)]
    return paths


def _apply_world(data: Any, mutation: tuple) -> None:
    path, action, value = mutation
    node = data
    for key in path[:-1]:
        in_dict = isinstance(node, dict) and key in node
        in_list = isinstance(node, list) and isinstance(key, int) and key < len(node)
        if in_dict or in_list:
            node = node[key]
        else:
            return
    last = path[-1]
    if isinstance(node, dict):
        if action == "delete":
            node.pop(last, None)
        elif action == "unknown":
            node[f"{last}_typo"] = copy.deepcopy(value)
        else:
            node[last] = copy.deepcopy(value)
    elif isinstance(node, list) and isinstance(last, int):
        if last < len(node):
            if action == "delete":
                node.pop(last)
            else:
                node[last] = copy.deepcopy(value)
        elif action == "set":
            node.append(copy.deepcopy(value))


@st.composite
def world_cases(draw) -> Any:
    """The base ``world`` section with one to three entries set to hostile values (numbers,
    lists, huge counts, other behaviours), deleted or misspelt; or a hostile section."""
    if draw(st.integers(0, 19)) == 0:
        return draw(st.sampled_from(HOSTILE))
    data = copy.deepcopy(WORLD_BASE)
    value = st.one_of(
        _TUPLES,
        st.sampled_from(HOSTILE),
        st.floats(allow_nan=True, allow_infinity=True),
        st.integers(min_value=-(2**70), max_value=2**70),
        st.sampled_from(["wander", "orca", "social_force", "waypoints", "dance", [[0.0, 0.0]],
                         {"box": [5, 5, 0.5, 0.5]}, {"disc": [1.0, 1.0, 0.5]}, 10_000, 5000,
                         [0, 0, 10, 10], [[1, 1], [1e9, 1]], 1e-9, 0.01, 9.9]),
    )  # fmt: skip
    for path in draw(st.lists(st.sampled_from(_world_paths()), min_size=1, max_size=3)):
        action = draw(st.sampled_from(["set", "set", "set", "delete", "unknown"]))
        _apply_world(data, (path, action, draw(value)))
    return data


def run_world(spec: Any) -> Any:
    """Build the world of a case on a 10 m room, start two worlds clear of a robot's start
    and goal, step them with the robot, cast a scan and measure distances."""
    from wheelbase.planning import Footprint, OccupancyGrid
    from wheelbase.world import RobotBodies, world_from_spec

    occupied = np.zeros((100, 100), bool)
    occupied[[0, -1], :] = occupied[:, [0, -1]] = True
    world = world_from_spec(spec, OccupancyGrid(occupied, 0.1))
    keep = [[1.0, 1.0, 0.4], [9.0, 9.0, 0.4]]
    state = world.start([0, 1], keep, labels=["start", "goal"])
    footprint = Footprint.rectangle(0.4, 0.4)
    robots = RobotBodies(np.tile([1.0, 1.0, 0.3], (2, 1, 1)), np.tile([0.3, 0.1], (2, 1, 1)),
                         footprint)  # fmt: skip
    for _ in range(3):
        state = world.step(state, 0.1, robots)
    if not np.all(np.isfinite(state.position)) or not np.all(np.isfinite(state.velocity)):
        raise AssertionError("non-finite agent state")  # silently wrong: a raw failure
    poses = robots.pose.reshape(-1, 3)
    index = np.arange(2, dtype=np.int64)
    world.cast(poses, np.linspace(-np.pi, np.pi, 90, endpoint=False), 8.0, index, state,
               robots, np.zeros(2, np.int64))  # fmt: skip
    return world.distances(poses, footprint, index, state, robots, np.zeros(2, np.int64))


# =========================================================================== SLAM inputs
_G2O_LINES = [
    "VERTEX_SE2 0 0 0 0",
    "VERTEX_SE2 1 1 0 0.1",
    "VERTEX_SE2 2 2 0.1 0.2",
    "EDGE_SE2 0 1 1 0 0.1 100 0 0 100 0 400",
    "EDGE_SE2 1 2 1 0.1 0.1 100 0 0 100 0 400",
    "EDGE_SE2 0 2 2 0.1 0.2 50 0 0 50 0 200",
    "FIX 0",
]


def _flaser(ranges: list[str], pose: str = "1 2 0.5", t: str = "1.0") -> str:
    return f"FLASER {len(ranges)} {' '.join(ranges)} {pose} {pose} {t} host {t}"


@st.composite
def _g2o(draw) -> tuple[str, bytes]:
    lines = list(_G2O_LINES)
    for _ in range(draw(st.integers(0, 3))):
        k = draw(st.integers(0, len(lines) - 1))
        tokens = lines[k].split()
        if not tokens:  # an earlier mutation left the line blank (a whitespace token)
            continue
        j = draw(st.integers(0, len(tokens) - 1))
        tokens[j] = draw(st.sampled_from(HOSTILE_TEXT))
        lines[k] = " ".join(tokens) if draw(st.booleans()) else " ".join(tokens[: j + 1])
    if draw(st.booleans()):
        lines = draw(st.permutations(lines))[: draw(st.integers(0, len(lines)))]
    return ".g2o", "\n".join(lines).encode()


@st.composite
def _carmen(draw) -> tuple[str, bytes]:
    scans = draw(st.integers(0, 6))
    beams = draw(st.sampled_from([1, 4, 30]))
    lines = ["# CARMEN", "PARAM robot_x 0 host 0", "ODOM 0 0 0 0 0 0 1 h 1"]
    moving = draw(st.booleans())  # a robot that never moves, or one that does
    for k in range(scans):
        ranges = [draw(st.sampled_from(["1.0", "2.5", "nan", "inf", "-1", "81.83", "0",
                                        "1e300"])) for _ in range(beams)]  # fmt: skip
        pose = f"{0.3 * k if moving else 0.0} 0 0"
        lines.append(_flaser(ranges, pose, str(1.0 + k)))
    for _ in range(draw(st.integers(0, 2))):
        if lines:
            k = draw(st.integers(0, len(lines) - 1))
            tokens = lines[k].split()
            j = draw(st.integers(0, len(tokens) - 1))
            tokens[j] = draw(st.sampled_from(HOSTILE_TEXT))
            lines[k] = " ".join(tokens)
    return draw(st.sampled_from([".log", ".clf"])), "\n".join(lines).encode()


@st.composite
def slam_file_cases(draw) -> tuple[str, bytes, dict[str, Any]]:
    """(suffix, bytes, options) of a g2o graph or a CARMEN log, possibly damaged, and the
    mapping options to build its map with (resolution, max_cells, max_range)."""
    suffix, content = draw(st.one_of(_g2o(), _carmen()))
    options = {
        "resolution": draw(st.sampled_from([0.05, 0.5, 1e-5, 0.0, -1.0, float("nan")])),
        "max_cells": draw(st.sampled_from([10**6, 10, 1])),
        "max_range": draw(st.sampled_from([30.0, 1e-9, float("inf")])),
    }
    return suffix, content, options


def slam_file(case: tuple[str, bytes, dict[str, Any]]) -> Any:
    """Read a SLAM input as a user would and run what reads it: a g2o file is optimised, a
    CARMEN log mapped with its own poses (within ``max_cells``) and run through lidar SLAM."""
    from wheelbase.datasets import read_carmen, read_g2o
    from wheelbase.mapping import LidarSlam, OccupancyMapper, optimize_pose_graph

    suffix, content, options = case
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / f"data{suffix}"
        path.write_bytes(content)
        if suffix == ".g2o":
            return optimize_pose_graph(read_g2o(path), initial="chordal")
        log = read_carmen(path)
    mapper = OccupancyMapper(resolution=options["resolution"], max_range=options["max_range"])
    mapper.build(log.reference, log.ranges, log.angles, sensor_max_range=log.max_range,
                 max_cells=options["max_cells"])  # fmt: skip
    return LidarSlam().run(log)


# =========================================================================== constructors
def _constructors() -> dict[str, tuple[Callable[..., Any], dict[str, Any]]]:
    """Public constructors and entry points with valid arguments (one is then made hostile)."""
    import wheelbase as wb
    from wheelbase.control import VelocityLimits
    from wheelbase.planning import Footprint, OccupancyGrid, dubins_length, reeds_shepp_length

    grid = OccupancyGrid.from_array(np.zeros((40, 40), bool), 0.1)
    line = wb.PlannedPath.from_points([[0.0, 0.0], [2.0, 0.0]])
    limits = VelocityLimits(max_speed=0.5, max_yaw_rate=1.0)

    def plan(**kw):
        planner = wb.HybridAStar(grid, kw.pop("footprint"), kw.pop("turning_radius"), **kw)
        return planner.plan((1.0, 1.0, 0.0), (3.0, 2.0, 1.0))

    def plan_poses(start, goal):
        return wb.HybridAStar(grid, (0.4, 0.3), 0.5).plan(start, goal)

    def mppi(**kw):
        controller = wb.MPPI(wb.Unicycle(), **kw)
        return controller(0.0, (0.5, 0.5, 0.0), line)

    def mppi_pose(pose, reference):
        controller = wb.MPPI(wb.Unicycle(), 10, 0.1, 32, 0.2, 0.1, None, limits)
        return controller(0.0, pose, reference)

    def perceived(law, cost, resolution, origin, position, velocity, covariance, radius, time):
        from types import SimpleNamespace

        costmap = SimpleNamespace(cost=cost, resolution=resolution, origin=origin)
        tracks = SimpleNamespace(position=position, velocity=velocity, covariance=covariance,
                                 radius=radius)  # fmt: skip
        view = SimpleNamespace(costmap=costmap, tracks=tracks, time=time)
        if law == "dwa":
            controller = wb.control.DWA(wb.Unicycle(), v_samples=5, w_samples=5,
                                        footprint=Footprint.rectangle(0.4, 0.4))  # fmt: skip
        else:
            controller = wb.MPPI(wb.Unicycle(), 10, 0.1, 32, 0.2, 0.1, None, limits,
                                 footprint=Footprint.rectangle(0.4, 0.4))  # fmt: skip
        command = controller(0.2, (0.5, 0.5, 0.0), line, perception=view)
        finite(command)
        return command

    view_arguments = {
        "cost": np.zeros((20, 30), np.uint8) + np.uint8(40),
        "resolution": 0.1,
        "origin": (-0.5, -0.5),
        "position": [[1.2, 0.6]],
        "velocity": [[-0.3, 0.0]],
        "covariance": np.eye(4)[None] * 0.01,
        "radius": [0.3],
        "time": 0.1,
    }

    def dwa(**kw):
        controller = wb.control.DWA.from_gains(wb.Unicycle(), **kw)
        return controller(0.0, (0.5, 0.5, 0.0), line)

    def simulate(**kw):
        return wb.simulate(wb.DiffDrive(0.05, 0.2), **kw)

    def follow(**kw):
        return wb.PurePursuit(**kw)(0.0, (0.1, 0.1, 0.2), line)

    def track(**kw):
        return wb.Kanayama(**kw)

    room = OccupancyGrid.from_array(np.pad(np.zeros((20, 20), bool), 1, constant_values=True), 0.1)
    marks = np.array([[0.5, 0.5], [1.5, 0.5], [1.0, 1.8]])

    def finite(*arrays):
        """A result that came back without an error must be finite (never a NaN estimate)."""
        for array in arrays:
            if not np.all(np.isfinite(array)):
                raise RuntimeError(f"a non-finite result without an error: {array!r}")

    def lidar(**kw):
        from wheelbase.sensors import Lidar

        ranges = Lidar(**kw).scan(room, (1.0, 1.0, 0.3), rng=0)
        if np.any(ranges < 0):
            raise RuntimeError(f"negative ranges: {ranges!r}")
        return ranges

    def lidar_poses(poses, method):
        from wheelbase.sensors import Lidar

        return Lidar(beams=8, max_range=3.0).scan(room, poses, rng=0, method=method)

    def landmarks(**kw):
        from wheelbase.sensors import LandmarkSensor

        return LandmarkSensor(**kw).observe(marks, (1.0, 1.0, 0.3), rng=0)

    def imu_read(**kw):
        from wheelbase.sensors import Imu

        twist = kw.pop("twist")
        return Imu(**kw).read(twist, twist, 0.01, [np.random.default_rng(0)])

    def landmarks_args(landmarks, poses):
        from wheelbase.sensors import LandmarkSensor

        return LandmarkSensor(max_range=3.0, range_std=0.05).observe(landmarks, poses, rng=0)

    def kalman(kind, **kw):
        from wheelbase.localization import EKF, UKF

        filt = (EKF if kind == "ekf" else UKF)(marks, **kw)
        mean, cov = filt.predict((1.0, 1.0, 0.3), np.eye(3) * 0.01, (0.2, 0.1), 0.1)
        mean, cov, _info = filt.update(mean, cov, [0, 2], [[0.7, -2.4], [0.8, 1.2]])
        finite(mean, cov)
        return mean

    def kalman_args(kind, mean, cov, ids, z):
        from wheelbase.localization import EKF, UKF

        filt = (EKF if kind == "ekf" else UKF)(marks)
        mean, cov, _info = filt.update(mean, cov, ids, z)
        finite(mean, cov)
        return mean

    def amcl(**kw):
        from wheelbase.localization import AMCL
        from wheelbase.sensors import Lidar

        sensor = Lidar(beams=12, max_range=3.0)
        filt = AMCL(room, sensor, **kw)
        state = filt.initial_state((1.0, 1.0, 0.3), np.eye(3) * 0.01, rng=0)
        scan = sensor.scan(room, (1.0, 1.0, 0.3), noise=False)
        state, _info = filt.update(state, (0.3, 0.0, 0.0), rng=1, scan=scan, force=True)
        estimate = filt.estimate(state)
        finite(estimate.pose, estimate.cov)
        return estimate

    def amcl_args(odom, scan, pose, cov):
        from wheelbase.localization import AMCL
        from wheelbase.sensors import Lidar

        filt = AMCL(room, Lidar(beams=12, max_range=3.0), min_particles=50, max_particles=200)
        state = filt.initial_state(pose, cov, rng=0)
        state, _info = filt.update(state, odom, rng=1, scan=scan, force=True)
        estimate = filt.estimate(state)
        finite(estimate.pose, estimate.cov)
        return estimate

    beams = np.linspace(-math.pi, math.pi, 24, endpoint=False)

    def true_ranges(pose):
        """The true ranges of the room."""
        from wheelbase.sensors import scan_rays

        return scan_rays(room, [pose[:2]], [pose[2]], beams, 3.0, "exact")[0]

    def scan_of(pose, discs=((1.4, 1.2, 0.2),)):
        """A lidar scan of ``room`` with discs in it (the walkers of the perception cases)."""
        ranges = true_ranges(pose)
        angle = pose[2] + beams
        for cx, cy, rho in discs:
            dx, dy = cx - pose[0], cy - pose[1]
            b = np.cos(angle) * dx + np.sin(angle) * dy
            disc = b * b - (dx * dx + dy * dy - rho * rho)
            t = b - np.sqrt(np.maximum(disc, 0.0))
            ranges = np.where((disc >= 0) & (t >= 0) & (t < ranges), t, ranges)
        return ranges

    def costmap(**keys):
        from wheelbase.perception import CostmapSpec, LayeredCostmap, update_costmap

        spec = CostmapSpec.from_mapping(keys)
        layers = LayeredCostmap.from_map(spec, room, 0.1)
        pose = np.array([[1.0, 1.0, 0.3]])
        state = update_costmap(layers, layers.initial_state(1), pose, beams,
                               scan_of(pose[0])[None], 3.0)  # fmt: skip
        return layers.rolling_window(state, 0, pose[0]).to_occupancy_grid()

    def costmap_args(sensor_poses, beam_angles, ranges, max_range, index):
        from wheelbase.perception import CostmapSpec, LayeredCostmap, update_costmap

        layers = LayeredCostmap.from_map(CostmapSpec(), room, 0.1)
        return update_costmap(layers, layers.initial_state(2), sensor_poses, beam_angles,
                              ranges, max_range, index)  # fmt: skip

    def tracker(**keys):
        from wheelbase.perception import TrackerSpec, TrackerState, update_tracker

        spec = TrackerSpec.from_mapping(keys)
        state = TrackerState.initial(spec)
        for k in range(4):
            pose = np.array([1.0, 1.0, 0.3])
            disc = ((1.4 + 0.05 * k, 1.2, 0.2),)
            state = update_tracker(spec, state, 0.1 * k, pose, beams, scan_of(pose, disc), 3.0,
                                   room)  # fmt: skip
        tracks = state.tracks()
        finite(tracks.position, tracks.velocity, tracks.covariance)
        return tracks

    def tracker_args(time, sensor_pose, beam_angles, ranges, max_range):
        from wheelbase.perception import TrackerSpec, TrackerState, update_tracker

        spec = TrackerSpec()
        state = update_tracker(spec, TrackerState.initial(spec), 0.0, (1.0, 1.0, 0.3), beams,
                               scan_of((1.0, 1.0, 0.3)), 3.0, room)  # fmt: skip
        state = update_tracker(spec, state, time, sensor_pose, beam_angles, ranges, max_range,
                               room)  # fmt: skip
        tracks = state.tracks()
        finite(tracks.position, tracks.velocity, tracks.covariance)
        return tracks

    return {
        "DiffDrive": (wb.DiffDrive, {"wheel_radius": 0.05, "half_track": 0.2}),
        "Bicycle": (wb.Bicycle, {"wheel_base": 0.5, "max_steering": 0.6}),
        "RearWheelBicycle": (wb.RearWheelBicycle, {"wheel_base": 0.5, "max_steering": 0.6}),
        "Ackermann": (wb.Ackermann, {"wheel_base": 0.5, "track": 0.3, "max_steering": 0.6}),
        "mecanum4": (
            wb.mecanum4,
            {"wheel_radius": 0.05, "half_length": 0.2, "half_width": 0.15},
        ),
        "omni3": (wb.omni3, {"wheel_radius": 0.05, "base_radius": 0.2}),
        "Footprint.rectangle": (
            Footprint.rectangle,
            {"length": 0.6, "width": 0.4, "rear_axle_to_center": 0.1},
        ),
        "OccupancyGrid.from_array": (
            OccupancyGrid.from_array,
            {
                "occupied": np.zeros((3, 3)),
                "resolution": 0.1,
                "origin": (0.0, 0.0),
                "occupied_thresh": 0.5,
            },
        ),
        "HybridAStar.plan": (
            plan,
            {
                "footprint": (0.4, 0.3),
                "turning_radius": 0.5,
                "headings": 36,
                "xy_resolution": 0.2,
                "time_limit": 1.0,
                "curvatures": 3,
                "smooth": True,
            },
        ),
        "HybridAStar.plan(poses)": (
            plan_poses,
            {"start": (1.0, 1.0, 0.0), "goal": (3.0, 2.0, -6.12)},
        ),
        "MPPI": (
            mppi,
            {
                "horizon_steps": 10,
                "dt": 0.1,
                "samples": 32,
                "noise_std": 0.2,
                "temperature": 0.1,
                "critics": None,
                "limits": limits,
                "backend": "numpy",
                "seed": 0,
            },
        ),
        "MPPI(pose)": (mppi_pose, {"pose": (0.5, 0.5, -6.12), "reference": line}),
        "MPPI(perception)": (perceived, {"law": "mppi", **view_arguments}),
        "DWA(perception)": (perceived, {"law": "dwa", **view_arguments}),
        "DWA": (
            dwa,
            {
                "max_speed": 0.5,
                "min_speed": 0.0,
                "max_yaw_rate": 1.5,
                "max_acceleration": 2.5,
                "sim_time": 1.7,
                "sim_dt": 0.1,
                "v_samples": 5,
                "w_samples": 5,
                "path_dist": 640.0,
                "dynamic_inflation": 0.5,
                "oscillation": True,
                "goal_tolerance": (0.05, 0.25),
                "trajectory_generator": "standard",
            },
        ),
        "simulate": (
            simulate,
            {
                "pose0": (0.0, 0.0, 0.0),
                "inputs": (1.0, 0.8),
                "t_end": 1.0,
                "dt": 0.1,
                "method": "rk4",
            },
        ),
        "PurePursuit": (follow, {"speed": 0.3, "min_lookahead": 0.3, "lookahead_gain": 0.2}),
        "Kanayama": (track, {"k_x": 1.0, "k_y": 4.0, "k_theta": 2.0}),
        "Encoder": (wb.Encoder, {"pulses_per_revolution": 1024, "noise_std": 0.5, "seed": 1}),
        "SpeedLimits": (wb.SpeedLimits, {"max_speed": 0.5, "max_acceleration": 0.5}),
        "VelocityLimits": (VelocityLimits, {"max_speed": 0.5, "max_yaw_rate": 1.0}),
        "dubins_length": (
            dubins_length,
            {"start": (0.0, 0.0, 0.0), "goal": (2.0, 1.0, 1.0), "turning_radius": 1.0},
        ),
        "reeds_shepp_length": (
            reeds_shepp_length,
            {"start": (0.0, 0.0, 0.0), "goal": (2.0, 1.0, 1.0), "turning_radius": 1.0},
        ),
        "load_scenario": (wb.load_scenario, {"source": "demo"}),
        "Lidar.scan": (
            lidar,
            {
                "beams": 16,
                "fov": 6.0,
                "max_range": 3.0,
                "min_range": 0.05,
                "range_std": 0.01,
                "mount": (0.1, 0.0, 0.0),
            },
        ),
        "Lidar.scan(poses)": (lidar_poses, {"poses": [(1.0, 1.0, 0.3)], "method": "fast"}),
        "LandmarkSensor.observe": (
            landmarks,
            {
                "max_range": 3.0,
                "fov": 3.0,
                "range_std": 0.05,
                "bearing_std": 0.02,
                "detection_probability": 0.9,
                "false_rate": 0.5,
            },
        ),
        "Imu.read": (
            imu_read,
            {
                "gyro_noise_density": 1e-4,
                "gyro_bias_std": 1e-3,
                "accel_noise_density": 4e-3,
                "accel_bias_std": 0.1,
                "mount": (0.1, 0.0),
                "twist": [(0.5, 0.0, 0.2)],
            },
        ),
        "LandmarkSensor.observe(args)": (
            landmarks_args,
            {"landmarks": marks.tolist(), "poses": (1.0, 1.0, 0.3)},
        ),
        "EKF": (
            kalman,
            {"kind": "ekf", "range_std": 0.1, "bearing_std": 0.02, "gate_probability": 0.99},
        ),
        "UKF": (
            kalman,
            {"kind": "ukf", "range_std": 0.1, "bearing_std": 0.02, "gate_probability": 0.99},
        ),
        "EKF.update": (
            kalman_args,
            {
                "kind": "ekf",
                "mean": (1.0, 1.0, 0.3),
                "cov": np.eye(3) * 0.01,
                "ids": [0, 2],
                "z": [[0.7, -2.4], [0.8, 1.2]],
            },
        ),
        "UKF.update": (
            kalman_args,
            {
                "kind": "ukf",
                "mean": (1.0, 1.0, 0.3),
                "cov": np.eye(3) * 0.01,
                "ids": [0, 2],
                "z": [[0.7, -2.4], [0.8, 1.2]],
            },
        ),
        "AMCL": (
            amcl,
            {
                "min_particles": 50,
                "max_particles": 200,
                "kld_err": 0.05,
                "kld_delta": 0.01,
                "max_beams": 12,
                "z_hit": 0.5,
                "z_rand": 0.5,
                "sigma_hit": 0.2,
                "likelihood_max_dist": 2.0,
                "recovery_alpha_slow": 0.001,
                "recovery_alpha_fast": 0.1,
                "update_min_d": 0.25,
                "resample_interval": 1,
            },
        ),
        "CostmapSpec.from_mapping": (
            costmap,
            {
                "inflation_radius": 0.55,
                "cost_scaling_factor": 10.0,
                "obstacle_max_range": 2.5,
                "obstacle_min_range": 0.0,
                "raytrace_max_range": 3.0,
                "raytrace_min_range": 0.0,
                "window": 3.0,
                "resolution": 0.1,
                "track_unknown": False,
            },
        ),
        "update_costmap": (
            costmap_args,
            {
                "sensor_poses": [[1.0, 1.0, 0.3]],
                "beam_angles": beams,
                "ranges": np.full((1, 24), 1.5),
                "max_range": 3.0,
                "index": [1],
            },
        ),
        "TrackerSpec.from_mapping": (
            tracker,
            {
                "map_tolerance": 0.2,
                "cluster_distance": 0.3,
                "min_points": 2,
                "max_radius": 1.0,
                "measurement_std": 0.05,
                "process_noise": 0.5,
                "initial_speed_std": 1.0,
                "gate_probability": 0.99,
                "hits_to_confirm": 3,
                "misses_to_delete": 5,
                "max_tracks": 64,
            },
        ),
        "update_tracker": (
            tracker_args,
            {
                "time": 0.1,
                "sensor_pose": (1.0, 1.0, 0.3),
                "beam_angles": beams,
                "ranges": np.full(24, 1.5),
                "max_range": 3.0,
            },
        ),
        "AMCL.update": (
            amcl_args,
            {
                "odom": (0.3, 0.0, 0.0),
                "scan": np.full(12, 1.0),
                "pose": (1.0, 1.0, 0.3),
                "cov": np.eye(3) * 0.01,
            },
        ),
    }


_CONSTRUCTORS: dict[str, tuple[Callable[..., Any], dict[str, Any]]] = {}


def constructors() -> dict[str, tuple[Callable[..., Any], dict[str, Any]]]:
    """The constructor table (built once)."""
    if not _CONSTRUCTORS:
        _CONSTRUCTORS.update(_constructors())
    return _CONSTRUCTORS


@st.composite
def constructor_cases(draw) -> tuple[str, dict[str, Any]]:
    """(name, keyword arguments) with one or two arguments made hostile."""
    table = constructors()
    name = draw(st.sampled_from(sorted(table)))
    _function, arguments = table[name]
    kwargs = dict(arguments)
    value = st.one_of(
        st.sampled_from(HOSTILE),
        st.floats(allow_nan=True, allow_infinity=True),
        st.integers(-(2**70), 2**70),
    )
    for key in draw(st.lists(st.sampled_from(sorted(arguments)), min_size=1, max_size=2)):
        kwargs[key] = draw(value)
    return name, kwargs


def call_constructor(case: tuple[str, dict[str, Any]]) -> Any:
    """Call the constructor of a case."""
    name, kwargs = case
    return constructors()[name][0](**copy.deepcopy(kwargs))


# =========================================================================== CLI
# MRCLAM data set 6 where the tests find real data (an absent folder is a clean error too)
_MRCLAM = DATA / "mrclam"

# command → (required arguments, optional flags with their number of values)
CLI_COMMANDS: dict[str, tuple[list[str], dict[str, int]]] = {
    "simulate": (
        ["--no-gif", "--left", "1", "--right", "0.8", "--t-end", "2"],
        {
            "--model": 1,
            "--wheel-radius": 1,
            "--half-track": 1,
            "--left": 1,
            "--right": 1,
            "--v": 1,
            "--omega": 1,
            "--wheel-base": 1,
            "--speed": 1,
            "--steering": 1,
            "--max-steering": 1,
            "--t-end": 1,
            "--dt": 1,
            "--method": 1,
            "--pose0": 3,
            "--length": 1,
        },
    ),
    "control": (
        ["--start", "1", "1", "0", "--t-end", "5", "--dt", "0.05"],
        {
            "--law": 1,
            "--start": 3,
            "--goal": 3,
            "--max-speed": 1,
            "--max-yaw-rate": 1,
            "--t-end": 1,
            "--dt": 1,
        },
    ),
    "plan": (
        ["maze", "--start", "1", "1", "0", "--goal", "3", "1", "0"],
        {
            "--start": 3,
            "--goal": 3,
            "--turning-radius": 1,
            "--footprint": 2,
            "--rear-axle-to-center": 1,
            "--case": 1,
            "--headings": 1,
            "--xy-resolution": 1,
            "--collision-step": 1,
            "--time-limit": 1,
            "--resolution": 1,
        },
    ),
    "goto": (
        ["--goal", "0.5", "0.5"],
        {"--goal": 2, "--ed": 1, "--eb": 1, "--method": 1, "--seed": 1},
    ),
    "dynamics": (
        ["--no-gif", "--t-end", "2"],
        {"--torques": 2, "--t-end": 1, "--dt": 1, "--method": 1, "--preset": 1},
    ),
    "schema": ([], {}),
    "scenarios": ([], {}),
    "batch": (
        ["demo", "--seeds", "2"],
        {"--seeds": 1, "--workers": 1, "--chunk-size": 1, "--memory-mb": 1},  # not --scheduler
    ),
    "localize": (
        [str(_MRCLAM), "--robot", "1", "--filter", "ekf"],
        {"--robot": 1, "--filter": 1, "--seed": 1},
    ),
}


@st.composite
def cli_cases(draw) -> list[str]:
    """Arguments of one command (without ``--out``) with one to three flags made hostile."""
    command = draw(st.sampled_from(sorted(CLI_COMMANDS)))
    required, flags = CLI_COMMANDS[command]
    args = [command, *required]
    if flags:
        for flag in draw(st.lists(st.sampled_from(sorted(flags)), min_size=1, max_size=3)):
            values = [
                draw(st.one_of(st.sampled_from(HOSTILE_TEXT), st.text(max_size=6)))
                for _ in range(flags[flag])
            ]
            args += [flag, *values]
    return args


def run_cli(args: list[str]) -> Any:
    """Run ``wheelbase ARGS --out TMP``; raise unless it ended with code 0 or 2 and no exception
    escaped (exit code 2 is both the CLI's one-line errors and click's usage errors)."""
    from typer.testing import CliRunner

    from wheelbase.cli import app

    with tempfile.TemporaryDirectory() as folder:
        extra = [] if args[0] in ("schema", "scenarios") else ["--out", str(Path(folder) / "o")]
        result = CliRunner().invoke(app, [*args, *extra])
    if result.exception is not None and not isinstance(result.exception, SystemExit):
        raise result.exception
    if result.exit_code not in (0, 2):
        raise RuntimeError(f"exit code {result.exit_code}: {result.output[-300:]}")
    if "Traceback" in result.output:
        raise RuntimeError(f"a traceback was printed: {result.output[-300:]}")
    if result.exit_code == 2:
        raise CliRefused(result.output.strip()[-300:] or "exit code 2")
    return result


class CliRefused(WheelbaseError):
    """The CLI refused the arguments cleanly (exit code 2: one line, or click's usage)."""


_EXPLORATION_PATHS: list[tuple[str, ...]] = [
    ("map",), ("world",), ("world", "map"), ("world", "agents"), ("exploration",),
    ("exploration", "min_frontier_size"), ("exploration", "max_legs"),
    ("exploration", "resolution"), ("exploration", "initial_scans"),
    ("exploration", "approach"), ("exploration", "distance_weight"),
    ("exploration", "leg_slack"), ("exploration", "slam"), ("exploration", "replan_distance"),
    ("exploration", "wall_fringe"),
    ("start",), ("goal",),
    ("sensors",), ("sensors", "lidar"), ("sensors", "lidar", "max_range"),
    ("sensors", "lidar", "beams"), ("duration",), ("dt",), ("plant",), ("controller", "law"),
    ("resources", "max_map_cells"), ("localization",),
]  # fmt: skip


@st.composite
def exploration_cases(draw) -> dict[str, Any]:
    """The bundled doorway exploration with one to three fields hostile, deleted or misspelt."""
    from wheelbase.exploration import bundled_explorations

    data = yaml.safe_load(bundled_explorations()["doorway"].read_text())
    for mutation in draw(st.lists(_mutation(_EXPLORATION_PATHS), min_size=1, max_size=3)):
        _apply(data, mutation)
    return data


def run_exploration(data: dict[str, Any]) -> Any:
    """Validate an exploration case as ``wheelbase explore`` does, then drive its first leg
    (``max_legs`` 1: a whole exploration is 10 s; the loop after the first leg repeats it)."""
    from wheelbase.exploration import explore, load_exploration

    scenario, spec = load_exploration(copy.deepcopy(data))
    return explore((scenario, spec.model_copy(update={"max_legs": 1})))
