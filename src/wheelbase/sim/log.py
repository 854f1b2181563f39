"""The one record of a closed-loop run: every signal of N robots, batch axis first.

Every entry point of wheelbase that closes a loop (``wheelbase.run``, the controller
benchmarks, go-to-goal, computed-torque tracking, ``wheelbase batch``) returns a :class:`Log`.
Arrays are ``(N, T, …)``: robot, then time row. Robots finish at different times (arrival,
collision, …); robot ``i`` recorded ``length[i]`` rows and is frozen afterwards (its later rows
repeat its last one). :meth:`Log.robot` picks one robot and trims it to its own rows.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from wheelbase._io import write_csv
from wheelbase.errors import InputError
from wheelbase.geometry import wrap_angle

__all__ = ["REVERSAL_BAND", "STATUSES", "Log", "status_code"]

STATUSES: tuple[str, ...] = (
    "running",
    "arrived",
    "missed_goal",
    "collision",
    "timeout",
    "diverged",
    "blocked",
    "stuck",
)
"""Status names by code. ``running`` only appears while the engine steps; a finished run ends
``arrived`` (the estimate says the goal is reached, the robot is at rest, and the true pose is
within tolerance too), ``missed_goal`` (the estimate says so but the true pose is off: drift),
``collision`` (the footprint touched an obstacle), ``timeout`` (time limit), ``diverged`` (a
non-finite command or state), ``blocked`` (no plan to the goal exists on what the robot sees,
after its recoveries: it stopped) or ``stuck`` (commanded to move, the robot did not move for a
stated time: dug into soft soil, spinning on ice). Codes are stable: new names are appended."""


def status_code(name: str) -> int:
    """The integer code of a status name of :data:`STATUSES`.

    Parameters
    ----------
    name : str
        A status name.
    """
    try:
        return STATUSES.index(name)
    except ValueError:
        raise InputError(f"unknown status {name!r}; allowed: {', '.join(STATUSES)}") from None


@dataclass(frozen=True)
class Log:
    """Everything a closed-loop batch recorded, one row per control step.

    Attributes
    ----------
    t : numpy.ndarray, shape (T,)
        Times of the rows [s].
    true_pose, estimated_pose, reference_pose : numpy.ndarray, shape (N, T, 3)
        True pose, the controller's estimate and the reference [m, m, rad].
    twist : numpy.ndarray, shape (N, T, 3)
        True body twist (u [m/s], v [m/s], r [rad/s]) during the step that starts at the row.
    command : numpy.ndarray, shape (N, T, k)
        The controller's output ((v, ω), (v, δ), (v_x, v_y, ω) or wheel torques [N·m]).
    wheel_rates : numpy.ndarray, shape (N, T, 2)
        True wheel angular rates (left, right) [rad/s] of the encoder axle.
    ticks : numpy.ndarray of int64, shape (N, T, 2)
        Cumulative encoder counts (left, right) (zeros with perfect state).
    torques : numpy.ndarray, shape (N, T, 2) or None
        Wheel torques (left, right) [N·m] on a dynamic plant.
    status : numpy.ndarray of int8, shape (N,)
        Each robot's final status, a code of :data:`STATUSES`.
    length : numpy.ndarray of int64, shape (N,)
        Rows each robot recorded (its last row is its final state).
    goal : numpy.ndarray, shape (N, 3) or None
        The goal each robot was judged against.
    seeds : numpy.ndarray of int64, shape (N,)
        Each robot's seed of its random errors.
    command_names : tuple of str
        Names of the command columns.
    controller_status : numpy.ndarray of int16, shape (N, T)
        A controller's own per-step status (MPPI's ``ok``/``all_collide``/``arrived``) as an
        index into ``controller_status_names``; −1 where the controller reports none.
    controller_status_names : tuple of str
        Names of the controller status codes.
    extras : dict of str to numpy.ndarray
        Further signals ``(N, T)`` or ``(N, T, m)`` of a plant or estimator (set-points, duty).
    rollout_fans : dict of (int, int) to numpy.ndarray
        For a sampling controller (MPPI), some sampled rollouts ``(K, H + 1, 2)`` [m] keyed by
        (robot, row), for drawing.
    scans : dict of (int, int) to numpy.ndarray
        Lidar ranges ``(beams,)`` [m] keyed by (robot, row): the scan taken at that row's true
        pose (read by the engine's sensors at the end of the step before it).
    particles : dict of (int, int) to numpy.ndarray
        A particle filter's particles ``(P, 3)`` keyed by (robot, row), now and then: the
        belief behind that row's estimate.
    perceived : dict of (int, int) to dict
        Now and then, what a robot perceived (its lidar's marks ``(M, 2)`` [m] and its
        confirmed tracks ``(K, 5)`` = (x, y, v_x, v_y, radius)) keyed by (robot, row), for
        drawing.
    summaries : tuple of dict
        What each robot's controller says of its whole run at the end (a navigator's replans,
        recoveries and plans), when it says anything (``summary()``); else empty.
    agents : numpy.ndarray, shape (B, T, A, 4), or None
        The moving agents of each world (x [m], y [m], v_x [m/s], v_y [m/s]) at every row
        (float32; robot i lives in world i // R for a fleet of R robots), when the run had a
        world with agents and kept its sensors.
    """

    t: np.ndarray
    true_pose: np.ndarray
    estimated_pose: np.ndarray
    reference_pose: np.ndarray
    twist: np.ndarray
    command: np.ndarray
    wheel_rates: np.ndarray
    ticks: np.ndarray
    torques: np.ndarray | None
    status: np.ndarray
    length: np.ndarray
    goal: np.ndarray | None = None
    seeds: np.ndarray | None = None
    command_names: tuple[str, ...] = ("v", "omega")
    controller_status: np.ndarray | None = None
    controller_status_names: tuple[str, ...] = ()
    extras: dict[str, np.ndarray] = field(default_factory=dict)
    rollout_fans: dict[tuple[int, int], np.ndarray] = field(default_factory=dict)
    scans: dict[tuple[int, int], np.ndarray] = field(default_factory=dict)
    particles: dict[tuple[int, int], np.ndarray] = field(default_factory=dict)
    agents: np.ndarray | None = None
    summaries: tuple = ()
    perceived: dict[tuple[int, int], dict] = field(default_factory=dict)

    # ------------------------------------------------------------------ picking robots
    @property
    def n_robots(self) -> int:
        """Number of robots N."""
        return int(self.true_pose.shape[0])

    @property
    def statuses(self) -> list[str]:
        """The final status name of every robot."""
        return [STATUSES[int(code)] for code in self.status]

    @property
    def final_pose(self) -> np.ndarray:
        """Each robot's last true pose ``(N, 3)``."""
        return self.true_pose[np.arange(self.n_robots), self.length - 1]

    @property
    def final_estimate(self) -> np.ndarray:
        """Each robot's last estimated pose ``(N, 3)``."""
        return self.estimated_pose[np.arange(self.n_robots), self.length - 1]

    @property
    def end_time(self) -> np.ndarray:
        """Time [s] of each robot's last row ``(N,)`` (its arrival time when it arrived)."""
        return self.t[self.length - 1]

    def robot(self, index: int) -> Log:
        """Robot ``index`` alone: a :class:`Log` with N = 1, trimmed to its own rows.

        Parameters
        ----------
        index : int
            Robot index, 0 <= index < N (negative counts from the end).
        """
        n = self.n_robots
        if isinstance(index, bool) or not isinstance(index, (int, np.integer)):
            raise InputError(f"robot index must be an integer (got {index!r})")
        if not -n <= index < n:
            raise InputError(f"robot index must be in [{-n}, {n}) (got {index})")
        i = int(index) % n
        rows = int(self.length[i])

        def pick(array: np.ndarray | None) -> np.ndarray | None:
            return None if array is None else array[i : i + 1, :rows].copy()

        return replace(
            self,
            t=self.t[:rows].copy(),
            true_pose=pick(self.true_pose),
            estimated_pose=pick(self.estimated_pose),
            reference_pose=pick(self.reference_pose),
            twist=pick(self.twist),
            command=pick(self.command),
            wheel_rates=pick(self.wheel_rates),
            ticks=pick(self.ticks),
            torques=pick(self.torques),
            status=self.status[i : i + 1].copy(),
            length=np.array([rows]),
            goal=None if self.goal is None else self.goal[i : i + 1].copy(),
            seeds=None if self.seeds is None else self.seeds[i : i + 1].copy(),
            controller_status=pick(self.controller_status),
            extras={key: value[i : i + 1, :rows].copy() for key, value in self.extras.items()},
            rollout_fans={(0, row): fan for (r, row), fan in self.rollout_fans.items() if r == i},
            scans={(0, row): scan for (r, row), scan in self.scans.items() if r == i},
            particles={(0, row): cloud for (r, row), cloud in self.particles.items() if r == i},
            agents=self._agents_of(i, rows),
            summaries=self.summaries[i : i + 1],
            perceived={(0, row): seen for (r, row), seen in self.perceived.items() if r == i},
        )

    def _agents_of(self, i: int, rows: int) -> np.ndarray | None:
        """Robot i's world's agents: its own world in a batch of one robot per world, else
        every world (a fleet shares one)."""
        if self.agents is None:
            return None
        worlds = self.agents if self.agents.shape[0] != self.n_robots else self.agents[i : i + 1]
        return worlds[:, :rows].copy()

    def controller_status_counts(self, index: int = 0) -> dict[str, int]:
        """How many steps robot ``index``'s controller reported each status.

        Parameters
        ----------
        index : int
            Robot index.
        """
        if self.controller_status is None:
            return {}
        codes = self.controller_status[index, : self.length[index]]
        codes = codes[codes >= 0]
        values, counts = np.unique(codes, return_counts=True)
        return {
            self.controller_status_names[int(v)]: int(c)
            for v, c in zip(values, counts, strict=True)
        }

    # ------------------------------------------------------------------ summaries
    def metrics(self) -> list[dict[str, Any]]:
        """Numbers that summarise each robot's run (one dict per robot).

        Returns
        -------
        list of dict
            ``status``, ``collision``, ``duration_s``, ``distance_travelled_m``,
            ``reversals`` (changes of the direction of travel, :data:`REVERSAL_BAND`), the
            largest and RMS wheel torque on a dynamic plant, tracking errors against the
            log's time-indexed reference (RMS and max of the position error, RMS heading
            error in degrees), the final pose errors of the true pose against the goal (when
            there is one). The errors of the estimate, only where the controller did not see
            the truth: the estimated pose's final error against the goal, and the position
            error |true − estimated| over the run, RMS and max (``localization_rms_error_m``,
            ``localization_max_error_m``); at the end, ``odometry_drift_m`` and
            ``odometry_drift_per_m`` (per metre travelled) for dead reckoning, or
            ``localization_final_error_m`` for a filter (a log with ``loc_`` signals).
        """
        rows = []
        for i in range(self.n_robots):
            n = int(self.length[i])
            true, est, ref = (
                self.true_pose[i, :n],
                self.estimated_pose[i, :n],
                self.reference_pose[i, :n],
            )
            position_error = np.hypot(*(true[:, :2] - ref[:, :2]).T)
            heading_error = np.degrees(wrap_angle(true[:, 2] - ref[:, 2]))
            travelled = float(np.sum(np.hypot(*np.diff(true[:, :2], axis=0).T)))
            drift = float(np.hypot(*(true[-1, :2] - est[-1, :2])))
            perfect = np.array_equal(true, est)  # the controller saw the truth: no estimate
            status = STATUSES[int(self.status[i])]
            row: dict[str, Any] = {
                "status": status,
                "collision": status == "collision",
                "duration_s": float(self.t[n - 1]),
                "distance_travelled_m": travelled,
                "tracking_rms_position_error_m": float(np.sqrt(np.mean(position_error**2))),
                "tracking_max_position_error_m": float(np.max(position_error)),
                "tracking_rms_heading_error_deg": float(np.sqrt(np.mean(heading_error**2))),
            }
            if self.goal is not None:
                goal = self.goal[i]
                row.update(
                    final_position_error_true_m=float(np.hypot(*(true[-1, :2] - goal[:2]))),
                    final_heading_error_true_deg=float(
                        np.degrees(abs(wrap_angle(true[-1, 2] - goal[2])))
                    ),
                )
                if not perfect:
                    row["final_position_error_estimated_m"] = float(
                        np.hypot(*(est[-1, :2] - goal[:2]))
                    )
            row["reversals"] = _reversals(self.twist[i, : max(n - 1, 0), 0])
            if self.torques is not None:
                torques = self.torques[i, :n]
                row["max_wheel_torque_nm"] = float(np.max(np.abs(torques)))
                row["rms_wheel_torque_nm"] = float(np.sqrt(np.mean(torques**2)))
            if not perfect:
                if "loc_updates" in self.extras:  # a filter: its error, not a drift
                    row["localization_final_error_m"] = drift
                else:  # dead reckoning
                    row["odometry_drift_m"] = drift
                    row["odometry_drift_per_m"] = drift / travelled if travelled > 0 else 0.0
                error = np.hypot(*(true[:, :2] - est[:, :2]).T)
                row["localization_rms_error_m"] = float(np.sqrt(np.mean(error**2)))
                row["localization_max_error_m"] = float(np.max(error))
            counts = self.controller_status_counts(i)
            if counts:
                row["controller_statuses"] = counts
            rows.append(row)
        return rows

    def columns(self) -> dict[str, np.ndarray]:
        """The log as named columns in the long format: one row per (robot, time row).

        Only each robot's own rows are included; the ``robot`` column says whose they are.
        """
        index = [np.full(int(n), i, dtype=np.int64) for i, n in enumerate(self.length)]

        def flat(array: np.ndarray) -> np.ndarray:
            return np.concatenate([array[i, : int(n)] for i, n in enumerate(self.length)])

        out: dict[str, np.ndarray] = {
            "robot": np.concatenate(index),
            "t": np.concatenate([self.t[: int(n)] for n in self.length]),
        }
        for prefix, array in (
            ("true", self.true_pose),
            ("est", self.estimated_pose),
            ("ref", self.reference_pose),
        ):
            values = flat(array)
            for k, axis in enumerate(("x", "y", "theta")):
                out[f"{prefix}_{axis}"] = values[:, k]
        commands = flat(self.command)
        for k, name in enumerate(self.command_names):
            out[f"cmd_{name}"] = commands[:, k]
        rates = flat(self.wheel_rates)
        out["wheel_rate_left"], out["wheel_rate_right"] = rates[:, 0], rates[:, 1]
        if self.torques is not None:
            torques = flat(self.torques)
            out["torque_left"], out["torque_right"] = torques[:, 0], torques[:, 1]
        ticks = flat(self.ticks)
        out["ticks_left"], out["ticks_right"] = ticks[:, 0], ticks[:, 1]
        for key, value in self.extras.items():
            values = flat(value)
            if values.ndim == 1:
                out[key] = values
            else:
                for k in range(values.shape[1]):
                    out[f"{key}_{k}"] = values[:, k]
        return out

    def to_csv(self, path: str | Path, *, overwrite: bool = False) -> Path:
        """Write :meth:`columns` (long format with a ``robot`` column) to a CSV file.

        Parameters
        ----------
        path : str or Path
            Output file.
        overwrite : bool
            Replace an existing file (default: raise FileExistsError).
        """
        return write_csv(path, self.columns(), overwrite=overwrite)

    def plot(self, ax: Any = None, *, robots: Any = None, estimate: bool = True):
        """Draw the driven paths (and the estimates and the reference) in the plane.

        Parameters
        ----------
        ax : matplotlib.axes.Axes, optional
            Where to draw (default: a new figure).
        robots : iterable of int, optional
            Which robots (default: all, at most 50).
        estimate : bool
            Also draw the estimated paths (dotted).

        Returns
        -------
        matplotlib.figure.Figure
        """
        import matplotlib.pyplot as plt

        if ax is None:
            fig, ax = plt.subplots(figsize=(6, 5))
        else:
            fig = ax.figure
        chosen = range(min(self.n_robots, 50)) if robots is None else robots
        for count, i in enumerate(chosen):
            n = int(self.length[i])
            label = count == 0
            ax.plot(*self.reference_pose[i, :n, :2].T, "--", color="0.6", lw=0.8,
                    label="reference" if label else None)  # fmt: skip
            ax.plot(*self.true_pose[i, :n, :2].T, "-", color="tab:blue", lw=1.2,
                    label="driven" if label else None)  # fmt: skip
            if estimate:
                ax.plot(*self.estimated_pose[i, :n, :2].T, ":", color="tab:green", lw=1.0,
                        label="estimated" if label else None)  # fmt: skip
        if self.goal is not None:
            ax.plot(*self.goal[:, :2].T, "x", color="tab:red", label="goal")
        ax.set_aspect("equal")
        ax.set_xlabel("x [m]")
        ax.set_ylabel("y [m]")
        ax.legend(loc="best", fontsize=8)
        return fig


REVERSAL_BAND = 0.05
"""A direction of travel counts where the forward speed exceeds this fraction of the run's
peak speed (and 1e-6 m/s): the band between is hysteresis, so that a robot turning in place,
its forward speed flickering by 1e-5 m/s, does not reverse."""


def _reversals(speed: np.ndarray) -> int:
    """How often the direction of travel changes (:data:`REVERSAL_BAND`)."""
    if speed.size == 0:
        return 0
    band = max(1e-6, REVERSAL_BAND * float(np.max(np.abs(speed))))
    sign = np.sign(speed[np.abs(speed) > band])
    return int(np.count_nonzero(sign[1:] != sign[:-1]))
