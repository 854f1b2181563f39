"""Figures of the dynamics chapter of document 000 (figures 5.2–5.5, 5.8–5.11, 5.13, 5.16).

Like :mod:`wheelbase.plot`, these functions only draw what the algorithms returned; they build
:class:`matplotlib.figure.Figure` objects without ``pyplot`` (any backend, no global state).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
from matplotlib.figure import Figure

from wheelbase.dynamics import DynamicsResult, InverseDynamicsResult
from wheelbase.errors import InputError
from wheelbase.geometry import wrap_angle
from wheelbase.models.path import PoseTrajectory
from wheelbase.sim.log import Log

__all__ = ["plot_forward_cases", "plot_inverse_dynamics", "plot_tracking"]


def plot_forward_cases(results: Mapping[str, DynamicsResult]) -> Figure:
    """x–y paths of forward-dynamics runs, one panel each (document 000 figures 5.2–5.5).

    Parameters
    ----------
    results : mapping of str to DynamicsResult
        Label (e.g. ``"τ = (0.01, 0.012) N·m"``) → single-robot result.

    Returns
    -------
    matplotlib.figure.Figure
    """
    if not results:
        raise InputError("plot_forward_cases needs at least one result")
    n = len(results)
    cols = min(n, 2)
    rows = (n + cols - 1) // cols
    fig = Figure(figsize=(5.0 * cols, 4.2 * rows), layout="constrained")
    for k, (label, result) in enumerate(results.items()):
        ax = fig.add_subplot(rows, cols, k + 1)
        poses = result.poses
        ax.plot(poses[:, 0], poses[:, 1], "b-", lw=1.5)
        ax.plot(poses[0, 0], poses[0, 1], "go", label="start")
        ax.plot(poses[-1, 0], poses[-1, 1], "rs", label="end")
        ax.set_title(label)
        ax.set_xlabel("x [m]")
        ax.set_ylabel("y [m]")
        ax.set_aspect("equal", adjustable="datalim")
        ax.grid(True, alpha=0.3)
        ax.legend(loc="best", fontsize="small")
    return fig


def plot_inverse_dynamics(reference: PoseTrajectory, inverse: InverseDynamicsResult) -> Figure:
    """The four plots of document 000 §5.2: path (5.8), body twist (5.9), forces (5.10) and
    wheel torques (5.11).

    Parameters
    ----------
    reference : PoseTrajectory
        The trajectory, with its waypoints.
    inverse : InverseDynamicsResult
        Forces and torques along it (same times).

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig = Figure(figsize=(11.0, 8.0), layout="constrained")
    axes = fig.subplots(2, 2)
    ax = axes[0, 0]
    ax.plot(reference.poses[:, 0], reference.poses[:, 1], "b-", label="trajectory")
    ax.plot(*reference.waypoints.T, "ro", label="waypoints")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title("position (fig. 5.8)")
    ax.set_aspect("equal", adjustable="datalim")
    ax.legend(loc="best", fontsize="small")
    t = reference.t
    ax = axes[0, 1]
    for k, (name, unit) in enumerate((("u", "m/s"), ("v", "m/s"), ("r", "rad/s"))):
        ax.plot(t, reference.twist[:, k], label=f"{name} [{unit}]")
    ax.set_title("body velocities (fig. 5.9)")
    ax = axes[1, 0]
    for k, (name, unit) in enumerate((("F_x", "N"), ("F_y", "N"), ("M_z", "N·m"))):
        ax.plot(inverse.t, inverse.force[:, k], label=f"{name} [{unit}]")
    ax.set_title("body forces (fig. 5.10)")
    ax = axes[1, 1]
    ax.plot(inverse.t, inverse.torques[:, 0], label="τ_left [N·m]")
    ax.plot(inverse.t, inverse.torques[:, 1], label="τ_right [N·m]")
    ax.set_title("wheel torques (fig. 5.11)")
    for ax in (axes[0, 1], axes[1, 0], axes[1, 1]):
        ax.set_xlabel("t [s]")
        ax.legend(loc="best", fontsize="small")
    for ax in axes.flat:
        ax.grid(True, alpha=0.3)
    return fig


def plot_tracking(runs: Sequence[Log], labels: Sequence[str] | None = None) -> Figure:
    """Desired vs actual path and the errors over time (document 000 figures 5.13 and 5.16).

    Parameters
    ----------
    runs : sequence of Log
        Runs on the same reference (open loop, PID …), robot 0 of each.
    labels : sequence of str, optional
        One label per run (default: run 1, run 2, …).

    Returns
    -------
    matplotlib.figure.Figure
    """
    if not runs:
        raise InputError("plot_tracking needs at least one run")
    labels = [f"run {k + 1}" for k in range(len(runs))] if labels is None else list(labels)
    if len(labels) != len(runs):
        raise InputError(f"labels must have {len(runs)} entries (got {len(labels)})")
    fig = Figure(figsize=(12.0, 5.0), layout="constrained")
    path_ax, pos_ax, head_ax = (
        fig.add_subplot(1, 2, 1),
        fig.add_subplot(2, 2, 2),
        fig.add_subplot(2, 2, 4),
    )
    ref = runs[0].reference_pose[0]
    path_ax.plot(ref[:, 0], ref[:, 1], "k--", lw=2.0, label="desired")
    for run, label in zip(runs, labels, strict=True):
        n = int(run.length[0])
        actual, desired = run.true_pose[0, :n], run.reference_pose[0, :n]
        position_error = np.hypot(*(desired[:, :2] - actual[:, :2]).T)
        heading_error = wrap_angle(desired[:, 2] - actual[:, 2])
        path_ax.plot(actual[:, 0], actual[:, 1], lw=1.2, label=f"actual, {label}")
        pos_ax.semilogy(run.t[:n], np.maximum(position_error, 1e-12), label=label)
        head_ax.plot(run.t[:n], np.degrees(heading_error), label=label)
    path_ax.set_xlabel("x [m]")
    path_ax.set_ylabel("y [m]")
    path_ax.set_title("desired vs actual position")
    path_ax.set_aspect("equal", adjustable="datalim")
    pos_ax.set_ylabel("position error [m]")
    head_ax.set_ylabel("heading error [deg]")
    head_ax.set_xlabel("t [s]")
    for ax in (path_ax, pos_ax, head_ax):
        ax.grid(True, alpha=0.3)
        ax.legend(loc="best", fontsize="small")
    return fig
