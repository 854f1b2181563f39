"""The ``stuck`` rule: a robot commanded to move that does not move for a stated time.

A robot is *commanded to move* while the reference pose is farther than ``distance`` from its
true pose (the loop asks it to get somewhere), and *not moving* while its planar speed and yaw
rate are below the rest thresholds. When both hold for ``time`` seconds without a break it
ends ``stuck`` (:data:`~wheelbase.sim.STATUSES`): dug into soft soil, or spinning its wheels on
ice. The engine applies the rule when it has one (:class:`~wheelbase.sim.Engine` ``stuck=``);
``wheelbase.run`` gives it to scenarios with a ``terrain`` section.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from wheelbase._validate import positive

__all__ = ["Stuck"]


@dataclass(frozen=True)
class Stuck:
    """When a robot counts as stuck (module docstring).

    Parameters
    ----------
    time : float
        Seconds commanded to move without moving, > 0.
    distance : float
        Lag behind the reference pose [m] beyond which the robot is commanded to move, > 0.
    rest_speed : float
        Planar speed [m/s] below which it is not moving, > 0.
    rest_yaw_rate : float
        Yaw rate [rad/s] below which it is not turning, > 0.
    """

    time: float = 5.0
    distance: float = 0.1
    rest_speed: float = 0.01
    rest_yaw_rate: float = 0.05

    def __post_init__(self) -> None:
        object.__setattr__(self, "time", positive("stuck time", self.time, "s"))
        object.__setattr__(self, "distance", positive("stuck distance", self.distance, "m"))
        object.__setattr__(self, "rest_speed", positive("rest_speed", self.rest_speed, "m/s"))
        object.__setattr__(
            self, "rest_yaw_rate", positive("rest_yaw_rate", self.rest_yaw_rate, "rad/s")
        )

    def update(
        self,
        still: np.ndarray,
        pose: np.ndarray,
        twist: np.ndarray,
        reference: np.ndarray,
        dt: float,
    ) -> tuple[np.ndarray, np.ndarray]:
        """The time each robot has stood still while commanded, and which are stuck.

        Parameters
        ----------
        still : numpy.ndarray, shape (N,)
            Seconds each robot had stood still while commanded before this step.
        pose, twist : numpy.ndarray, shape (N, 3)
            True poses and body twists now.
        reference : numpy.ndarray, shape (N, 3)
            Reference poses now (NaN: none, never commanded).
        dt : float
            Step [s].

        Returns
        -------
        still, stuck : numpy.ndarray
            The new times ``(N,)`` and ``(N,)`` bool.
        """
        lag = np.hypot(reference[:, 0] - pose[:, 0], reference[:, 1] - pose[:, 1])
        commanded = lag > self.distance  # NaN compares False: no reference, no command
        resting = (np.hypot(twist[:, 0], twist[:, 1]) <= self.rest_speed) & (
            np.abs(twist[:, 2]) <= self.rest_yaw_rate
        )
        waiting = commanded & resting
        new = np.where(waiting, still + dt, 0.0)
        return new, new >= self.time - 1e-9
