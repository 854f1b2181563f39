"""Exteroceptive sensors in the closed loop: a lidar and a landmark sensor read at the true poses.

:class:`SensorSuite` holds the constant part (the sensors, what they see, their rates); the
engine keeps the robots' seeds for their random streams, :class:`SensorStreams`, in
:attr:`~wheelbase.sim.EngineState.sensors`. After each plant step, a sensor whose
period has come round is read at the robots' *new true* poses and its :class:`Readings` go to
the estimator with the step's encoder ticks.

Timing: with rate f [Hz] and step dt [s], the sensor is read after step k (at t = (k + 1)·dt)
when ⌊(k + 1)·dt·f⌋ > ⌊k·dt·f⌋, i.e. once per period, at the first step that reaches it (every
step when f >= 1/dt). Nothing is read at t = 0.

Randomness is counter-based (:mod:`wheelbase.sim.streams`): robot i's lidar noise after step
k comes from (seed_i, :data:`LIDAR_STREAM`, k) and its landmark noise (detections, clutter)
from (seed_i, :data:`LANDMARK_STREAM`, k), so robot i of a batch reads exactly what the single
run with seed i reads, and reading one step twice gives the same readings. The ray cast
itself is one batched call.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from wheelbase._validate import as_float_array, check_choice, positive
from wheelbase.errors import ConfigError
from wheelbase.sim.streams import counter_stream

__all__ = ["LANDMARK_STREAM", "LIDAR_STREAM", "Readings", "SensorStreams", "SensorSuite"]

LIDAR_STREAM = 1
"""Stream of a robot's lidar noise (:func:`~wheelbase.sim.streams.counter_stream`)."""
LANDMARK_STREAM = 2
"""Stream of a robot's landmark noise."""


@dataclass(frozen=True)
class Readings:
    """What the sensors read after one step, for the robots the estimator is updating.

    Rows follow the ``index`` the engine hands the estimator (robots still running).

    Attributes
    ----------
    scan : numpy.ndarray, shape (M, beams) or None
        Lidar ranges [m] (NaN in the blind zone); None when the lidar was not due.
    landmark_ids : numpy.ndarray of int64, shape (M, K) or None
        Identities of the detected landmarks (rows of :attr:`SensorSuite.landmarks`), −1 in
        the padding; None when the landmark sensor was not due.
    landmark_z : numpy.ndarray, shape (M, K, 2) or None
        (range [m], bearing [rad]) of each detection; NaN in the padding.
    """

    scan: np.ndarray | None = None
    landmark_ids: np.ndarray | None = None
    landmark_z: np.ndarray | None = None

    @property
    def empty(self) -> bool:
        """True when no sensor was read."""
        return self.scan is None and self.landmark_ids is None

    def rows(self, rows: Any) -> Readings:
        """The readings of some robots only.

        Parameters
        ----------
        rows : array_like of int or bool
            Rows to keep.
        """

        def pick(array: np.ndarray | None) -> np.ndarray | None:
            return None if array is None else array[rows]

        return Readings(pick(self.scan), pick(self.landmark_ids), pick(self.landmark_z))


class SensorStreams:
    """The robots' seeds of the sensors' counter-based random streams (module docstring).

    Parameters
    ----------
    seeds : numpy.ndarray of int, shape (N,)
        One seed per robot.
    """

    def __init__(self, seeds: np.ndarray) -> None:
        self.seeds = np.array(seeds, dtype=np.int64)
        self.seeds.setflags(write=False)

    def generators(self, stream: int, step: int, index: np.ndarray) -> list[np.random.Generator]:
        """One generator per robot of ``index`` for ``stream`` after step ``step``.

        Parameters
        ----------
        stream : int
            :data:`LIDAR_STREAM` or :data:`LANDMARK_STREAM`.
        step : int
            The step just taken.
        index : numpy.ndarray of int
            Which robots.
        """
        return [counter_stream(self.seeds[i], stream, step) for i in index]


def _due(step: int, dt: float, rate: float) -> bool:
    """Whether a sensor of ``rate`` [Hz] is read after step ``step`` (module docstring)."""
    eps = 1e-9
    return math.floor((step + 1) * dt * rate + eps) > math.floor(step * dt * rate + eps)


@dataclass(frozen=True, eq=False)
class SensorSuite:
    """The sensors of the robots of a closed loop (module docstring).

    Parameters
    ----------
    world : OccupancyGrid or PolygonWorld or None
        What the lidar sees (needed with a lidar).
    lidar : Lidar or None
        The lidar (its beams, range limits, noise and mount).
    lidar_rate_hz : float
        Scans per second, > 0.
    landmarks : array_like, shape (L, 2), or None
        Landmark positions [m]; identity ℓ is row ℓ (needed with a landmark sensor).
    landmark_sensor : LandmarkSensor or None
        The range–bearing sensor.
    landmark_rate_hz : float
        Landmark readings per second, > 0.
    method : {"fast", "exact", "numpy"}
        Ray-casting method of the lidar (:mod:`wheelbase.sensors.raycast`).

    Examples
    --------
    >>> from wheelbase.sensors import LandmarkSensor
    >>> suite = SensorSuite(landmarks=[[1.0, 0.0]], landmark_sensor=LandmarkSensor())
    >>> streams = suite.start(np.array([0]))
    >>> seen = suite.read(9, 0.02, np.zeros((1, 3)), streams)
    >>> seen.landmark_ids.tolist(), seen.landmark_z.round(3).tolist(), seen.scan is None
    ([[0]], [[[1.0, 0.0]]], True)
    """

    world: Any = None
    lidar: Any = None
    lidar_rate_hz: float = 10.0
    landmarks: Any = None
    landmark_sensor: Any = None
    landmark_rate_hz: float = 5.0
    method: str = "fast"

    def __post_init__(self) -> None:
        from wheelbase.planning import OccupancyGrid, PolygonWorld
        from wheelbase.sensors import RAY_METHODS, LandmarkSensor, Lidar

        if self.lidar is None and self.landmark_sensor is None:
            raise ConfigError("a sensor suite needs a lidar or a landmark_sensor (got neither)")
        if self.lidar is not None:
            if not isinstance(self.lidar, Lidar):
                raise ConfigError(f"lidar must be a Lidar (got {type(self.lidar).__name__})")
            if not isinstance(self.world, OccupancyGrid | PolygonWorld):
                raise ConfigError(
                    "a lidar needs a world to see: an OccupancyGrid or a PolygonWorld "
                    f"(got {type(self.world).__name__})"
                )
        object.__setattr__(
            self, "lidar_rate_hz", positive("lidar_rate_hz", self.lidar_rate_hz, "Hz")
        )
        if self.landmark_sensor is not None:
            if not isinstance(self.landmark_sensor, LandmarkSensor):
                raise ConfigError(
                    "landmark_sensor must be a LandmarkSensor "
                    f"(got {type(self.landmark_sensor).__name__})"
                )
            if self.landmarks is None:
                raise ConfigError("a landmark_sensor needs landmarks: positions (L, 2) [m]")
        if self.landmarks is not None:
            marks = as_float_array("landmarks", self.landmarks, 2, min_ndim=2, max_ndim=2)
            if marks.shape[0] == 0:
                raise ConfigError("landmarks must hold at least one position (got shape (0, 2))")
            marks.setflags(write=False)
            object.__setattr__(self, "landmarks", marks)
        object.__setattr__(
            self, "landmark_rate_hz", positive("landmark_rate_hz", self.landmark_rate_hz, "Hz")
        )
        check_choice("method", self.method, RAY_METHODS)

    def start(self, seeds: np.ndarray) -> SensorStreams:
        """The robots' random streams.

        Parameters
        ----------
        seeds : numpy.ndarray of int, shape (N,)
            One seed per robot.
        """
        return SensorStreams(np.asarray(seeds))

    def due(self, step: int, dt: float) -> tuple[bool, bool]:
        """Whether the lidar and the landmark sensor are read after step ``step``.

        Parameters
        ----------
        step : int
            Index of the step just taken (it ended at ``(step + 1)·dt``).
        dt : float
            Step [s].
        """
        return (
            self.lidar is not None and _due(step, dt, self.lidar_rate_hz),
            self.landmark_sensor is not None and _due(step, dt, self.landmark_rate_hz),
        )

    def read(
        self,
        step: int,
        dt: float,
        poses: np.ndarray,
        streams: SensorStreams,
        index: np.ndarray | None = None,
        cast: Any = None,
    ) -> Readings:
        """Read the sensors that are due after step ``step`` at true ``poses``.

        Parameters
        ----------
        step : int
            Index of the step just taken.
        dt : float
            Step [s].
        poses : numpy.ndarray, shape (M, 3)
            True poses of the robots ``index`` [m, m, rad].
        streams : SensorStreams
            Every robot's seed.
        index : numpy.ndarray of int, shape (M,), optional
            Which robots these are (default 0 … M − 1).
        cast : callable, optional
            ``cast(sensor_poses (M, 3), beam_angles, max_range, index) -> (M, beams)`` true
            ranges in a world beyond the map (:meth:`~wheelbase.sim.Surroundings.caster`);
            default the map alone.

        Returns
        -------
        Readings
        """
        if index is None:
            index = np.arange(poses.shape[0])
        lidar_due, landmarks_due = self.due(step, dt)
        scan = ids = z = None
        if lidar_due and poses.shape[0]:
            scan = self.scan(poses, streams.generators(LIDAR_STREAM, step, index), cast, index)
        if landmarks_due and poses.shape[0]:
            ids, z = self.observe(poses, streams.generators(LANDMARK_STREAM, step, index))
        return Readings(scan, ids, z)

    def scan(
        self,
        poses: np.ndarray,
        generators: list[np.random.Generator],
        cast: Any = None,
        index: np.ndarray | None = None,
    ) -> np.ndarray:
        """Lidar scans ``(M, beams)`` at ``poses``, robot i's noise from ``generators[i]``.

        Parameters
        ----------
        poses : numpy.ndarray, shape (M, 3)
            True robot poses.
        generators : list of numpy.random.Generator
            One per pose.
        cast : callable, optional
            The true ranges in a world beyond the map (see :meth:`read`).
        index : numpy.ndarray of int, shape (M,), optional
            Which robots these are (for ``cast``).
        """
        from wheelbase.sensors import scan_rays

        lidar = self.lidar
        sensor = lidar.sensor_poses(poses)
        if cast is not None:
            where = np.arange(poses.shape[0]) if index is None else index
            true = cast(sensor, lidar.beam_angles, lidar.max_range, where)
        else:
            true = scan_rays(
                self.world, sensor[:, :2], sensor[:, 2], lidar.beam_angles, lidar.max_range,
                self.method,
            )  # fmt: skip
        return np.stack(
            [lidar.readings(true[i], generator) for i, generator in enumerate(generators)]
        )

    def observe(
        self, poses: np.ndarray, generators: list[np.random.Generator]
    ) -> tuple[np.ndarray, np.ndarray]:
        """Landmark detections at ``poses``, padded: ids ``(M, K)`` and z ``(M, K, 2)``.

        Parameters
        ----------
        poses : numpy.ndarray, shape (M, 3)
            True robot poses.
        generators : list of numpy.random.Generator
            One per pose.
        """
        from wheelbase.sensors import LandmarkObservations

        seen = [
            self.landmark_sensor.observe(self.landmarks, poses[i], generator)
            for i, generator in enumerate(generators)
        ]
        joined = LandmarkObservations(
            robot=np.concatenate([np.full(len(s), i, dtype=np.int64) for i, s in enumerate(seen)]),
            landmark=np.concatenate([s.landmark for s in seen]).astype(np.int64),
            range=np.concatenate([s.range for s in seen]),
            bearing=np.concatenate([s.bearing for s in seen]),
            false=np.concatenate([s.false for s in seen]),
        )
        return joined.padded(poses.shape[0])
