"""MPPI (issue 9): cross-backend agreement, softmin, warm start, smoothing, safe stop, errors,
and the closed-loop evaluation (figure-eight tracking, clearance on the cluttered map)."""

from __future__ import annotations

import builtins
import json
import math
import subprocess
import sys
from importlib import resources
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from control_cases import figure_eight_reference, three_point_turn_path
from wheelbase.control import (
    MPPI,
    MPPICritics,
    PurePursuit,
    SteeringLimits,
    VelocityLimits,
)
from wheelbase.errors import ConfigError, InputError
from wheelbase.models import (
    Bicycle,
    BodyTwist,
    DiffDrive,
    RearWheelBicycle,
    Unicycle,
    mecanum4,
)
from wheelbase.planning import Footprint, OccupancyGrid, PlannedPath, load_map
from wheelbase.sim import closed_loop

LIMITS = VelocityLimits(max_speed=0.5, max_yaw_rate=1.5)
STRAIGHT = PlannedPath.from_points([[1.0, 4.0], [11.0, 4.0]])  # the cluttered map's reference path
ROBOT = Footprint.rectangle(0.4, 0.4)


@pytest.fixture(scope="module")
def cluttered():
    path = Path(str(resources.files("wheelbase") / "data" / "maps" / "cluttered.yaml"))
    return load_map(path)


def make(backend="numpy", samples=64, steps=20, **options):
    options.setdefault("seed", 3)
    return MPPI(Unicycle(), steps, 0.05, samples, (0.2, 0.5), 0.03, None, LIMITS,
                backend=backend, **options)  # fmt: skip


def backends():
    out = ["numpy", "numba"]
    try:
        import jax  # noqa: F401

        out.append("jax")
    except ImportError:
        pass
    return out


# --------------------------------------------------------------------------- backends agree
@pytest.mark.parametrize(
    ("model", "limits", "reference", "pose"),
    [
        (Unicycle(), LIMITS, STRAIGHT, (2.6, 3.9, 0.2)),
        (DiffDrive(0.05, 0.2), LIMITS, STRAIGHT, (5.2, 4.3, -0.3)),
        (
            RearWheelBicycle(wheel_base=0.3, max_steering=0.6),
            SteeringLimits(0.5, max_speed=0.5),
            PlannedPath.from_points([[2.0, 4.0], [4.0, 4.0], [3.0, 4.0]], [1, -1]),
            (3.7, 4.05, 0.0),
        ),
        (
            Bicycle(wheel_base=0.3, max_steering=0.6),
            SteeringLimits(0.5, max_speed=0.5),
            STRAIGHT,
            (5.0, 3.8, 0.4),
        ),
        (BodyTwist(), LIMITS, STRAIGHT, (2.6, 3.9, 0.2)),
        (mecanum4(0.05, 0.2, 0.15), LIMITS, STRAIGHT, (5.2, 4.3, 1.2)),
    ],
    ids=["unicycle", "diffdrive", "bicycle_cusp", "front_bicycle", "body_twist", "mecanum"],
)
def test_backends_agree_on_the_command(cluttered, model, limits, reference, pose):
    names = backends()
    sigma = (0.2, 0.4) if len(model.input_names) == 2 else (0.2, 0.2, 0.4)
    controllers = {
        name: MPPI(
            model,
            24,
            0.05,
            128,
            sigma,
            0.05,
            {"twirl": 1.0},
            limits,
            backend=name,
            grid=cluttered,
            footprint=ROBOT,
            jax_float64=True,
        )
        for name in names
    }
    rng = np.random.default_rng(7)
    for _ in range(3):  # three calls: the warm start is carried the same way
        noise = rng.standard_normal((128, 24, len(sigma))) * sigma
        plans = {name: c.plan(pose, reference, noise) for name, c in controllers.items()}
        reference_plan = plans["numpy"]
        for plan in plans.values():
            np.testing.assert_allclose(plan.costs, reference_plan.costs, rtol=1e-9, atol=1e-9)
            np.testing.assert_allclose(plan.command, reference_plan.command, atol=1e-5)
            np.testing.assert_allclose(plan.controls, reference_plan.controls, atol=1e-5)


def test_numba_noise_is_reproducible_and_seeded():
    pose = (1.2, 4.0, 0.0)
    a = make("numba", seed=1).plan(pose, STRAIGHT).command
    b = make("numba", seed=1).plan(pose, STRAIGHT).command
    c = make("numba", seed=2).plan(pose, STRAIGHT).command
    np.testing.assert_array_equal(a, b)
    assert not np.array_equal(a, c)


def test_numba_noise_is_standard_normal():
    from wheelbase.control.mppi_numba import NORMAL_TABLE as _NORMAL_TABLE
    from wheelbase.control.mppi_numba import _normal_pair

    draws = np.array([_normal_pair(np.uint64(5), np.uint64(0), np.uint64(i), np.uint64(0),
                                   _NORMAL_TABLE) for i in range(20000)])  # fmt: skip
    assert abs(draws.mean()) < 0.02
    assert abs(draws.std() - 1.0) < 0.02
    assert abs(np.corrcoef(draws[:, 0], draws[:, 1])[0, 1]) < 0.03


# --------------------------------------------------------------------------- MPPI identities
@pytest.mark.parametrize("temperature", [1e-12, 1e-3, 1.0, 1e12])
def test_softmin_never_overflows(cluttered, temperature):
    mppi = MPPI(Unicycle(), 20, 0.05, 64, (0.2, 0.5), temperature, None, LIMITS,
                grid=cluttered, footprint=ROBOT)  # fmt: skip
    plan = mppi.plan((2.6, 3.9, 0.2), STRAIGHT)
    assert np.all(np.isfinite(plan.weights)) and np.all(np.isfinite(plan.command))
    assert math.isclose(plan.weights.sum(), 1.0, rel_tol=1e-12)
    assert plan.weights[np.argmin(plan.costs)] == plan.weights.max()


def test_tiny_temperature_picks_the_best_sample():
    mppi = MPPI(Unicycle(), 20, 0.05, 64, (0.2, 0.5), 1e-9, None, LIMITS, savgol_window=0)
    noise = np.random.default_rng(0).standard_normal((64, 20, 2)) * (0.2, 0.5)
    plan = mppi.plan((1.0, 4.1, 0.0), STRAIGHT, noise)
    # a forward path section: the speed is sampled in [0, max_speed]
    best = np.clip(noise[np.argmin(plan.costs)], (0.0, -1.5), (0.5, 1.5))
    np.testing.assert_allclose(plan.controls, best, atol=1e-12)


def test_warm_start_is_shifted_by_one_step():
    mppi = make(savgol_window=0)
    first = mppi.plan((1.0, 4.1, 0.0), STRAIGHT)
    # zero noise: every sample is the warm start, so the new plan is the shifted old one
    second = mppi.plan((1.0, 4.1, 0.0), STRAIGHT, np.zeros((64, 20, 2)))
    expected = np.concatenate([first.controls[1:], first.controls[-1:]])
    np.testing.assert_allclose(second.controls, expected, atol=1e-15)
    np.testing.assert_allclose(second.command, expected[0], atol=1e-15)


def test_savitzky_golay_keeps_cubics_and_matches_scipy():
    from scipy.signal import savgol_filter

    mppi = make(steps=30)
    t = np.linspace(0.0, 1.0, 30)
    cubic = np.stack([0.1 + t - 2 * t**3, 0.5 * t**2], -1)
    np.testing.assert_allclose(mppi._smooth(cubic), cubic, atol=1e-12)
    rough = np.random.default_rng(1).normal(size=(30, 2))
    np.testing.assert_allclose(
        mppi._smooth(rough), savgol_filter(rough, 9, 3, axis=0, mode="interp"), atol=1e-12
    )


def test_constant_extra_critic_does_not_change_the_command():
    noise = np.random.default_rng(2).standard_normal((64, 20, 2)) * (0.2, 0.5)
    plain = make().plan((1.0, 4.1, 0.0), STRAIGHT, noise)
    critics = MPPICritics(extra=lambda poses, controls: np.full(poses.shape[0], 3.0))
    shifted = MPPI(Unicycle(), 20, 0.05, 64, (0.2, 0.5), 0.03, critics, LIMITS)
    plan = shifted.plan((1.0, 4.1, 0.0), STRAIGHT, noise)
    np.testing.assert_allclose(plan.costs, plain.costs + 3.0)
    np.testing.assert_allclose(plan.command, plain.command, atol=1e-12)


def test_extra_critic_steers_the_robot():
    # penalise the left half-plane: the robot turns right
    def right(poses, controls):
        return 50.0 * np.sum(np.maximum(poses[..., 1] - 4.0, 0.0), axis=1)

    mppi = MPPI(Unicycle(), 20, 0.05, 256, (0.2, 0.5), 0.03, {"extra": right}, LIMITS)
    for _ in range(5):
        command = mppi(0.0, (1.0, 4.0, 0.3), STRAIGHT)
    assert command[1] < 0.0
    bad = MPPI(Unicycle(), 20, 0.05, 16, (0.2, 0.5), 0.03,
               {"extra": lambda p, c: np.zeros(3)}, LIMITS)  # fmt: skip
    with pytest.raises(InputError, match="extra critic"):
        bad(0.0, (1.0, 4.0, 0.0), STRAIGHT)


def test_predicted_poses_follow_the_euler_step():
    mppi = make()
    plan = mppi.plan((1.0, 4.1, 0.3), STRAIGHT)
    poses = mppi.predict()
    x, y, th = 1.0, 4.1, 0.3
    for k, (v, omega) in enumerate(plan.controls):
        x, y, th = x + 0.05 * v * math.cos(th), y + 0.05 * v * math.sin(th), th + 0.05 * omega
        np.testing.assert_allclose(poses[k + 1], (x, y, th), atol=1e-12)


def test_all_samples_colliding_stops_safely(cluttered):
    mppi = make("numba", grid=cluttered, footprint=ROBOT)
    command = mppi(0.0, (3.5, 4.6, 0.0), STRAIGHT)  # inside a disc
    assert mppi.status == "all_collide"
    np.testing.assert_array_equal(command, [0.0, 0.0])
    assert np.all(np.isfinite(mppi.last_plan.weights))
    command = mppi(0.1, (2.6, 4.0, 0.0), STRAIGHT)
    assert mppi.status == "ok" and np.all(np.isfinite(command))


def test_batch_shape_and_one_robot_only():
    mppi = make()
    assert mppi(0.0, [[1.0, 4.0, 0.0]], STRAIGHT).shape == (1, 2)
    with pytest.raises(InputError, match="one robot"):
        mppi(0.0, np.zeros((2, 3)), STRAIGHT)


# --------------------------------------------------------------------------- bad input
@pytest.mark.parametrize(
    ("change", "match"),
    [
        ({"samples": 0}, "samples"),
        ({"horizon_steps": 0}, "horizon_steps"),
        ({"dt": -0.1}, "dt"),
        ({"temperature": 0.0}, "temperature"),
        ({"noise_std": (0.0, 0.5)}, "noise_std"),
        ({"critics": {"obstacle": -1.0}}, "obstacle"),
        ({"critics": {"nonsense": 1.0}}, "nonsense"),
        ({"critics": {"near_goal_distance": -1.0}}, "near_goal_distance"),
        ({"backend": "cuda"}, "backend"),
        ({"limits": VelocityLimits(max_speed=0.5)}, "finite"),
        ({"savgol_window": 4}, "savgol_window"),
        ({"approach_deceleration": 0.0}, "approach_deceleration"),
        # what a scenario file can put in the gains: strings, huge integers, inf
        ({"noise_std": "abc"}, r"noise_std must be 2 values > 0.*\(got 'abc'\)"),
        ({"seed": 2**70}, r"seed must be an integer in \[0, 18446744073709551615\]"),
        ({"seed": 1.5}, r"seed must be an integer"),
        ({"samples": 2.5}, r"samples must be an integer >= 1 \(got 2.5\)"),
        ({"savgol_window": math.inf}, r"savgol_window must be 0 or an odd integer >= 3"),
        ({"savgol_window": "x"}, r"savgol_window must be 0 or an odd integer >= 3"),
        ({"goal_tolerance": 0.1}, r"goal_tolerance must be \(position \[m\], heading \[rad\]\)"),
        ({"allow_reverse": "no"}, r"allow_reverse must be true or false \(got 'no'\)"),
        ({"jax_float64": "yes"}, r"jax_float64 must be true or false"),
        (
            {"samples": 10**6, "horizon_steps": 200},
            r"samples × horizon_steps = 2e\+08: more than max_sample_steps = 10000000",
        ),
        ({"dt": 1.56e154}, r"the horizon reaches 1.56e\+155 m .* more than 1e\+10 m"),
        (
            {"footprint": Footprint.rectangle(1e5, 1e5)},
            r"footprint .* needs 2e\+06 outline disks .* more than 100000",
        ),
    ],
)
def test_bad_parameters(change, match):
    args = dict(model=Unicycle(), horizon_steps=20, dt=0.05, samples=16, noise_std=(0.2, 0.5),
                temperature=0.1, critics=None, limits=LIMITS)  # fmt: skip
    args.update(change)
    with pytest.raises(ConfigError, match=match):
        MPPI(**args)


def test_sample_step_limit_can_be_raised():
    mppi = MPPI(Unicycle(), 10, 0.05, 100, 0.2, 0.1, None, LIMITS, max_sample_steps=1000)
    assert mppi.samples * mppi.horizon_steps == 1000
    with pytest.raises(ConfigError, match="max_sample_steps = 999"):
        MPPI(Unicycle(), 10, 0.05, 100, 0.2, 0.1, None, LIMITS, max_sample_steps=999)


@pytest.mark.parametrize(
    ("gains", "match"),
    [
        ({"max_steering": "abc"}, "max_steering"),
        ({"max_speed": "abc"}, "max_speed"),
        ({"critics": [1, 2]}, "critics must be a mapping"),
    ],
)
def test_from_gains_bad_values(gains, match):
    with pytest.raises(ConfigError, match=match):
        MPPI.from_gains(RearWheelBicycle(wheel_base=0.3, max_steering=0.6), **gains)


def test_numba_kernel_has_no_infinity_sentinels():
    # fastmath lets LLVM assume no value is ever inf or NaN: a comparison with an inf sentinel
    # (`best = np.inf; if d2 < best`) is then undefined. The kernel starts from finite ones.
    import inspect
    import re

    from wheelbase.control import dwa_kernels, footprint_field, mppi_numba, obstacle_critics

    for kernel in (mppi_numba.mppi_kernel, mppi_numba._nearest, footprint_field.clearance_at,
                   obstacle_critics.track_cost_at, dwa_kernels.dwa_kernel):  # fmt: skip
        source = inspect.getsource(kernel.py_func)
        assert not re.search(r"\b(np|math|numpy)\.inf\b|float\(.-?inf", source)


def test_unsupported_model():
    class Sledge:
        input_names = ("push", "pull")

    with pytest.raises(ConfigError, match="holonomic wheeled bases"):
        MPPI(Sledge(), 10, 0.05, 8, 0.2, 0.1, None, LIMITS)
    with pytest.raises(ConfigError, match="3 values"):
        MPPI(BodyTwist(), 10, 0.05, 8, (0.2, 0.4), 0.1, None, LIMITS)


def test_holonomic_bases_follow_the_path_and_use_their_lateral_speed():
    # A mecanum base facing +y follows a path along +x. With the default critics it turns to
    # the path and arrives; with the heading critics off it strafes more than it drives ahead.
    base = mecanum4(0.05, 0.2, 0.15)
    path = PlannedPath.from_points([[0.0, 0.0], [3.0, 0.0]])
    lateral = {}
    for critics in (None, {"path_align": 0.0, "goal_heading": 0.0, "twirl": 5.0}):
        mppi = MPPI(base, 30, 0.05, 300, (0.2, 0.2, 0.4), 0.03, critics, LIMITS,
                    backend="numba", goal_tolerance=(0.05, 3.2))  # fmt: skip
        assert mppi.command_names == ("vx", "vy", "omega")
        result = closed_loop(mppi, base, (0.0, 0.0, math.pi / 2), path, 20.0, 0.05)
        assert mppi.status == "arrived"
        assert np.hypot(*(result.true_pose[0, -1, :2] - path.points[-1])) <= 0.05
        assert path.distance(result.true_pose[0, :, :2]).max() < 0.05
        # the speed limit holds in every direction (no √2 on the diagonal)
        assert np.hypot(*result.command[0, :, :2].T).max() <= 0.5 + 1e-12
        commands = np.abs(result.command[0])
        lateral[critics is None] = commands[:, 1].mean() / commands[:, 0].mean()
    assert lateral[False] > 1.0 > lateral[True]


def test_nan_pose_and_bad_noise():
    mppi = make()
    with pytest.raises(InputError, match="pose"):
        mppi(0.0, (np.nan, 0.0, 0.0), STRAIGHT)
    with pytest.raises(InputError, match="noise"):
        mppi.plan((1.0, 4.0, 0.0), STRAIGHT, np.zeros((3, 20, 2)))


def test_jax_backend_missing_names_the_extra(monkeypatch):
    real_import = builtins.__import__

    def no_jax(name, *args, **kwargs):
        if name == "jax" or name.startswith("jax."):
            raise ImportError("no jax")
        return real_import(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", no_jax)
    with pytest.raises(ConfigError, match=r"wheelbase\[jax\]"):
        make("jax")


# --------------------------------------------------------------------------- closed loop
def lateral_errors(result, path, after=5.0):
    error = path.distance(result.true_pose[0, :, :2])[result.t >= after]
    return float(np.sqrt(np.mean(error**2))), float(np.max(error))


def test_figure_eight_tracking_beside_pure_pursuit():
    eight = PlannedPath.from_points(figure_eight_reference(30.0, 0.01).poses[::20, :2])
    start = np.array([1.1, 0.8, 0.0])
    pursuit = PurePursuit(speed=eight.length / 30.0, limits=LIMITS)
    pp = closed_loop(pursuit, Unicycle(), start, eight, 30.0, 0.05)
    mppi = MPPI(Unicycle(), 30, 0.05, 200, (0.2, 0.5), 0.03, None,
                VelocityLimits(max_speed=0.35, max_yaw_rate=1.5), backend="numba")  # fmt: skip
    result = closed_loop(mppi, Unicycle(), start, eight, 36.0, 0.05)
    rms, worst = lateral_errors(result, eight)
    rms_pp, worst_pp = lateral_errors(pp, eight)
    # measured 3.3 / 13 mm beside pure pursuit's 5.9 / 17 mm
    assert rms < rms_pp and worst < worst_pp
    assert result.metrics()[0]["reversals"] <= 2  # no twitching backwards on a forward path
    # went all the way round (the path is closed: its end is its start)
    assert result.metrics()[0]["distance_travelled_m"] > 0.97 * eight.length
    assert np.hypot(*(result.true_pose[0, -1, :2] - eight.points[-1])) < 0.05


def test_clearance_where_pure_pursuit_collides(cluttered):
    start = np.array([1.0, 4.0, 0.0])
    pp = closed_loop(PurePursuit(speed=0.4, limits=LIMITS), Unicycle(), start, STRAIGHT,
                         26.0, 0.1)  # fmt: skip
    assert cluttered.in_collision(ROBOT, pp.true_pose[0]).any()
    for seed in range(3):
        mppi = MPPI(Unicycle(), 30, 0.1, 200, (0.2, 0.5), 0.03, None, LIMITS, seed=seed,
                    backend="numba", grid=cluttered, footprint=ROBOT)  # fmt: skip
        result = closed_loop(mppi, Unicycle(), start, STRAIGHT, 30.0, 0.1)
        poses = result.true_pose[0]
        assert cluttered.footprint_clearance(ROBOT, poses).min() >= 0.1
        assert np.hypot(*(poses[-1, :2] - STRAIGHT.points[-1])) < 0.2


@pytest.mark.parametrize(
    ("model", "limits", "noise"),
    [
        (Unicycle(), VelocityLimits(0.3, 1.5), (0.2, 0.5)),
        (
            RearWheelBicycle(wheel_base=0.5, max_steering=math.radians(35.0)),
            SteeringLimits(math.radians(35.0), max_speed=0.3),
            (0.2, 0.3),
        ),
    ],
    ids=["unicycle", "bicycle"],
)
def test_cusp_path_reverses_and_arrives(model, limits, noise):
    path = three_point_turn_path()
    mppi = MPPI(model, 30, 0.05, 200, noise, 0.03, None, limits, backend="numba")
    result = closed_loop(mppi, model, (0.0, 0.05, 0.0), path, 40.0, 0.05)
    assert mppi.status == "arrived"
    assert np.hypot(*(result.true_pose[0, -1, :2] - path.points[-1])) <= 0.05
    # the two cusps (and a correction at the goal)
    assert 2 <= result.metrics()[0]["reversals"] <= 6
    # in the sections before the goal, the speed keeps the sign of the path section
    v = result.command[0, :, 0]
    near_goal = np.hypot(*(result.true_pose[0, : v.size, :2] - path.points[-1]).T) < 0.5
    section = np.cumsum(np.abs(np.diff(np.sign(v), prepend=1.0)) > 1.0)
    assert section[~near_goal].max() <= 2
    assert path.distance(result.true_pose[0, :, :2]).max() < 0.15
    np.testing.assert_array_equal(result.command[0, -2], [0.0, 0.0])


def test_progress_is_kept_when_the_path_is_a_fresh_array_each_call():
    """Seam: MPPI knows the path by its content; a fresh copy per call changes nothing."""
    path = three_point_turn_path()

    class FreshCopy:
        command_names = ("v", "omega")
        per_robot = True

        def __init__(self, law):
            self.law = law

        def reset(self):
            self.law.reset()

        def __call__(self, t, pose, reference):
            fresh = PlannedPath.from_points(reference.points.copy(), reference.directions[1:])
            return self.law(t, pose, fresh)

    def mppi():
        return MPPI(Unicycle(), 30, 0.05, 200, (0.2, 0.5), 0.03, None,
                    VelocityLimits(0.3, 1.5), backend="numba")  # fmt: skip

    same = closed_loop(mppi(), Unicycle(), (0.0, 0.05, 0.0), path, 40.0, 0.05)
    fresh = closed_loop(FreshCopy(mppi()), Unicycle(), (0.0, 0.05, 0.0), path, 40.0, 0.05)
    assert same.metrics()[0]["reversals"] >= 2  # it passed the cusps
    np.testing.assert_array_equal(fresh.true_pose, same.true_pose)


def test_from_gains_builds_the_limits_and_critics(cluttered):
    mppi = MPPI.from_gains(Unicycle(), grid=cluttered, footprint=ROBOT, samples=32,
                           horizon_steps=10, max_speed=0.4, obstacle=30.0,
                           critics={"effort": 0.5})  # fmt: skip
    assert mppi.samples == 32 and mppi.horizon_steps == 10 and mppi.backend == "numba"
    assert mppi.critics.obstacle == 30.0 and mppi.critics.effort == 0.5
    np.testing.assert_array_equal(mppi._hi, [0.4, 1.5])
    bike = RearWheelBicycle(wheel_base=0.5, max_steering=0.6)
    steered = MPPI.from_gains(bike, samples=16, horizon_steps=8)
    assert steered.command_names == ("speed", "steering")
    np.testing.assert_array_equal(steered._hi, [0.5, 0.6])
    with pytest.raises(ConfigError, match="horizon"):
        MPPI.from_gains(Unicycle(), horizon=10)


def test_jax_float32_is_close_to_the_float64_reference():
    pytest.importorskip("jax")
    noise = np.random.default_rng(4).standard_normal((64, 20, 2)) * (0.2, 0.5)
    reference = make("numpy").plan((2.6, 3.9, 0.2), STRAIGHT, noise)
    single = make("jax").plan((2.6, 3.9, 0.2), STRAIGHT, noise)
    np.testing.assert_allclose(single.costs, reference.costs, rtol=1e-4, atol=1e-4)
    np.testing.assert_allclose(single.command, reference.command, atol=1e-3)


def test_jax_on_a_gpu_reduces_on_the_device_and_agrees(monkeypatch, cluttered):
    # On a GPU the weighted mean is taken on the device; the command is the same.
    jax = pytest.importorskip("jax")
    noise = np.random.default_rng(2).standard_normal((128, 24, 2)) * (0.2, 0.4)
    reference = make("numpy", samples=128, steps=24, grid=cluttered, footprint=ROBOT)
    expected = [reference.plan((2.6, 3.9, 0.2), STRAIGHT, noise) for _ in range(2)]
    monkeypatch.setattr(jax, "default_backend", lambda: "gpu")
    device = make("jax", samples=128, steps=24, grid=cluttered, footprint=ROBOT,
                  jax_float64=True)  # fmt: skip
    for want in expected:
        got = device.plan((2.6, 3.9, 0.2), STRAIGHT, noise)
        np.testing.assert_allclose(got.costs, want.costs, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(got.controls, want.controls, atol=1e-9)
        np.testing.assert_allclose(got.samples, want.samples, atol=1e-12)


def test_jax_draws_its_noise_on_the_device(monkeypatch):
    # On a GPU the noise is drawn inside the compiled function; pretend to be on one.
    jax = pytest.importorskip("jax")
    monkeypatch.setattr(jax, "default_backend", lambda: "gpu")
    wide = VelocityLimits(max_speed=50.0, max_yaw_rate=50.0)

    def samples(seed):
        mppi = MPPI(Unicycle(), 20, 0.05, 4000, (0.2, 0.5), 0.03, None, wide, seed=seed,
                    backend="jax", reverse_against_path=True, approach_deceleration=1e6,
                    savgol_window=0)  # fmt: skip
        first = mppi.plan((5.0, 4.0, 0.0), STRAIGHT).samples
        return first, mppi.plan((5.0, 4.0, 0.0), STRAIGHT).samples

    first, second = samples(7)
    assert first.shape == (256, 20, 2)  # the rest of the 4,000 samples stay on the device
    # the first call perturbs a zero warm start: the samples are the noise itself
    np.testing.assert_allclose(first.reshape(-1, 2).std(axis=0), (0.2, 0.5), rtol=0.02)
    np.testing.assert_allclose(first.reshape(-1, 2).mean(axis=0), 0.0, atol=0.01)
    again, _ = samples(7)
    np.testing.assert_array_equal(first, again)  # seeded
    assert not np.allclose(first, samples(8)[0])
    assert not np.allclose(first - first.mean(0), second - second.mean(0))  # new noise per call


@settings(
    max_examples=25, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(
    temperature=st.sampled_from([5e-324, 1e-300, 1e-3, 1.0, 1e300, 1.7e308]),
    x=st.floats(0.5, 11.5),
    y=st.floats(0.5, 7.5),
    theta=st.floats(-math.pi, math.pi),
)
def test_command_is_finite_and_within_limits(cluttered, temperature, x, y, theta):
    mppi = MPPI(Unicycle(), 12, 0.05, 32, (0.2, 0.5), temperature, None, LIMITS,
                backend="numba", grid=cluttered, footprint=ROBOT)  # fmt: skip
    plan = mppi.plan((x, y, theta), STRAIGHT)
    assert np.all(np.isfinite(plan.command)) and np.all(np.isfinite(plan.weights))
    assert abs(plan.command[0]) <= 0.5 and abs(plan.command[1]) <= 1.5
    if plan.status == "all_collide":
        np.testing.assert_array_equal(plan.command, [0.0, 0.0])


def test_benchmark_quick_prints_the_promised_json():
    script = Path(__file__).resolve().parents[1] / "benchmarks" / "mppi.py"
    done = subprocess.run([sys.executable, str(script), "--quick"], capture_output=True,
                          text=True, timeout=300, check=False)  # fmt: skip
    assert done.returncode == 0, done.stderr
    report = json.loads(done.stdout)
    rates = report["cpu_hz_2000x56"]
    assert rates["numpy"] > 0 and rates["numba"] > 0 and rates["numba_1_thread"] > 0
    laws = {(row["reference"], row["plant"], row["law"]) for row in report["tracking"]}
    assert ("figure_eight", "unicycle", "mppi") in laws
    assert ("figure_eight", "unicycle", "pure_pursuit") in laws
    clearance = report["clearance"]
    assert clearance["pure_pursuit_collides"] and clearance["mppi_success_rate"] == 1.0
    # the GPU keys are there, null with the reason where JAX sees no GPU
    for key in ("gpu_hz_2000x56", "gpu_hz_100000x56", "gpu_hz_1000000x56"):
        assert key in report
    assert report["gpu"].startswith("none") == (report["gpu_hz_2000x56"] is None)
    assert report["parking"]["seeds"] == 0  # the 4.5 m car runs only in the full benchmark
    assert report["default_backend"] == "numba"
    assert rates["numba_with_view"] > 0 and rates["numpy_with_view"] > 0
    assert report["crowd"]["head_on"]["collisions"] == 0


def test_closed_path_is_driven_round_before_arriving():
    # the figure-eight ends where it starts: arriving needs the progress near the end too
    eight = PlannedPath.from_points(figure_eight_reference(30.0, 0.01).poses[::20, :2])
    mppi = MPPI(Unicycle(), 30, 0.05, 200, (0.2, 0.4), 0.03, None,
                VelocityLimits(max_speed=0.35, max_yaw_rate=1.5), backend="numba",
                goal_tolerance=(0.2, 3.0))  # fmt: skip
    result = closed_loop(mppi, Unicycle(), (1.1, 0.8, 0.0), eight, 3.0, 0.05)
    assert mppi.status == "ok" and result.metrics()[0]["distance_travelled_m"] > 0.5


def test_speed_is_capped_into_a_cusp():
    # 2 cm before the cusp of a forward-then-reverse path: |v| <= √(2·a·d) with a = 0.5 m/s²
    path = PlannedPath.from_points([[0.0, 0.0], [2.0, 0.0], [1.0, 0.0]], [1, -1])
    mppi = make(samples=200, approach_deceleration=0.5, cusp_tolerance=0.01)
    for _ in range(5):
        command = mppi(0.0, (1.98, 0.0, 0.0), path)
        assert 0.0 <= command[0] <= math.sqrt(2.0 * 0.5 * 0.02) + 1e-12
        plan = mppi.last_plan
        assert np.all(plan.samples[..., 0] >= 0.0)  # the forward section samples v >= 0


def test_cusp_is_passed_when_the_robot_crosses_its_line():
    # 8 cm beside the cusp (outside cusp_tolerance) but past it: the reverse section is active
    path = PlannedPath.from_points([[0.0, 0.0], [2.0, 0.0], [1.0, 0.0]], [1, -1])
    mppi = make(samples=100)
    mppi(0.0, (1.7, 0.0, 0.0), path)
    assert mppi._path.section == 0
    command = mppi(0.0, (2.01, 0.08, 0.0), path)
    assert mppi._path.section == 1 and command[0] <= 0.0


def test_reverse_against_path_samples_both_signs():
    mppi = make(samples=400, reverse_against_path=True)
    mppi(0.0, (2.0, 4.0, 0.0), STRAIGHT)
    assert np.any(mppi.last_plan.samples[..., 0] < 0.0)


def test_goal_next_to_an_obstacle_is_reached(cluttered):
    # The goal's footprint clearance is ~0.08 m, inside the 0.4 m inflation: with the obstacle
    # repulsion kept on to the end the robot is pushed 0.18 m aside; off within 1 m, it arrives.
    path = PlannedPath.from_points([[1.5, 4.0], [2.85, 4.0]])
    ends = {}
    for near in (0.0, 1.0):
        mppi = MPPI(Unicycle(), 30, 0.05, 200, (0.2, 0.4), 0.03, {"near_goal_distance": near},
                    LIMITS, backend="numba", grid=cluttered, footprint=ROBOT)  # fmt: skip
        result = closed_loop(mppi, Unicycle(), (1.5, 4.0, 0.0), path, 20.0, 0.05)
        assert not cluttered.in_collision(ROBOT, result.true_pose[0]).any()
        ends[near] = (mppi.status, np.hypot(*(result.true_pose[0, -1, :2] - path.points[-1])))
    assert ends[1.0][0] == "arrived" and ends[1.0][1] <= 0.05
    assert ends[0.0][0] != "arrived" and ends[0.0][1] > 0.1


def test_a_car_backs_up_to_a_wall_behind_it():
    # A 4.5 × 1.8 m car, 0.3 m in front of a wall behind it: its covering circles would reach
    # 0.56 m past its rear and call every rollout a collision; its outline disks do not.
    occupied = np.zeros((200, 200), bool)
    occupied[:, :20] = True  # wall: x < 1 m
    grid = OccupancyGrid.from_array(occupied, 0.05)
    car = Footprint.rectangle(4.5, 1.8, rear_axle_to_center=1.35)
    pose = np.array([1.0 + 0.9 + 0.3, 5.0, 0.0])  # rear bumper 0.3 m from the wall
    assert grid.footprint_clearance(car, pose[None])[0] == pytest.approx(0.3, abs=0.06)
    bike = RearWheelBicycle(wheel_base=2.7, max_steering=0.6)
    mppi = MPPI(bike, 30, 0.05, 200, (0.2, 0.3), 0.03, None, SteeringLimits(0.6, max_speed=1.0),
                backend="numba", grid=grid, footprint=car)  # fmt: skip
    reverse = PlannedPath.from_points([[2.2, 5.0], [6.0, 5.0]], [1])
    plan = mppi.plan(pose, reverse)
    assert plan.status == "ok" and plan.costs.min() < mppi.critics.collision_cost


def test_conservative_collisions_do_not_freeze_a_clear_robot():
    # The car's rear is 0.1 m from a wall: clear, but the critics' disks and their cell margin
    # (0.17 m) see it in collision. Only rollouts that get deeper count as collisions then.
    occupied = np.zeros((200, 200), bool)
    occupied[:, :20] = True  # wall: x < 1 m
    grid = OccupancyGrid.from_array(occupied, 0.05)
    car = Footprint.rectangle(4.5, 1.8, rear_axle_to_center=1.35)
    pose = np.array([1.0 + 0.9 + 0.1, 5.0, 0.0])
    assert not grid.in_collision(car, pose[None]).any()
    bike = RearWheelBicycle(wheel_base=2.7, max_steering=0.6)
    mppi = MPPI(bike, 30, 0.05, 200, (0.2, 0.3), 0.03, None, SteeringLimits(0.6, max_speed=1.0),
                backend="numba", grid=grid, footprint=car)  # fmt: skip
    now, _ = mppi._field.clearance(pose)
    assert now <= 0.0
    plan = mppi.plan(pose, PlannedPath.from_points([[2.0, 5.0], [6.0, 5.0]]))
    assert plan.status == "ok"
    best = mppi.predict(plan, plan.samples[np.argmin(plan.costs)])
    assert mppi._field.clearance(best)[0].min() >= now - 0.01
    # truly inside the wall, every rollout stays lethal: a safe stop
    assert mppi.plan(
        np.array([1.5, 5.0, 0.0]), PlannedPath.from_points([[2.0, 5.0], [6.0, 5.0]])
    ).status == ("all_collide")


def test_after_all_rollouts_collided_both_signs_are_sampled():
    occupied = np.zeros((200, 200), bool)
    occupied[:, :20] = True  # wall: x < 1 m, far from the path
    grid = OccupancyGrid.from_array(occupied, 0.05)
    path = PlannedPath.from_points([[5.0, 5.0], [9.0, 5.0]])
    mppi = make("numba", samples=400, grid=grid, footprint=ROBOT)
    mppi(0.0, (0.5, 5.0, 0.0), path)  # inside the wall
    assert mppi.status == "all_collide"
    mppi(0.1, (5.0, 5.0, 0.0), path)
    assert mppi.status == "ok"
    assert np.any(mppi.last_plan.samples[..., 0] < 0.0)  # backing off is allowed once
    mppi(0.2, (5.0, 5.0, 0.0), path)
    assert np.all(mppi.last_plan.samples[..., 0] >= 0.0)  # then forward only again


# --------------------------------------------------------------------------- extreme values
FAR = 4.5e9  # m: UTM-like and beyond; a multiple of float64's spacing there (2^-20 m)


def _shifted(grid, offset):
    return OccupancyGrid.from_array(grid.occupied, grid.resolution, np.add(grid.origin, offset))


@pytest.mark.parametrize("backend", [*backends(), "jax32"])
def test_same_commands_at_a_4_5e9_m_offset(cluttered, backend):
    # Every backend works relative to the robot: at 4.5e9 m the JAX float32 backend used to
    # cast absolute poses, path and map origin to float32 (512 m apart there), and float64 lost
    # the micrometres the costs compare. Inputs here are exact in float64 at both places.
    if backend.startswith("jax"):
        pytest.importorskip("jax")
    options = {"backend": backend[:3] if backend == "jax32" else backend,
               "jax_float64": backend == "jax"}  # fmt: skip
    far_path = PlannedPath.from_points(np.asarray(STRAIGHT.points) + FAR)
    near = make(samples=128, grid=cluttered, footprint=ROBOT, **options)
    far = make(samples=128, grid=_shifted(cluttered, FAR), footprint=ROBOT, **options)
    noise = np.random.default_rng(5).standard_normal((128, 20, 2)) * (0.2, 0.5)
    pose = np.array([2.5, 3.875, 0.25])
    for _ in range(3):
        a = near.plan(pose, STRAIGHT, noise)
        b = far.plan(pose + np.array([FAR, FAR, 0.0]), far_path, noise)
        np.testing.assert_allclose(b.costs, a.costs, rtol=1e-6, atol=1e-9)
        np.testing.assert_allclose(b.command, a.command, rtol=1e-6, atol=1e-9)
        pose = pose + np.array([0.25, 0.0, 0.0])


@pytest.mark.parametrize("backend", backends())
def test_headings_are_wrapped_on_entry(cluttered, backend):
    # -6.12 rad is 0.163 rad: the same robot, the same command (the numba kernel's one-step
    # wrap assumed (-π, π] on entry).
    noise = np.random.default_rng(6).standard_normal((64, 20, 2)) * (0.2, 0.5)
    a = make(backend, grid=cluttered, footprint=ROBOT, jax_float64=True)
    b = make(backend, grid=cluttered, footprint=ROBOT, jax_float64=True)
    wrapped = -6.12 + 2 * math.pi
    first = a.plan((2.5, 3.9, wrapped), STRAIGHT, noise)
    second = b.plan((2.5, 3.9, -6.12), STRAIGHT, noise)
    np.testing.assert_allclose(second.costs, first.costs, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(second.command, first.command, atol=1e-9)


def test_a_huge_step_keeps_the_path_window_to_the_path():
    # dt = 157409 s reached 9.4e5 m ahead: a window of 1.9e7 path points (9 GiB); the window
    # never holds more than the path has.
    mppi = MPPI(Unicycle(), 10, 157409.0, 32, 0.2, 0.1, None, LIMITS)
    assert mppi(0.0, (0.5, 0.0, 0.0), STRAIGHT).shape == (2,)
    assert mppi._path.window_points * 0.05 <= 1.2 * STRAIGHT.length + 0.2


def test_a_long_horizon_smooths_without_a_horizon_squared_matrix():
    # 130,539 steps made a 127 GiB Savitzky–Golay matrix; long horizons filter directly.
    from scipy.signal import savgol_filter

    mppi = MPPI(Unicycle(), 130_539, 0.1, 2, 0.2, 0.1, None, LIMITS, savgol_window=9)
    sequence = np.random.default_rng(0).standard_normal((130_539, 2))
    expected = savgol_filter(sequence, 9, 3, axis=0, mode="interp")
    np.testing.assert_allclose(mppi._smooth(sequence), expected, atol=1e-12)
    short = make(steps=20)
    small = np.random.default_rng(1).standard_normal((20, 2))
    np.testing.assert_allclose(
        short._smooth(small), savgol_filter(small, 9, 3, axis=0, mode="interp"), atol=1e-12
    )


@pytest.mark.parametrize("step", [0.01, 0.025, 0.05, 0.2])
def test_the_path_window_holds_its_reach_however_finely_the_path_is_sampled(step):
    from wheelbase.control.local_path import PathWindow

    # a Hybrid A* path comes every 0.025 m: a window counted in points of the 0.05 m spacing
    # held 1.75 m instead of 3.5 m, and the robot never went faster than half its top speed
    reach = 3.5
    x = np.arange(0.0, 20.0 + step / 2, step)
    path = PlannedPath.from_points(np.stack([x, 0.3 * np.sin(x / 3.0)], -1))
    window = PathWindow(0.05, reach, 0.5, 0.05)
    tables = window.tables(path)
    cut, _info = window.window(np.array([4.0, 0.3 * math.sin(4.0 / 3.0), 0.0]), tables)
    assert reach - max(step, 0.05) <= cut[-1, 3] <= reach + 1e-9
    assert np.all(np.diff(cut[:, 3]) >= 0.0)


def test_mppi_reaches_its_top_speed_on_a_finely_sampled_straight_path():
    x = np.arange(0.0, 12.0 + 1e-9, 0.025)
    path = PlannedPath.from_points(np.stack([x, np.zeros_like(x)], -1))
    mppi = MPPI.from_gains(Unicycle(), samples=300, max_speed=1.0, seed=3)
    result = closed_loop(mppi, Unicycle(), np.array([0.0, 0.0, 0.0]), path, 6.0, 0.05)
    speed = result.twist[0, 40:100, 0]  # 2-5 s: past the start, before the goal's approach
    assert speed.mean() > 0.85  # measured 0.6 m/s with the window counted in points
