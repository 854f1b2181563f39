"""What the controller knows: encoders on the wheels and the estimator that reads them.

The engine reads the encoders after each plant step (the wheel angles went from ``before`` to
``after``) and hands the tick differences to the estimator, whose estimate the controller sees
at the next step. :class:`PerfectState` hands the controller the true state instead.

An estimator has ``encoder`` (the encoders it reads, or None), ``start(poses, seeds)`` (what it
keeps besides the estimate: a covariance, particles; None here) and ``update(estimate, ticks,
dt, pose, twist, state=..., index=...)`` returning the new estimate ``(M, 3)``, the estimated
twist ``(M, 3)`` and its new state, for the robots ``index`` still running. When the engine has
sensors it also passes ``readings=`` (:class:`~wheelbase.sim.sensors.Readings`, rows as
``index``); the filters that use them are in :mod:`wheelbase.sim.localizers`. An estimator may
also have ``first_estimate(state)`` (the estimate at t = 0 when it does not start from the
true start pose: a global localisation), ``signals(state)`` (named per-robot arrays for the
log, e.g. a covariance) and ``particles_of(state, robot)`` (particles for drawing). A
non-finite estimate for a robot ends that robot ``diverged``.

Random encoder errors are counter-based (:mod:`wheelbase.sim.streams`): the errors of robot
``i`` at step k come from its seed, :data:`ENCODER_STREAM` and k, so a robot's run does not
depend on which batch it ran in (robot ``i`` of a batch equals the single run with seed
``seeds[i]``) and reading the ticks of one step twice gives the same ticks. Gaussian tick
noise is drawn in blocks of :data:`NOISE_BLOCK` steps (one generator per robot and block,
kept while the steps stay in that block; the numbers of a step depend only on its block and
its place in it).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from wheelbase.errors import ConfigError
from wheelbase.geometry import wrap_angle
from wheelbase.sim.streams import counter_stream

__all__ = [
    "ENCODER_STREAM",
    "NOISE_BLOCK",
    "TICK_STREAM",
    "EncoderOdometry",
    "EncoderReadings",
    "PerfectState",
]

NOISE_BLOCK = 512
"""Steps of Gaussian tick noise drawn per call of a robot's generator."""
ENCODER_STREAM = 0
"""Stream of the Gaussian tick noise (counter: the block of :data:`NOISE_BLOCK` steps)."""
TICK_STREAM = 5
"""Stream of an encoder with missed or extra ticks (counter: the step)."""


class EncoderReadings:
    """The encoders of N robots and their counter-based random errors (module docstring).

    Parameters
    ----------
    encoder : Encoder
        The encoder model (:class:`wheelbase.odometry.Encoder`).
    seeds : numpy.ndarray of int, shape (N,)
        One seed per robot.
    """

    def __init__(self, encoder: Any, seeds: np.ndarray) -> None:
        self.encoder = encoder
        self.seeds = np.array(seeds, dtype=np.int64)
        self.seeds.setflags(write=False)
        self._gaussian_only = encoder.miss_probability == 0 and encoder.extra_probability == 0
        # the noise of one block of steps, (block, (N, NOISE_BLOCK, 2)): a cache of a function
        # of the seeds and the block, not a state (whoever reads a step gets the same numbers)
        self._block: tuple[int, np.ndarray | None] = (-1, None)

    def _block_noise(self, block: int) -> np.ndarray:
        if self._block[0] != block:
            std = self.encoder.noise_std
            noise = np.stack(
                [
                    counter_stream(seed, ENCODER_STREAM, block).normal(0.0, std, (NOISE_BLOCK, 2))
                    for seed in self.seeds
                ]
            )
            self._block = (block, noise)
        return self._block[1]  # type: ignore[return-value]

    def tick_deltas(self, before: np.ndarray, after: np.ndarray, step: int) -> np.ndarray:
        """Tick differences ``(N, 2)`` counted during step ``step`` while the wheels turn from
        ``before`` to ``after`` [rad], with each robot's random errors of that step.

        Parameters
        ----------
        before, after : numpy.ndarray, shape (N, 2)
            Cumulative wheel angles [rad].
        step : int
            Index of the step (the counter of the random streams), >= 0.
        """
        encoder = self.encoder
        # Encoder.count without its input checks: the engine's angles are finite arrays
        per_tick = encoder.radians_per_tick
        true = (np.floor(after / per_tick + 1e-9) - np.floor(before / per_tick + 1e-9)).astype(
            np.int64
        )
        if encoder.is_ideal:
            return true
        if self._gaussian_only:
            block, row = divmod(int(step), NOISE_BLOCK)
            noise = self._block_noise(block)[:, row]
            return true + np.round(noise).astype(np.int64)
        return np.stack(
            [
                encoder.tick_deltas(before[i], after[i], counter_stream(seed, TICK_STREAM, step))
                for i, seed in enumerate(self.seeds)
            ]
        )


class _EstimateOnly:
    """An estimator that keeps nothing between steps besides the estimate."""

    def start(self, poses: np.ndarray, seeds: np.ndarray) -> None:
        """Nothing to keep besides the estimate.

        Parameters
        ----------
        poses : numpy.ndarray, shape (N, 3)
            Start poses.
        seeds : numpy.ndarray
            The robots' seeds.
        """
        return None


@dataclass(frozen=True)
class PerfectState(_EstimateOnly):
    """The controller sees the true pose and twist; wheel angles are still logged."""

    encoder: ClassVar[None] = None

    def update(self, estimate, ticks, dt, pose, twist, *, state=None, index=None, readings=None):
        """The true pose and twist.

        Parameters
        ----------
        estimate : numpy.ndarray, shape (N, 3)
            The previous estimate (unused).
        ticks : numpy.ndarray or None
            Tick differences (unused).
        dt : float
            Step [s] (unused).
        pose, twist : numpy.ndarray, shape (N, 3)
            The true pose and body twist.
        state, index : optional
            What the estimator keeps, and which robots these are (unused).
        readings : Readings, optional
            Sensor readings (unused).
        """
        return pose.copy(), twist.copy(), state


@dataclass(frozen=True)
class EncoderOdometry(_EstimateOnly):
    """Wheel encoders and the dead reckoning that reads them (document 003 §III).

    Parameters
    ----------
    encoder : Encoder
        The encoders of both wheels of the encoder axle.
    odometry : WheelOdometry
        The dead reckoning with the *nominal* geometry.
    """

    encoder: Any
    odometry: Any

    def __post_init__(self) -> None:
        from wheelbase.odometry import Encoder, WheelOdometry

        if not isinstance(self.encoder, Encoder):
            raise ConfigError(f"encoder must be an Encoder (got {type(self.encoder).__name__})")
        if not isinstance(self.odometry, WheelOdometry):
            raise ConfigError(
                f"odometry must be a WheelOdometry (got {type(self.odometry).__name__})"
            )

    def update(
        self, estimate, ticks, dt, pose, twist, *, state=None, index=None, readings=None,
        command=None,
    ):  # fmt: skip
        """Dead-reckon the estimate over one step (:meth:`travel`), and the twist it implies.

        Parameters
        ----------
        estimate : numpy.ndarray, shape (N, 3)
            The estimate at the start of the step.
        ticks : numpy.ndarray, shape (N, 2)
            Tick differences counted during the step.
        dt : float
            Step [s].
        pose, twist : numpy.ndarray, shape (N, 3)
            The truth (unused: odometry only sees ticks).
        state, index : optional
            What the estimator keeps, and which robots these are (unused).
        readings : Readings, optional
            Sensor readings (unused: odometry alone).
        command : numpy.ndarray, shape (N, 2), optional
            The wheel torques held over the step, for an odometry that reads them.
        """
        distance, rotation, state = self.travel(estimate, ticks, dt, state=state, index=index,
                                                command=command)  # fmt: skip
        return (*self.dead_reckon(estimate, distance, rotation, dt), state)

    def travel(self, estimate, ticks, dt, *, state=None, index=None, command=None):
        """The distance [m] and rotation [rad] the odometry counts over one step, ``(N,)``
        each, and its state after (what :meth:`update` dead-reckons; a wrapper that changes
        the heading, :class:`~wheelbase.sim.gyrodometry.Gyrodometry`, starts from it).

        Parameters
        ----------
        estimate : numpy.ndarray, shape (N, 3)
            The estimate at the start of the step (unused here).
        ticks : numpy.ndarray, shape (N, 2)
            Tick differences counted during the step.
        dt : float
            Step [s] (unused here).
        state, index : optional
            What the estimator keeps, and which robots these are (unused here).
        command : numpy.ndarray, shape (N, 2), optional
            The wheel torques (unused here).
        """
        distance, rotation = self.odometry.increments(ticks)
        return distance, rotation, state

    def dead_reckon(
        self, estimate: np.ndarray, distance: np.ndarray, rotation: np.ndarray, dt: float
    ) -> tuple[np.ndarray, np.ndarray]:
        """The estimate moved by one step's travel, and the twist it implies.

        Parameters
        ----------
        estimate : numpy.ndarray, shape (N, 3)
            The estimate at the start of the step.
        distance, rotation : numpy.ndarray, shape (N,)
            Distance travelled [m] and rotation [rad] over the step.
        dt : float
            Step [s].

        Returns
        -------
        pose, twist : numpy.ndarray, shape (N, 3)
        """
        from wheelbase.odometry.dead_reckoning import pose_increment

        new = estimate.copy()
        new[:, :2] += pose_increment(estimate[:, 2], distance, rotation, self.odometry.method)
        new[:, 2] = wrap_angle(estimate[:, 2] + rotation)
        return new, self.twist(distance, rotation, dt)

    @staticmethod
    def twist(distance: np.ndarray, rotation: np.ndarray, dt: float) -> np.ndarray:
        """The body twist (u [m/s], v = 0, r [rad/s]) ``(N, 3)`` of one step's travel.

        Parameters
        ----------
        distance, rotation : numpy.ndarray, shape (N,)
            Distance travelled [m] and rotation [rad] over the step.
        dt : float
            Step [s].
        """
        return np.stack([distance / dt, np.zeros_like(distance), rotation / dt], -1)
