"""General PID and computed-torque PID tracking (document 000 §5.3)."""

import math

import numpy as np
import pytest

from wheelbase.control.pid import PID
from wheelbase.control.torque import ComputedTorquePID, TorqueGains
from wheelbase.dynamics import RM100, _step, inverse_dynamics
from wheelbase.errors import ConfigError, InputError
from wheelbase.sim import track_trajectory, tune_computed_torque
from wheelbase.trajectory import feasible_trajectory, heading_from_velocity, trapezoidal

DOC = [[0, 0], [10, 10], [20, 0], [30, 0]]
REF = feasible_trajectory(DOC, (0.1, 0.1))


# --------------------------------------------------------------------------- PID
def test_pid_closed_forms():
    pid = PID(kp=2.0, ki=0.5, kd=0.0)
    assert pid.update(1.0, 0.0, 0.1) == pytest.approx(2.0)  # integral starts at 0
    assert pid.update(1.0, 0.0, 0.1) == pytest.approx(2.0 + 0.5 * 1.0 * 0.1)
    pid.reset()
    assert pid.update(1.0, 0.0, 0.1) == pytest.approx(2.0)


def test_pid_derivative_on_measurement_has_no_setpoint_kick_and_is_filtered():
    pid = PID(kp=1.0, kd=1.0)
    pid.update(0.0, 0.0, 0.1)
    assert pid.update(5.0, 0.0, 0.1) == pytest.approx(5.0)  # setpoint step: P only, no kick
    # a measurement ramp of slope 2: unfiltered D = −2 at once; filtered D → −2 as 1 − e^{-t/T_f}
    filt = PID(kp=0.0, kd=1.0, derivative_filter=1.0)
    raw = PID(kp=0.0, kd=1.0)
    dt, outs = 0.01, []
    for k in range(301):
        outs.append(filt.update(0.0, 2.0 * k * dt, dt))
        last_raw = raw.update(0.0, 2.0 * k * dt, dt)
    assert last_raw == pytest.approx(-2.0)
    assert outs[-1] == pytest.approx(-2.0 * (1 - math.exp(-3.0)), rel=2e-2)
    assert filt.update(0.0, 0.0, dt, measurement_rate=0.0) > outs[-1]  # given rate is used


def test_pid_anti_windup():
    clamp = PID(kp=1.0, ki=1.0, output_limits=(-1.0, 1.0))
    back = PID(kp=1.0, ki=1.0, output_limits=(-1.0, 1.0), anti_windup="back-calculation")
    none = PID(kp=1.0, ki=1.0, output_limits=(-1.0, 1.0), anti_windup="none")
    for _ in range(100):
        for pid in (clamp, back, none):
            assert abs(pid.update(10.0, 0.0, 0.1)) <= 1.0
    assert clamp.integral == 0.0  # never integrated while saturated
    assert none.integral == pytest.approx(100.0)
    # back-calculation: İ = e + (u_sat − u)/T_t → I settles where 10 + (1 − 10 − I)/1 = 0
    assert back.integral == pytest.approx(1.0, abs=1e-3)
    # after the setpoint comes back, the wound-up one stays saturated much longer
    assert clamp.update(0.5, 0.0, 0.1) < 1.0 and none.update(0.5, 0.0, 0.1) == 1.0


def test_pid_vector_channels_and_bad_input():
    pid = PID(kp=[1.0, 2.0], ki=0.0)
    np.testing.assert_allclose(pid.update([1.0, 1.0], [0.0, 0.5], 0.1), [1.0, 1.0])
    with pytest.raises(ConfigError, match="kp"):
        PID(kp=-1.0)
    with pytest.raises(ConfigError, match="output_limits"):
        PID(output_limits=(1.0, -1.0))
    with pytest.raises(ConfigError, match="anti_windup"):
        PID(anti_windup="reset")
    with pytest.raises(ConfigError, match="dt"):
        PID().update(0.0, 0.0, 0.0)


# --------------------------------------------------------------------------- computed torque
def test_zero_error_gives_the_inverse_dynamics_torques():
    ctrl = ComputedTorquePID(RM100)
    ref = REF.at([160.0, 200.0])
    inv = inverse_dynamics(RM100, ref)
    for k in range(2):
        row = ref.reference()[k]
        state = row[:6].copy()
        np.testing.assert_allclose(ctrl(ref.t[k], state, row), inv.torques[k], atol=1e-15)


def test_compiled_loop_matches_step_by_step_calls():
    model = RM100.with_body(RM100.body.scaled(1.2, 0.8))
    ctrl = ComputedTorquePID(model, derivative_filter=0.05, max_torque=0.02)
    fast = track_trajectory(RM100, REF, ctrl, dt=0.05, t_end=40.0)
    ctrl.reset()
    states = np.concatenate([fast.true_pose[0], fast.twist[0]], axis=-1)
    state = states[0].copy()
    work = [np.empty(6) for _ in range(5)]
    for k in range(40):
        tau = ctrl(fast.t[k], state, REF)  # dt: the time since the previous call, as in a loop
        np.testing.assert_allclose(tau, fast.torques[0, k], atol=1e-12)
        _step(state, tau[0], tau[1], RM100.params, 0.05, 1, *work)
        np.testing.assert_allclose(state, states[k + 1], atol=1e-12)


def test_along_track_error_decays_with_the_placed_triple_pole():
    ref = feasible_trajectory([[0, 0], [10, 0]], 0.1)
    w, e0 = 0.8, 0.01
    ctrl = ComputedTorquePID(RM100, TorqueGains.pole_placement(w))
    run = track_trajectory(RM100, ref, ctrl, dt=0.002, state0=[-e0, 0, 0, 0, 0, 0], t_end=15.0)
    t = run.t
    expected = e0 * (1 + w * t - (w * t) ** 2) * np.exp(-w * t)  # (s + ω)³, z = ∫e
    error = run.reference_pose[0, :, 0] - run.true_pose[0, :, 0]
    np.testing.assert_allclose(error, expected, atol=2e-5)
    np.testing.assert_allclose(run.true_pose[0, :, 1:3], 0.0, atol=1e-12)


def test_issue_targets_on_the_feasible_document_trajectory():
    """Table of the issue: open loop vs PID, exact model and ±20 % mass and inertia."""
    exact = track_trajectory(RM100, REF, ComputedTorquePID(RM100)).metrics()[0]
    assert exact["tracking_max_position_error_m"] < 0.01
    assert exact["tracking_rms_heading_error_deg"] < 0.5
    for factor in (0.8, 1.2):
        wrong = RM100.with_body(RM100.body.scaled(factor, factor))
        pid = track_trajectory(RM100, REF, ComputedTorquePID(wrong)).metrics()[0]
        assert pid["tracking_max_position_error_m"] < 0.05
        open_loop = track_trajectory(RM100, REF, model=wrong).metrics()[0]
        assert (
            open_loop["tracking_max_position_error_m"] > 100 * pid["tracking_max_position_error_m"]
        )


def test_a_tracking_run_that_completes_its_reference_arrives_or_misses():
    # The reference's end is the arrival: the PID ends within micrometres (arrived), the open
    # loop half a metre off (missed_goal, not a timeout); a run cut short times out.
    pid = track_trajectory(RM100, REF, ComputedTorquePID(RM100))
    open_loop = track_trajectory(RM100, REF)
    assert pid.statuses == ["arrived"] and open_loop.statuses == ["missed_goal"]
    assert pid.metrics()[0]["final_position_error_true_m"] < 1e-4
    assert open_loop.metrics()[0]["final_position_error_true_m"] > 0.05
    np.testing.assert_allclose(pid.end_time, REF.duration, atol=0.011)
    early = track_trajectory(RM100, REF, ComputedTorquePID(RM100), t_end=100.0)
    assert early.statuses == ["timeout"]
    loose = track_trajectory(RM100, REF, tolerance=(1.0, math.pi))
    assert loose.statuses == ["arrived"]  # within a metre, any heading


def test_open_loop_on_the_documents_heading_jumps_misses_by_metres():
    doc = heading_from_velocity(trapezoidal(DOC, (0.1, 0.1)))
    run = track_trajectory(RM100, doc)
    assert run.metrics()[0]["tracking_max_position_error_m"] > 10.0
    # the robot never turns: it drives on along 45° (the torques have no yaw moment)
    np.testing.assert_allclose(run.true_pose[0, :, 2], math.pi / 4, atol=1e-12)


def test_anti_windup_limits_overshoot_under_torque_saturation():
    ref = feasible_trajectory([[0, 0], [10, 0]], 0.1)
    kwargs = {"dt": 0.01, "state0": [-0.5, 0, 0, 0, 0, 0], "t_end": 60.0}
    gains = TorqueGains.pole_placement(1.0)
    runs = [
        track_trajectory(
            RM100, ref, ComputedTorquePID(RM100, gains, max_torque=0.05, anti_windup=aw), **kwargs
        )
        for aw in (True, False)
    ]
    assert all(np.abs(r.torques).max() <= 0.05 + 1e-15 for r in runs)
    overshoot = [-(r.reference_pose[0, :, 0] - r.true_pose[0, :, 0]).min() for r in runs]
    assert overshoot[0] < 0.5 * overshoot[1]


def test_tuning_does_not_do_worse_than_its_start():
    model = RM100.with_body(RM100.body.scaled(1.2, 1.2))
    gains = tune_computed_torque(RM100, REF, model=model, horizon=20.0, dt=0.02)
    assert isinstance(gains, TorqueGains)
    run = track_trajectory(RM100, REF, ComputedTorquePID(model, gains)).metrics()[0]
    assert run["tracking_max_position_error_m"] < 0.01


def test_bad_controller_input():
    ctrl = ComputedTorquePID(RM100)
    with pytest.raises(InputError, match="twist"):
        ctrl(0.0, [0, 0, 0], REF)
    with pytest.raises(InputError, match="reference"):
        ctrl(0.0, np.zeros(6), [1.0, 2.0])
    with pytest.raises(ConfigError, match="max_torque"):
        ComputedTorquePID(RM100, max_torque=0.0)
    with pytest.raises(ConfigError, match="kp"):
        TorqueGains((-1, 0, 0), (0, 0, 0), (0, 0, 0))
    with pytest.raises(InputError, match="PoseTrajectory"):
        track_trajectory(RM100, [[0, 0]])


# --------------------------------------------------------------------------- command line
def _cli():
    import typer

    from wheelbase.commands.dynamics import register

    app = typer.Typer()

    @app.callback()
    def _main() -> None:
        """Test app."""

    register(app)
    return app


def test_track_waypoints_command_writes_metrics_matching_the_api(tmp_path):
    import json

    from typer.testing import CliRunner

    out = tmp_path / "run"
    args = ["track-waypoints", "--out", str(out), "--waypoints", "0,0 2,2 4,0",
            "--peak-velocity", "0.2", "--peak-yaw-rate", "30deg/s", "--dt", "0.02", "--no-gif",
            "--model-error", "0.2"]  # fmt: skip
    result = CliRunner().invoke(_cli(), args)
    assert result.exit_code == 0, result.output
    assert "open_loop" in result.output and "pid" in result.output
    metrics = json.loads((out / "metrics.json").read_text())
    ref = feasible_trajectory([[0, 0], [2, 2], [4, 0]], 0.2, peak_yaw_rate=math.radians(30),
                              dt=0.02)  # fmt: skip
    model = RM100.with_body(RM100.body.scaled(1.2, 1.2))
    gains = TorqueGains.pole_placement(1.0, speed=float(ref.twist[:, 0].max()))
    run = track_trajectory(RM100, ref, ComputedTorquePID(model, gains), dt=0.02)
    for key in (
        "tracking_max_position_error_m",
        "tracking_rms_position_error_m",
        "tracking_rms_heading_error_deg",
    ):
        assert metrics["pid"][key] == pytest.approx(run.metrics()[0][key], rel=1e-9)
        assert key in metrics["open_loop"]
    rows = np.loadtxt(out / "tracking.csv", delimiter=",", skiprows=1)
    assert rows.shape[0] == run.t.size
    assert {p.name for p in out.iterdir()} == {
        "reference.csv", "tracking.csv", "reference.png", "tracking.png", "metrics.json"
    }  # fmt: skip
    again = CliRunner().invoke(_cli(), args)
    assert again.exit_code != 0 and isinstance(again.exception, FileExistsError)


def test_track_waypoints_command_bad_input(tmp_path):
    from typer.testing import CliRunner

    for extra, error in (
        (["--waypoints", "0,0"], "at least two"),
        (["--waypoints", "0,0 1"], "x,y pairs"),
        (["--peak-velocity", "0"], "peak_velocity"),
        (["--preset", "pioneer"], "preset"),
        (["--reference", "smooth"], "reference"),
    ):
        result = CliRunner().invoke(_cli(), ["track-waypoints", "--out", str(tmp_path), *extra])
        assert result.exit_code != 0
        assert error in str(result.exception)
