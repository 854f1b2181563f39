"""Scenario validation: every bad field is a ScenarioError naming the field, its unit, what is
allowed and what was given; extreme but valid values are accepted (and headings wrapped)."""

import math

import numpy as np
import pytest

from wheelbase.errors import ScenarioError
from wheelbase.scenario import load_scenario

BASE = {
    "map": "empty",
    "robot": {"model": "diffdrive"},
    "odometry": {"mode": "perfect"},
    "start": [0.0, 0.0, 0.0],
    "goal": [2.0, 0.0, 0.0],
}


def _with(**changes):
    return {**BASE, **changes}


@pytest.mark.parametrize(
    ("change", "match"),
    [
        # planner options: only HybridAStar's keywords, and not those the scenario sets
        ({"planner": {"options": {"bogus": 1}}}, r"planner.options: unknown option 'bogus'.*"),
        (
            {"planner": {"options": {"turning_radius": 1.0}}},
            r"planner.options: 'turning_radius' .*planner.turning_radius",
        ),
        # goal tolerance: a negative one can never be met
        ({"goal_tolerance": [-0.1, 5.0]}, r"goal_tolerance: position must be > 0 m.*-0.1"),
        ({"goal_tolerance": [0.1, 0.0]}, r"goal_tolerance: heading must be in \(0, 180\] deg"),
        # steps: duration / dt is bounded (each step is a controller call and a log row)
        (
            {"dt": 1e-9},
            r"duration / dt = 1.2e\+11 steps.*resources.max_steps = 1000000",
        ),
        # coordinates: finite is not enough, float64 keeps micrometres only up to 1e10 m
        ({"goal": [1e300, 0.0, 0.0]}, r"goals: .*within ±1e\+10 m.*1e\+300"),
        ({"start": [0.0, -2e10, 0.0]}, r"start: .*within ±1e\+10 m"),
        # the empty map around far-apart points would not fit in memory
        ({"goal": [1e6, 0.0, 0.0]}, r"map: empty .* 2.4e\+09 cells.*resources.max_map_cells"),
        # seeds drive 64-bit counters
        ({"seed": 2**64}, r"seed: .*less than or equal to 18446744073709551615"),
    ],
)
def test_bad_fields_are_scenario_errors(change, match):
    with pytest.raises(ScenarioError, match=match):
        load_scenario(_with(**change))


def test_known_planner_options_pass_to_the_planner_unchanged():
    scenario = load_scenario(_with(planner={"options": {"headings": 36, "time_limit": 2.0}}))
    assert scenario.planner.options == {"headings": 36, "time_limit": 2.0}


def test_limits_can_be_raised():
    far = _with(goal=[1e5, 0.0, 0.0])  # 2.4e8 cells: over the default 1e8
    with pytest.raises(ScenarioError, match="max_map_cells"):
        load_scenario(far)
    assert load_scenario({**far, "resources": {"max_map_cells": 10**9}}).goals[0][0] == 1e5
    fine = _with(dt=1e-4, duration=200.0, resources={"max_steps": 2_000_000})
    assert load_scenario(fine).dt == 1e-4


def test_extreme_but_valid_coordinates_are_accepted():
    far = 4.5e9
    scenario = load_scenario(_with(start=[far, far, 0.0], goal=[far + 2.0, far, 0.0]))
    assert scenario.start[0] == far


@pytest.mark.parametrize(
    ("given", "wrapped"), [(-350.6, 9.4), (540.0, 180.0), (-180.0, 180.0), (725.0, 5.0)]
)
def test_headings_are_wrapped_on_entry(given, wrapped):
    data = {**_with(start=[0.0, 0.0, given]), "goal": [2.0, 0.0, given]}
    scenario = load_scenario(data)
    assert math.isclose(scenario.start[2], wrapped, abs_tol=1e-9)
    assert all(math.isclose(g[2], wrapped, abs_tol=1e-9) for g in scenario.goals)


@pytest.mark.parametrize(
    ("content", "match"),
    [
        (
            b"name: caf\xe9\nstart: [0, 0, 0]\n",
            r"bad.yaml: not UTF-8 text \(byte 0xe9 at offset 9\)",
        ),
        (b"seed: " + b"9" * 5000 + b"\n", r"bad.yaml: unreadable YAML: .*4300 digits"),
        (b"start: " + b"[" * 5000 + b"]" * 5000 + b"\n", r"bad.yaml: (unreadable|malformed) YAML"),
    ],
    ids=["latin-1", "5000-digit-integer", "nested-5000-deep"],
)
def test_unreadable_files_are_scenario_errors(tmp_path, content, match):
    path = tmp_path / "bad.yaml"
    path.write_bytes(content)
    with pytest.raises(ScenarioError, match=match):
        load_scenario(path)


def test_tick_noise_is_per_tick_difference_and_accumulates():
    # What tick_noise_std is: Gaussian noise (rounded) on each tick difference, i.e. at every
    # step dt, so the count wanders as a random walk (variance grows with the number of reads);
    # the schema and the encoder say so.
    from wheelbase.odometry import Encoder
    from wheelbase.scenario import scenario_json_schema

    sigma, reads, runs = 2.0, 200, 4000
    encoder = Encoder(1024, noise_std=sigma)
    angles = np.zeros((reads + 1, runs))  # the wheel does not turn
    counts = encoder.measure(angles, np.random.default_rng(1))
    variance = np.var(counts[1:], axis=1)  # across runs, after 1..reads reads
    per_read = sigma**2 + 1 / 12  # rounding adds ~1/12 tick²
    slope = np.polyfit(np.arange(1, reads + 1), variance, 1)[0]
    assert slope == pytest.approx(per_read, rel=0.05)
    schema = scenario_json_schema()["$defs"]["OdometrySpec"]["properties"]["tick_noise_std"]
    assert "each tick difference" in schema["description"]
    assert "random walk" in schema["description"]
    assert "each tick difference" in " ".join(Encoder.__doc__.split())


@pytest.mark.parametrize("source", [True, 3, -math.inf, [], None])
def test_a_source_that_is_not_a_file_name_or_mapping(source):
    with pytest.raises(ScenarioError, match="a scenario is a file path, a bundled name or a"):
        load_scenario(source)
