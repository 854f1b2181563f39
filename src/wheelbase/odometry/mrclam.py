"""Real odometry against motion capture: the UTIAS MRCLAM dataset (Leung et al., IJRR 2011).

The records come from :func:`wheelbase.datasets.mrclam.load_mrclam` (odometry and ground truth
aligned on the odometry times). :func:`dead_reckoning_errors` dead-reckons windows of given
lengths from several start times, each started from the true pose, and measures the error at
the end of the window; :func:`yaw_rate_fit` and :func:`command_response` compare the logged
command with the motion the robot made.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from wheelbase._validate import check_choice, positive
from wheelbase.datasets.mrclam import MrclamData
from wheelbase.errors import ConfigError, DataError
from wheelbase.geometry import wrap_angle
from wheelbase.odometry.dead_reckoning import DEAD_RECKONING_METHODS, dead_reckon

__all__ = ["command_response", "dead_reckoning_errors", "yaw_rate_fit"]


def dead_reckoning_errors(
    data: MrclamData,
    horizons: Sequence[float] = (10.0, 60.0, 300.0),
    n_starts: int = 8,
    methods: Sequence[str] = DEAD_RECKONING_METHODS,
) -> list[dict[str, float | str]]:
    """Dead-reckoning error against ground truth after each horizon, from several start times.

    Parameters
    ----------
    data : MrclamData
        Aligned odometry and ground truth (:func:`wheelbase.datasets.mrclam.load_mrclam`).
    horizons : sequence of float
        Window lengths [s], > 0.
    n_starts : int
        Number of start times, evenly spaced over what the log allows for each horizon (>= 1).
    methods : sequence of str
        Dead-reckoning updates (``euler``, ``midpoint``, ``exact``).

    Returns
    -------
    list of dict
        One record per (horizon, method, start): ``horizon_s``, ``method``, ``start_s``
        (relative to the first sample), ``position_error_m``, ``heading_error_rad``,
        ``distance_m`` (ground-truth path length), ``drift_per_metre`` (position error over
        distance) and ``true_heading_position_error_m``: the position error when the true
        heading is used with the odometry speed — what is left once heading errors are removed.

    Raises
    ------
    ConfigError
        A horizon longer than the log, ``n_starts < 1`` or an unknown method.
    """
    if isinstance(n_starts, bool) or not isinstance(n_starts, (int, np.integer)) or n_starts < 1:
        raise ConfigError(f"n_starts must be an integer >= 1 (got {n_starts!r})")
    for method in methods:
        check_choice("method", method, DEAD_RECKONING_METHODS)
    records: list[dict[str, float | str]] = []
    for horizon in horizons:
        horizon = positive("horizon", horizon, "s")
        if horizon > data.duration:
            raise ConfigError(
                f"horizon must be <= the log duration {data.duration:.1f} s (got {horizon:g})"
            )
        for start in np.linspace(0.0, data.duration - horizon, int(n_starts)):
            part = data.window(float(start), horizon)
            steps = np.diff(part.true_pose[:, :2], axis=0)
            distance = float(np.hypot(steps[:, 0], steps[:, 1]).sum())
            # Position from the odometry speed along the true heading (midpoint of each step).
            dt = np.diff(part.t)
            mid = part.true_pose[:-1, 2] + 0.5 * wrap_angle(np.diff(part.true_pose[:, 2]))
            along = part.v[:-1] * dt
            xy = part.true_pose[0, :2] + np.sum(
                np.column_stack([along * np.cos(mid), along * np.sin(mid)]), axis=0
            )
            speed_only = float(np.hypot(*(xy - part.true_pose[-1, :2])))
            for method in methods:
                est = dead_reckon(part.t, part.v, part.omega, part.true_pose[0], method)
                error = est[-1] - part.true_pose[-1]
                position = float(np.hypot(error[0], error[1]))
                records.append(
                    {
                        "horizon_s": horizon,
                        "method": method,
                        "start_s": float(start),
                        "position_error_m": position,
                        "heading_error_rad": float(abs(wrap_angle(error[2]))),
                        "distance_m": distance,
                        "drift_per_metre": position / distance if distance > 0 else float("nan"),
                        "true_heading_position_error_m": speed_only,
                    }
                )
    return records


def yaw_rate_fit(data: MrclamData, max_lag: float = 1.0, step: float = 0.05) -> dict[str, float]:
    """Compare the odometry yaw rate with the motion-capture one: lag, scale and bias.

    The ground-truth heading is unwrapped, resampled every ``step`` seconds, differentiated and
    smoothed over 5 samples; the odometry yaw rate (a zero-order hold) is resampled likewise.
    For each lag in [0, max_lag] the correlation is computed; at the best lag the least-squares
    scale ω_true ≈ s·ω_odometry and the median bias ω_odometry − ω_true are reported.

    Parameters
    ----------
    data : MrclamData
        Aligned odometry and ground truth.
    max_lag : float
        Largest lag of the ground truth behind the odometry to try [s], >= 0.
    step : float
        Resampling period [s], > 0.

    Returns
    -------
    dict
        ``lag_s`` (ground truth behind odometry), ``correlation``, ``scale`` (true/odometry)
        and ``bias_rad_per_s`` (odometry − true, median) at the best lag.
    """
    step = positive("step", step, "s")
    grid = np.arange(data.t[0], data.t[-1], step)
    index = np.searchsorted(data.t, grid, side="right") - 1  # zero-order hold of the odometry
    omega = data.omega[index]
    heading = np.interp(grid, data.t, np.unwrap(data.true_pose[:, 2]))
    truth = np.convolve(np.gradient(heading, step), np.ones(5) / 5.0, mode="same")
    best = (-np.inf, 0, 1.0, 0.0)
    for lag in range(int(max_lag / step) + 1):
        a = omega[: omega.size - lag] if lag else omega
        b = truth[lag:]
        corr = float(np.corrcoef(a, b)[0, 1])
        if corr > best[0]:
            best = (corr, lag, float(a @ b / (a @ a)), float(np.median(a - b)))
    corr, lag, scale, bias = best
    return {"lag_s": lag * step, "correlation": corr, "scale": scale, "bias_rad_per_s": bias}


def command_response(
    data: MrclamData, max_lag: float = 1.2, step: float = 0.05
) -> dict[str, float | np.ndarray]:
    """How the robot's motion follows its logged (v, ω): impulse responses and mean delays.

    The ground truth is resampled every ``step`` seconds; its increments over each step, the
    distance along the midpoint heading and the heading change, divided by ``step``, are
    regressed by least squares on the logged v and ω (zero-order holds) ``0, step, …`` seconds
    earlier: the coefficients h_k are the discrete impulse response of the robot's speed and
    yaw rate to the command. A step's increment answers to the command at its midpoint, so
    the mean delay is Σ k·step·h_k / Σ h_k + step/2 (a pure delay d gives d); the sum Σ h_k is
    the gain of the response.

    Parameters
    ----------
    data : MrclamData
        Aligned odometry and ground truth.
    max_lag : float
        Length of the impulse responses [s], > 0.
    step : float
        Resampling period [s], > 0.

    Returns
    -------
    dict
        ``speed_delay_s`` and ``yaw_rate_delay_s`` (mean delays), ``speed_gain`` and
        ``yaw_rate_gain``, and the responses ``speed_response`` and ``yaw_rate_response``
        (arrays of ``round(max_lag / step)`` coefficients, the k-th for a delay of k·step).
    """
    step = positive("step", step, "s")
    taps = max(round(positive("max_lag", max_lag, "s") / step), 1)
    grid = np.arange(data.t[0], data.t[-1], step)
    if grid.size < 4 * taps:
        raise DataError(f"the log is too short for a {max_lag:g} s response at {step:g} s steps")
    heading = np.interp(grid, data.t, np.unwrap(data.true_pose[:, 2]))
    x = np.interp(grid, data.t, data.true_pose[:, 0])
    y = np.interp(grid, data.t, data.true_pose[:, 1])
    mid = heading[:-1] + 0.5 * np.diff(heading)
    speed = (np.diff(x) * np.cos(mid) + np.diff(y) * np.sin(mid)) / step
    yaw_rate = np.diff(heading) / step
    lags = np.arange(taps) * step
    out: dict[str, float | np.ndarray] = {}
    for name, command, rate in (("speed", data.v, speed), ("yaw_rate", data.omega, yaw_rate)):
        index = np.searchsorted(data.t, grid[:-1, None] - lags, side="right") - 1
        design = command[np.clip(index, 0, data.t.size - 1)][taps:]
        response = np.linalg.lstsq(design, rate[taps:], rcond=None)[0]
        gain = float(response.sum())
        out[f"{name}_delay_s"] = float(lags @ response / gain + 0.5 * step)
        out[f"{name}_gain"] = gain
        out[f"{name}_response"] = response
    return out
