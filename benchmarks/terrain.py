"""Loads and terrain (issue 24): payloads, surfaces, slopes, soft soil, energy. Prints JSON.

Run ``python benchmarks/terrain.py`` (about 3 minutes on 2 cores; ``--quick``: seconds, fewer
and shorter runs; ``--figures DIR``: also the figures). Every run is a scenario through
``wheelbase.run``'s :func:`~wheelbase.runner.prepare` and the engine, so what is measured is
what a user gets.

- ``payload_max_error_m``: document 000's waypoint run (the bundled ``doc000_waypoints``:
  RM100, 4096-tick encoders) with a payload of 0, 50 and 100 % of the robot's mass at
  (0.10, 0.0) m that the controller does not know, tracked by today's computed torque and by
  the adaptive computed torque; ``payload_estimates``: the adaptive law's final θ̂ against
  the truth. Targets: adaptive ≤ 1 cm at +100 %, estimates within 5 %.
- ``surfaces``: the demo route (``demo``) on each surface with slip and with rolling contact:
  status, odometry drift per metre, the wheels' work, the largest slip, and the closed-loop
  energy balance (work − ΔT − gravity − losses, relative to the work).
- ``ice_traction``: on ice without and with traction control (``friction: map``, the
  floor's peak friction under each wheel): the demo route as it is, the demo at limits ice
  allows (0.3 m/s, 0.3 m/s², 0.5 rad/s: the demo's 0.6 m/s turns need 0.6 m/s² of lateral
  grip, ice gives 0.49), and a straight 4 m at 1 m/s²; target: with it, no wheel slips above
  0.1 (ice peaks at 0.06), and the demo slowed to the map's friction arrives. Seven ways each
  (``ICE_VARIANTS``): ``without``, ``with`` (the map's friction, torques clipped),
  ``with_hold_integrators``, ``with_slow_down`` (the reference's timing planned to the map's
  friction circles, :mod:`wheelbase.control.friction_timing`),
  ``with_slow_down_slip_compensation`` (and the odometry's slip compensation),
  ``estimated`` (``friction: estimate``: the robot's own estimate from encoders, torques and
  model — the first spin is how it learns, so ``max_slip_after_first_spin`` is the figure to
  hold against the bound), ``estimated_slow_down`` (the reference slowed to the estimate) and
  ``estimated_imu_slow_down`` (the estimate reading an IMU, ``sensors.imu``) and
  ``estimated_imu_gyro_slow_down`` (and the odometry's heading from the IMU's gyro where the
  wheels slip, ``odometry.gyro``: :mod:`wheelbase.sim.gyrodometry`).
  Each row: status, largest slip, the true final error, the odometry's final error against
  the truth (``final_odometry_error_m``), the time to the end against the
  reference's, the tracking error against the reference as timed, the deviation from the path,
  and with ``slow_down`` the tracking error against the slowed reference. A ``collision`` is
  reported with its cause: on the demo's turns ice's side grip runs out.
- ``grass_traction``: the demo on grass (μ_p 0.24, rolling resistance 0.10) without and
  with traction control (``GRASS_VARIANTS``, the rows of ``ice_traction``, with the distance
  travelled against the path's length). When the torque clip counted the drive wheels' own
  rolling moment against the grip the RM100 moved 9 mm and ended ``stuck``; target: with
  ``slow_down`` it drives at least 95 % of the path, no wheel slipping above ``slip_bound``.
- ``rolling_feedforward``: the demo with the rolling resistance fed forward
  (``controller.slope_feedforward: {rolling_resistance: true}``) ``off`` and ``on``, on the
  surfaces and traction variants of ``ROLLING_CASES`` (grass: the computed torque's model
  has no rolling resistance, and near the goal its torque stays below the 0.84 N·m a wheel
  grass needs to roll): status, the true final error, the largest slip, the time to the end
  and the closed-loop energy balance. Target: on grass with ``slow_down`` and slip
  compensation it arrives (``--quick``: that case alone).
- ``ramp``: a 10 % ramp up and down with +100 % payload: tracking error, and the mean wheel
  torque on the climb against the static m·g·sin α·r/2 per wheel; ``plain`` (the controller
  models level ground, plain encoder odometry: the PID's integrator lags by the closed form
  2·e⁻²·g·sin α/ω² where the ramp starts, and the climb's and descent's slip, ~1.7 %, puts
  the odometry 0.16 m off: ``missed_goal``) and ``slope_feedforward_slip_compensation`` (the
  two options that fix it).
- ``drawbar_pull``: DP/W against slip on Wong's dry sand and sandy loam (Table 2.3) for a
  1 m rigid wheel (5 kN, 0.3 m wide), Bekker–Janosi closed forms (what the plant computes)
  beside Wong and Reece's stress integrals.
- ``soft_soil``: the straight run on dry sand and sandy loam, RM100 with its casters as given
  (half the weight on the drive wheels) and with a sprung drive unit (80 %).
- ``drift_per_m``: odometry drift per metre on each surface with 0, 50, 100 % payload.
"""

from __future__ import annotations

import argparse
import copy
import json
import math
import os
import sys
import time
from pathlib import Path

import numpy as np

from wheelbase.inertial import inertial_parameters
from wheelbase.runner import prepare, run_metrics
from wheelbase.scenario import load_scenario

HARD = ("dry_concrete", "wet_concrete", "ice", "grass")
SOFT = ("dry_sand", "sandy_loam", "clay")
PAYLOADS = (0, 50, 100)
RM100_MASS = 26.2
G = 9.80665


def _scenario(name: str) -> dict:
    return load_scenario(name).model_dump(mode="json")


def _run(data: dict) -> tuple:
    prepared = prepare(copy.deepcopy(data))
    log = prepared.engine.run(prepared.start, seeds=[prepared.scenario.seed])
    return prepared, log, run_metrics(prepared, log, 0)


# --------------------------------------------------------------------------- payloads
def payloads(quick: bool) -> dict:
    base = _scenario("doc000_waypoints")
    if quick:
        base["goals"] = base["goals"][:1]
        base["duration"] = 200.0
    errors: dict = {"computed_torque": {}, "adaptive": {}}
    estimates, histories = {}, {}
    for law, key in (("computed_torque", "computed_torque"), ("adaptive_computed_torque",
                                                                "adaptive")):  # fmt: skip
        for percent in PAYLOADS:
            data = copy.deepcopy(base)
            data["robot"]["payload"] = {"mass": RM100_MASS * percent / 100, "position": [0.1, 0]}
            data["controller"]["law"] = law
            data["controller"]["model_payload"] = False
            prepared, _log, metrics = _run(data)
            errors[key][str(percent)] = metrics["tracking_max_position_error_m"]
            if key == "adaptive":
                controller = prepared.engine.controller.law
                truth = inertial_parameters(prepared.engine.plant.model.dynamics.body)
                final = controller.estimates[0][:4]
                estimates[str(percent)] = {
                    name: {
                        "estimate": float(e),
                        "truth": float(v),
                        "relative_error": None if v == 0 else float((e - v) / v),
                        "absolute_error": float(e - v),
                    }
                    for name, e, v in zip(
                        ("mass", "moment_x", "moment_y", "inertia_b"), final, truth, strict=True
                    )
                }
                times = np.array([t for t, _ in controller.history])
                values = np.array([theta[0, :4] for _, theta in controller.history])
                histories[str(percent)] = (times, values, truth)
    # the target: at +100 % (the weakly excited m·y_c = 0 has no relative error)
    converged = all(
        abs(entry["relative_error"]) <= 0.05
        for entry in estimates.get("100", {}).values()
        if entry["relative_error"] is not None
    )
    return {"errors": errors, "estimates": estimates, "converged": converged,
            "histories": histories}  # fmt: skip


# --------------------------------------------------------------------------- surfaces
def _energy_residual(prepared, log) -> float:
    """(work − ΔT − against gravity − losses) / work over the run, from the log."""
    plant = prepared.engine.plant
    model = plant.model
    e = log.extras
    n = int(log.length[0])
    work = e["energy_work_wheels"][0, n - 1] - e["energy_work_wheels"][0, 0]
    if work <= 0:
        return 0.0
    state = np.column_stack([log.true_pose[0, :n], log.twist[0, :n]])
    aux = np.zeros((n, 13))
    aux[:, :2] = log.wheel_rates[0, :n]
    kinetic = model.kinetic_energy(state[[0, n - 1]], aux[[0, n - 1]])
    spent = kinetic[1] - kinetic[0]
    for name in ("dissipated_slip", "dissipated_rolling", "dissipated_soil",
                 "dissipated_damping"):  # fmt: skip
        spent += e[f"energy_{name}"][0, n - 1] - e[f"energy_{name}"][0, 0]
    spent -= e["energy_work_gravity"][0, n - 1] - e["energy_work_gravity"][0, 0]
    return float((work - spent) / work)


def surfaces(quick: bool) -> dict:
    base = _scenario("demo")
    out = {}
    for name in HARD + SOFT:
        row = {}
        for slip in (True, False):
            data = {**copy.deepcopy(base), "terrain": {"surface": name, "slip": slip}}
            prepared, log, metrics = _run(data)
            tag = "slip" if slip else "rolling"
            row[f"status_{tag}"] = metrics["status"]
            row[f"drift_per_m_{tag}"] = metrics["odometry_drift_per_m"]
            row[f"distance_m_{tag}"] = metrics["distance_travelled_m"]
            row[f"wheel_work_j_{tag}"] = metrics["energy_wheels_j"]
            row[f"max_slip_{tag}"] = metrics["max_slip"]
            row[f"energy_residual_relative_{tag}"] = _energy_residual(prepared, log)
            if quick:
                break
        out[name] = row
    return out


TYRE_ROLLING_RESISTANCE = 0.013
"""c_rr the robot is told with ``friction: estimate``: its own tyres', as a steady-speed torque
measures it on its (concrete) floor; ice's is the same tyre hysteresis, grass's is not."""

ESTIMATE = {"friction": "estimate", "rolling_resistance": TYRE_ROLLING_RESISTANCE}

ICE_VARIANTS = {
    "without": (None, False),
    "with": ({"friction": "map"}, False),
    "with_hold_integrators": ({"friction": "map", "hold_integrators": True}, False),
    "with_slow_down": ({"friction": "map", "slow_down": True}, False),
    "with_slow_down_slip_compensation": ({"friction": "map", "slow_down": True}, True),
    "estimated": (ESTIMATE, False),
    "estimated_slow_down": ({**ESTIMATE, "slow_down": True}, False),
    "estimated_imu_slow_down": ({**ESTIMATE, "slow_down": True}, False),
    "estimated_imu_gyro_slow_down": ({**ESTIMATE, "slow_down": True}, False),
}
"""Traction control's variants on ice: (traction_control, odometry.slip_compensation)."""

IMU_VARIANTS = frozenset({"estimated_imu_slow_down", "estimated_imu_gyro_slow_down"})
"""Variants of ``ICE_VARIANTS`` whose robot has an IMU (``sensors.imu``, the defaults)."""

GYRO_VARIANTS = frozenset({"estimated_imu_gyro_slow_down"})
"""Variants of ``IMU_VARIANTS`` whose odometry takes its heading from the gyro where the
wheels slip (``odometry.gyro``)."""


def _slowed_error(prepared, log) -> float:
    """Largest distance [m] of the true position from the slowed reference: its clock run
    again over the log's times on the profile last planned (the run's own with the map's
    friction; with an estimate, the plan after its last change)."""
    again = copy.copy(prepared.engine.controller.timing)  # advancing changes clock, last_t
    again.last_t = None
    n = int(log.length[0])
    rows = np.array([again.advance(t) for t in log.t[:n]])
    return float(np.max(np.hypot(*(log.true_pose[0, :n, :2] - rows[:, :2]).T)))


def ice_traction() -> dict:
    demo = {**_scenario("demo"), "terrain": {"surface": "ice"}}
    slow = {
        **copy.deepcopy(demo),
        "trajectory": {"max_speed": 0.3, "max_acceleration": 0.3, "max_yaw_rate": 0.5},
    }
    straight = {**copy.deepcopy(STRAIGHT), "terrain": {"surface": "ice"},
                "trajectory": {"max_speed": 0.5, "max_acceleration": 1.0}}  # fmt: skip
    straight["goal"] = [4.0, 0.0, 0.0]
    out: dict = {"slip_bound": 0.1}
    for route, base in (("demo", demo), ("demo_at_ice_limits", slow),
                        ("straight_1_m_s2", straight)):  # fmt: skip
        out[route] = {}
        for label, (traction, compensate) in ICE_VARIANTS.items():
            out[route][label] = _traction_row(base, traction, compensate,
                                              imu=label in IMU_VARIANTS,
                                              gyro=label in GYRO_VARIANTS)  # fmt: skip
    return out


GRASS_VARIANTS = ("without", "with", "with_hold_integrators", "with_slow_down",
                  "with_slow_down_slip_compensation")  # fmt: skip
"""Traction control's variants on grass (those of ``ICE_VARIANTS`` that read the map)."""


def grass_traction() -> dict:
    """The demo on grass (μ_p 0.24, c_rr 0.10) without and with traction control: the
    wheels' rolling moment is the torque's, not the grip's, so the clipped robot drives."""
    demo = {**_scenario("demo"), "terrain": {"surface": "grass"}}
    out: dict = {"demo": {}}
    for label in GRASS_VARIANTS:
        traction, compensate = ICE_VARIANTS[label]
        out["demo"][label] = _traction_row(demo, traction, compensate)
    return out


ROLLING_CASES = (
    ("grass", "without"),
    ("grass", "with"),
    ("grass", "with_slow_down"),
    ("grass", "with_slow_down_slip_compensation"),
    ("dry_concrete", "without"),
    ("wet_concrete", "without"),
    ("ice", "with_slow_down"),
    ("ice", "with_slow_down_slip_compensation"),
)
"""(surface, variant of ``ICE_VARIANTS``) on which the demo runs with and without the rolling
resistance fed forward."""


def rolling_feedforward(quick: bool) -> dict:
    """The demo with the terrain's rolling resistance fed forward, off and on."""
    cases = (("grass", "with_slow_down_slip_compensation"),) if quick else ROLLING_CASES
    out: dict = {}
    for surface, variant in cases:
        traction, compensate = ICE_VARIANTS[variant]
        row = {}
        for label, feedforward in (("off", False), ("on", {"rolling_resistance": True})):
            data = {**_scenario("demo"), "terrain": {"surface": surface}}
            data["controller"]["traction_control"] = traction
            data["controller"]["slope_feedforward"] = feedforward
            data["odometry"]["slip_compensation"] = compensate
            prepared, log, metrics = _run(data)
            row[label] = {
                "status": metrics["status"],
                "final_position_error_true_m": metrics.get("final_position_error_true_m"),
                "max_slip": metrics["max_slip"],
                "duration_s": metrics["duration_s"],
                "trajectory_duration_s": metrics["trajectory_duration_s"],
                "energy_residual_relative": _energy_residual(prepared, log),
            }
        out.setdefault(surface, {})[variant] = row
    return out


def _traction_row(
    base: dict, traction: dict | None, compensate: bool, imu: bool = False, gyro: bool = False
) -> dict:
    """One run of ``base`` with ``traction_control``, the odometry's slip compensation,
    (``imu``) an IMU the friction estimate reads and (``gyro``) the odometry's heading from
    its gyro where the wheels slip."""
    data = copy.deepcopy(base)
    if imu:
        data["sensors"] = {**data.get("sensors", {}), "imu": {}}
    if gyro:
        data["odometry"]["gyro"] = True
    data["controller"]["traction_control"] = traction
    if compensate:
        data["odometry"]["slip_compensation"] = True
    prepared, log, metrics = _run(data)
    row = {
        "status": metrics["status"],
        "max_slip": metrics["max_slip"],
        "final_position_error_true_m": metrics.get("final_position_error_true_m"),
        "final_odometry_error_m": float(np.hypot(*(log.final_estimate - log.final_pose)[0, :2])),
        "odometry_drift_per_m": metrics["odometry_drift_per_m"],
        "duration_s": metrics["duration_s"],
        "trajectory_duration_s": metrics["trajectory_duration_s"],
        "tracking_max_position_error_m": metrics["tracking_max_position_error_m"],
        "path_deviation_max_m": metrics["path_deviation_max_m"],
        "distance_travelled_m": metrics["distance_travelled_m"],
        "path_length_m": metrics["path_length_m"],
    }
    timing = getattr(prepared.engine.controller, "timing", None)
    if timing is not None:  # against the slowed reference the robot was given
        row["slowed_tracking_max_position_error_m"] = _slowed_error(prepared, log)
    estimator = getattr(prepared.engine.controller, "estimator", None)
    if estimator is not None:  # the first spin is how it learns the ice
        spins = estimator.spins
        row["spins"] = len(spins)
        row["learnt_friction"] = [round(mu, 4) for *_, mu in spins]
        if spins:
            after = log.t > spins[0][0] + 0.1
            n = int(log.length[0])
            slip = np.abs(
                np.concatenate(
                    [
                        log.extras["slip_left"][0, :n][after[:n]],
                        log.extras["slip_right"][0, :n][after[:n]],
                    ]
                )
            )
            row["max_slip_after_first_spin"] = float(slip.max()) if slip.size else 0.0
    if metrics["status"] == "collision":
        row["note"] = (
            "lateral grip: the turns need more side force than the ground gives; "
            "wheel torque limits cannot keep the robot on the path"
        )
    return row


# --------------------------------------------------------------------------- ramp
RAMP = {
    "name": "ramp",
    "map": "empty",
    "robot": {"model": "diffdrive", "preset": "rm100",
              "payload": {"mass": RM100_MASS, "position": [0.1, 0.0]}},
    "plant": "dynamic",
    "controller": {"law": "computed_torque", "gains": {"bandwidth": 1.5}},
    "odometry": {"mode": "encoders", "pulses_per_revolution": 4096},
    "planner": {"reverse": False},
    "start": [0.0, 0.0, 0.0],
    "goals": [[10.0, 0.0, 0.0], [0.0, 0.0, 180.0]],
    "trajectory": {"max_speed": 0.3, "max_acceleration": 0.2, "max_yaw_rate": 0.5},
    "terrain": {"surface": "dry_concrete", "regions": [
        {"polygon": [[2, -2], [8, -2], [8, 2], [2, 2]], "surface": "dry_concrete",
         "grade_percent": 10, "uphill_deg": 0}]},
    "dt": 0.01,
    "duration": 150.0,
}  # fmt: skip


RAMP_VARIANTS = {
    "plain": {},
    "slope_feedforward_slip_compensation": {"slope_feedforward": True, "slip_compensation": True},
}
"""The ramp as it was (the controller's model level, plain encoder odometry) and with the two
library options that fix it: the slope's torque fed forward (``controller.slope_feedforward``)
and the slip of the commanded torques taken out of the odometry
(``odometry.slip_compensation``)."""


def ramp() -> dict:
    out = {}
    alpha = math.atan(0.1)
    for law in ("computed_torque", "adaptive_computed_torque"):
        out[law] = {}
        for variant, options in RAMP_VARIANTS.items():
            data = copy.deepcopy(RAMP)
            data["controller"]["law"] = law
            if options:
                data["controller"]["slope_feedforward"] = options["slope_feedforward"]
                data["odometry"]["slip_compensation"] = options["slip_compensation"]
            out[law][variant] = _ramp_row(data, alpha)
    bandwidth = RAMP["controller"]["gains"]["bandwidth"]
    out["integrator_lag_closed_form_m"] = 2 * math.exp(-2) * G * math.sin(alpha) / bandwidth**2
    return out


def _ramp_row(data: dict, alpha: float) -> dict:
    prepared, log, metrics = _run(data)
    mass = prepared.engine.plant.model.dynamics.body.mass
    radius = prepared.robot.dynamics.wheel_radius
    pose, twist, tau = log.true_pose[0], log.twist[0], log.torques[0]
    accel = np.gradient(twist[:, 0], log.t)
    going_up = np.cos(pose[:, 2]) > 0.99
    climbing = (pose[:, 0] > 3) & (pose[:, 0] < 7) & going_up & (np.abs(accel) < 0.01)
    descending = (pose[:, 0] > 3) & (pose[:, 0] < 7) & ~going_up & (np.abs(accel) < 0.01)
    static = mass * G * math.sin(alpha) * radius / 2
    rolling = 0.013 * mass * G * math.cos(alpha) * radius / 2
    up = float(np.mean(tau[climbing].sum(axis=1) / 2)) if climbing.any() else None
    down = float(np.mean(tau[descending].sum(axis=1) / 2)) if descending.any() else None
    return {
        "status": metrics["status"],
        "tracking_max_position_error_m": metrics["tracking_max_position_error_m"],
        "tracking_rms_position_error_m": metrics["tracking_rms_position_error_m"],
        "final_position_error_true_m": metrics["final_position_error_true_m"],
        "odometry_drift_m": metrics.get("odometry_drift_m"),
        "max_slip": metrics["max_slip"],
        "max_wheel_torque_nm": metrics["max_wheel_torque_nm"],
        "climb_torque_per_wheel_nm": up,
        "descent_torque_per_wheel_nm": down,
        "static_estimate_m_g_sin_a_r_over_2_nm": static,
        "static_plus_rolling_nm": static + rolling,
        "climb_over_static": None if up is None else up / static,
        "climb_over_static_plus_rolling": None if up is None else up / (static + rolling),
        "mass_kg": mass,
    }


# --------------------------------------------------------------------------- soil
def drawbar_pull() -> dict:
    from wheelbase.terrain.soil import SOILS, wong_reece
    from wheelbase.terrain.soil import drawbar_pull as closed_form

    slips = [0.05, 0.1, 0.15, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8]
    load, radius, width = 5000.0, 0.5, 0.3
    out = {"wheel": {"load_n": load, "radius_m": radius, "width_m": width}, "slips": slips}
    for name in ("dry_sand", "sandy_loam"):
        soil = SOILS[name]
        ours = [float(closed_form(load, i, radius, width, soil)) / load for i in slips]
        full = [wong_reece(load, i, radius, width, soil).drawbar_pull / load for i in slips]
        out[name] = {
            "closed_form_dp_over_w": ours,
            "wong_reece_dp_over_w": full,
            "max_abs_difference": float(np.max(np.abs(np.array(ours) - np.array(full)))),
        }
    return out


STRAIGHT = {
    "name": "soft",
    "map": "empty",
    "robot": {"model": "diffdrive", "preset": "rm100"},
    "plant": "dynamic",
    "controller": {"law": "computed_torque", "gains": {"bandwidth": 1.5}},
    "odometry": {"mode": "encoders", "pulses_per_revolution": 2048},
    "planner": {"reverse": False},
    "start": [0.0, 0.0, 0.0],
    "goal": [6.0, 0.0, 0.0],
    "trajectory": {"max_speed": 0.3, "max_acceleration": 0.2},
    "dt": 0.01,
    "duration": 60.0,
}


def soft_soil() -> dict:
    out = {}
    for label, share in (("rm100", None), ("rm100_sprung_drive_0.8", 0.8)):
        row = {}
        for surface in ("dry_sand", "sandy_loam"):
            data = copy.deepcopy(STRAIGHT)
            data["terrain"] = {"surface": surface}
            if share is not None:
                data["robot"]["contacts"] = {"drive_load_share": share}
            _prepared, _log, metrics = _run(data)
            row[surface] = {
                "status": metrics["status"],
                "distance_m": metrics["distance_travelled_m"],
                "max_sinkage_m": metrics["max_sinkage_m"],
                "duration_s": metrics["duration_s"],
            }
        out[label] = row
    return out


def drift(quick: bool) -> dict:
    base = _scenario("demo")
    out = {}
    for name in HARD if quick else HARD + SOFT:
        out[name] = {}
        for percent in (0, 100) if quick else PAYLOADS:
            data = {**copy.deepcopy(base), "terrain": {"surface": name}}
            data["robot"]["payload"] = {"mass": RM100_MASS * percent / 100, "position": [0.1, 0]}
            _prepared, _log, metrics = _run(data)
            out[name][str(percent)] = {
                "drift_per_m": metrics["odometry_drift_per_m"],
                "status": metrics["status"],
                "distance_m": metrics["distance_travelled_m"],
            }
    return out


# --------------------------------------------------------------------------- figures
def figures(folder: Path, report: dict, histories: dict) -> list[str]:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    folder.mkdir(parents=True, exist_ok=True)
    written = []
    fig, axes = plt.subplots(3, 1, figsize=(7, 7), sharex=True)
    for percent, (times, values, truth) in histories.items():
        for ax, k, label in zip(axes, (0, 1, 3), ("mass [kg]", "m·x_c [kg·m]", "I_B [kg·m²]"),
                                strict=True):  # fmt: skip
            line = ax.plot(times, values[:, k], lw=1.2, label=f"+{percent} %")[0]
            ax.axhline(truth[k], color=line.get_color(), ls="--", lw=0.8)
            ax.set_ylabel(label)
    for ax in axes:
        ax.grid(True, alpha=0.3)
    axes[0].set_ylim(0, 70)
    axes[0].legend(fontsize=8, title="payload", ncol=3)
    axes[-1].set_xlabel("t [s]")
    axes[0].set_title("adaptive computed torque on document 000's route (dashed: truth)")
    fig.tight_layout()
    written.append(_save(fig, folder / "terrain_payload_estimates.png"))
    dp = report["drawbar_pull"]
    fig, ax = plt.subplots(figsize=(6, 4))
    for name, colour in (("dry_sand", "tab:orange"), ("sandy_loam", "tab:brown")):
        ax.plot(dp["slips"], dp[name]["closed_form_dp_over_w"], "-o", color=colour, ms=3,
                label=f"{name}: Bekker–Janosi (the plant)")  # fmt: skip
        ax.plot(dp["slips"], dp[name]["wong_reece_dp_over_w"], "--s", color=colour, ms=3,
                label=f"{name}: Wong–Reece stresses")  # fmt: skip
    ax.set_xlabel("slip i")
    ax.set_ylabel("drawbar pull / load")
    ax.set_title("1 m rigid wheel, 5 kN, Wong's Table 2.3 soils")
    ax.legend(fontsize=7)
    ax.grid(True, alpha=0.3)
    fig.tight_layout()
    written.append(_save(fig, folder / "terrain_drawbar_pull.png"))
    table = report["drift_per_m"]
    names = list(table)
    fig, ax = plt.subplots(figsize=(7, 4))
    width = 0.8 / len(PAYLOADS)
    for k, percent in enumerate(PAYLOADS):
        x = np.arange(len(names)) + k * width
        for i, name in enumerate(names):
            entry = table[name].get(str(percent))
            if entry is None:
                continue
            if entry["distance_m"] < 1.0:  # dug in: no distance to divide by
                ax.text(x[i], 0.02, "stuck", rotation=90, ha="center", va="bottom", fontsize=7)
                continue
            ax.bar(x[i], 100 * entry["drift_per_m"], width, color=f"C{k}",
                   label=f"+{percent} % payload" if i == 0 else None)  # fmt: skip
    ax.set_xticks(np.arange(len(names)) + 0.4 - width / 2, names, rotation=20)
    ax.set_yscale("log")
    ax.set_ylim(0.01, 100)
    ax.set_ylabel("odometry drift [% of distance]")
    ax.set_title("the demo route with slip: slip becomes odometry error")
    ax.legend(fontsize=8)
    ax.grid(True, alpha=0.3, axis="y")
    fig.tight_layout()
    written.append(_save(fig, folder / "terrain_drift.png"))
    return written


def _save(fig, path: Path) -> str:
    import matplotlib.pyplot as plt

    fig.savefig(path, dpi=110)
    plt.close(fig)
    return str(path)


def main(argv: list[str] | None = None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true", help="fewer, shorter runs (smoke test)")
    parser.add_argument("--figures", type=Path, default=None, help="write the figures here")
    args = parser.parse_args(argv)
    start = time.perf_counter()
    payload = payloads(args.quick)
    report: dict = {
        "payload_max_error_m": payload["errors"],
        "payload_estimates": payload["estimates"],
        "payload_estimates_within_5pct": payload["converged"],
        "surfaces": surfaces(args.quick),
        "ice_traction": ice_traction(),
        "grass_traction": grass_traction(),
        "rolling_feedforward": rolling_feedforward(args.quick),
        "ramp": ramp(),
        "drawbar_pull": drawbar_pull(),
        "soft_soil": soft_soil(),
        "drift_per_m": drift(args.quick),
    }
    residuals = [
        abs(value)
        for row in report["surfaces"].values()
        for key, value in row.items()
        if key.startswith("energy_residual")
    ]
    residuals += [
        abs(run["energy_residual_relative"])
        for surface in report["rolling_feedforward"].values()
        for row in surface.values()
        for run in row.values()
    ]
    report["energy_balance_max_relative"] = max(residuals)
    ice = report["ice_traction"]
    soft = report["soft_soil"]["rm100_sprung_drive_0.8"]
    held = [ice[route]["with"]["max_slip"] for route in ("demo_at_ice_limits", "straight_1_m_s2")]
    report["targets"] = {
        "adaptive_max_error_at_100pct_le_1cm": payload["errors"]["adaptive"]["100"] <= 0.01,
        "estimates_within_5pct": payload["converged"],
        "ice_traction_slip_le_bound": max(held) <= ice["slip_bound"],
        "ice_traction_arrives_straight": ice["straight_1_m_s2"]["with"]["status"] == "arrived",
        "ice_demo_slowed_arrives_slip_le_bound": ice["demo"]["with_slow_down"]["status"]
        == "arrived"
        and ice["demo"]["with_slow_down"]["max_slip"] <= ice["slip_bound"],
        "grass_demo_slowed_drives_slip_le_bound": report["grass_traction"]["demo"][
            "with_slow_down"
        ]["distance_travelled_m"]
        >= 0.95 * report["grass_traction"]["demo"]["with_slow_down"]["path_length_m"]
        and report["grass_traction"]["demo"]["with_slow_down"]["max_slip"] <= ice["slip_bound"],
        "grass_demo_rolling_feedforward_arrives": report["rolling_feedforward"]["grass"][
            "with_slow_down_slip_compensation"
        ]["on"]["status"]
        == "arrived",
        "energy_balance_le_1e-6": report["energy_balance_max_relative"] <= 1e-6,
        "stuck_on_dry_sand_not_on_sandy_loam": soft["dry_sand"]["status"] == "stuck"
        and soft["sandy_loam"]["status"] != "stuck",
    }
    if args.figures is not None:
        report["figures"] = figures(args.figures, report, payload["histories"])
    report["seconds"] = time.perf_counter() - start
    report["cpu_count"] = os.cpu_count()
    report["quick"] = args.quick
    return report


if __name__ == "__main__":
    print(json.dumps(main(sys.argv[1:]), indent=2))
