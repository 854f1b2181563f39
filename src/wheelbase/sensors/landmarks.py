"""A range–bearing landmark sensor with known identities (camera with barcodes, RFID, …).

From a robot pose (x, y, θ) a landmark at (m_x, m_y) is at range r = ‖m − (x, y)‖ and bearing
φ = atan2(m_y − y, m_x − x) − θ (wrapped to (−π, π]): the measurement model of Thrun, Burgard and
Fox, *Probabilistic Robotics*, eq. 6.40. The sensor sees the landmarks within ``max_range`` and
``|φ| <= fov/2``; each one in view is detected with probability ``detection_probability`` and
measured with independent Gaussian noise on r and φ. False detections (clutter) come as a
Poisson number per scan with mean ``false_rate``, at a uniformly random range in
``[0, max_range]`` and bearing in the field of view, carrying the identity of a random landmark
(a wrong data association, which is what an estimator's innovation gate is for).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from wheelbase._validate import as_float_array, as_rng, nonnegative, positive
from wheelbase.errors import ConfigError, InputError
from wheelbase.geometry import wrap_angle
from wheelbase.limits import MAX_FALSE_RATE

__all__ = ["LandmarkObservations", "LandmarkSensor", "range_bearing"]


def range_bearing(poses: ArrayLike, landmarks: ArrayLike) -> np.ndarray:
    """Noise-free range and bearing of landmarks from poses (eq. 6.40 of Thrun et al.).

    Parameters
    ----------
    poses : array_like, shape (..., 3)
        Robot poses (x [m], y [m], θ [rad]).
    landmarks : array_like, shape (..., 2)
        Landmark positions [m]; broadcast against ``poses[..., :2]``.

    Returns
    -------
    numpy.ndarray, shape (..., 2)
        (range [m], bearing [rad] in (−π, π]).
    """
    poses = np.asarray(poses, dtype=np.float64)
    landmarks = np.asarray(landmarks, dtype=np.float64)
    dx = landmarks[..., 0] - poses[..., 0]
    dy = landmarks[..., 1] - poses[..., 1]
    return np.stack([np.hypot(dx, dy), wrap_angle(np.arctan2(dy, dx) - poses[..., 2])], -1)


@dataclass(frozen=True)
class LandmarkObservations:
    """The detections of one call of :meth:`LandmarkSensor.observe`, as flat arrays.

    Attributes
    ----------
    robot : numpy.ndarray, shape (K,)
        Index of the pose (robot) that made each detection, in increasing order.
    landmark : numpy.ndarray, shape (K,)
        Identity of the detected landmark: a row of the landmark array.
    range : numpy.ndarray, shape (K,)
        Measured range [m].
    bearing : numpy.ndarray, shape (K,)
        Measured bearing [rad], in (−π, π].
    false : numpy.ndarray, shape (K,)
        True for a false detection (the truth, for evaluating an estimator).
    """

    robot: np.ndarray
    landmark: np.ndarray
    range: np.ndarray
    bearing: np.ndarray
    false: np.ndarray

    def __len__(self) -> int:
        return int(self.robot.size)

    def padded(self, n_robots: int) -> tuple[np.ndarray, np.ndarray]:
        """The detections as padded per-robot arrays, as the estimators take them.

        Parameters
        ----------
        n_robots : int
            Number of robots (poses) N.

        Returns
        -------
        ids : numpy.ndarray, shape (N, M)
            Landmark identities, −1 where a robot has fewer than M detections.
        z : numpy.ndarray, shape (N, M, 2)
            (range [m], bearing [rad]); NaN in the padding.
        """
        counts = np.bincount(self.robot, minlength=n_robots)
        width = int(counts.max(initial=0))
        ids = np.full((n_robots, width), -1, dtype=np.int64)
        z = np.full((n_robots, width, 2), np.nan)
        starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
        slot = np.arange(self.robot.size) - starts[self.robot]
        ids[self.robot, slot] = self.landmark
        z[self.robot, slot, 0] = self.range
        z[self.robot, slot, 1] = self.bearing
        return ids, z


@dataclass(frozen=True)
class LandmarkSensor:
    """Range–bearing sensor of identified landmarks (module docstring).

    Parameters
    ----------
    max_range : float
        Largest range at which a landmark is seen [m], > 0.
    fov : float
        Field of view [rad] centred on the robot's heading, in (0, 2π].
    range_std : float
        Standard deviation of the range noise [m], >= 0.
    bearing_std : float
        Standard deviation of the bearing noise [rad], >= 0.
    detection_probability : float
        Probability that a landmark in view is detected, in [0, 1].
    false_rate : float
        Mean number of false detections per scan, >= 0.

    Examples
    --------
    >>> sensor = LandmarkSensor(max_range=5.0)
    >>> seen = sensor.observe([[1.0, 0.0], [9.0, 0.0]], [0.0, 0.0, 0.0], rng=0)
    >>> seen.landmark.tolist(), seen.range.tolist()
    ([0], [1.0])
    """

    max_range: float = 6.0
    fov: float = 2.0 * math.pi
    range_std: float = 0.0
    bearing_std: float = 0.0
    detection_probability: float = 1.0
    false_rate: float = 0.0

    def __post_init__(self) -> None:
        checked = {
            "max_range": positive("max_range", self.max_range, "m"),
            "fov": positive("fov", self.fov, "rad"),
            "range_std": nonnegative("range_std", self.range_std, "m"),
            "bearing_std": nonnegative("bearing_std", self.bearing_std, "rad"),
            "detection_probability": nonnegative(
                "detection_probability", self.detection_probability
            ),
            "false_rate": nonnegative("false_rate", self.false_rate, "per scan"),
        }
        if checked["fov"] > 2.0 * math.pi + 1e-12:
            raise ConfigError(f"fov must be in (0, 2π] rad (got {checked['fov']:g})")
        probability = checked["detection_probability"]
        if probability > 1.0:
            raise ConfigError(f"detection_probability must be in [0, 1] (got {probability:g})")
        if checked["false_rate"] > MAX_FALSE_RATE:
            raise ConfigError(
                f"false_rate must be <= {MAX_FALSE_RATE:g} per scan "
                f"(wheelbase.limits.MAX_FALSE_RATE; got {checked['false_rate']:g})"
            )
        for name, value in checked.items():  # the checked numbers, not what was given
            object.__setattr__(self, name, value)

    def observe(
        self,
        landmarks: ArrayLike,
        poses: ArrayLike,
        rng: np.random.Generator | int | None = None,
    ) -> LandmarkObservations:
        """Detections of ``landmarks`` from one pose or a batch.

        Parameters
        ----------
        landmarks : array_like, shape (L, 2)
            Landmark positions [m]; row ℓ has identity ℓ.
        poses : array_like, shape (3,) or (N, 3)
            Robot poses (x [m], y [m], θ [rad]); one pose counts as N = 1.
        rng : numpy.random.Generator, int or None
            Randomness of the noise, detections and clutter.

        Returns
        -------
        LandmarkObservations
            Detections sorted by robot (true ones by landmark, then false ones).
        """
        landmarks = as_float_array("landmarks", landmarks, 2, min_ndim=2, max_ndim=2)
        poses = as_float_array("poses", poses, 3, min_ndim=1, max_ndim=2).reshape(-1, 3)
        if landmarks.shape[0] == 0 and self.false_rate > 0.0:
            raise InputError("false detections need at least one landmark to name")
        rng = as_rng(rng)
        n, count = poses.shape[0], landmarks.shape[0]
        truth = range_bearing(poses[:, None, :], landmarks[None, :, :])  # (N, L, 2)
        seen = (truth[..., 0] <= self.max_range) & (np.abs(truth[..., 1]) <= self.fov / 2.0)
        seen &= rng.random(seen.shape) < self.detection_probability
        robot, landmark = np.nonzero(seen)
        z = truth[robot, landmark]
        z_range = np.maximum(z[:, 0] + self.range_std * rng.standard_normal(robot.size), 0.0)
        z_bearing = wrap_angle(z[:, 1] + self.bearing_std * rng.standard_normal(robot.size))
        clutter = rng.poisson(self.false_rate, n) if self.false_rate > 0 else np.zeros(n, int)
        c_robot = np.repeat(np.arange(n), clutter)
        c_id = rng.integers(0, max(count, 1), c_robot.size)
        c_range = rng.uniform(0.0, self.max_range, c_robot.size)
        c_bearing = wrap_angle(rng.uniform(-self.fov / 2.0, self.fov / 2.0, c_robot.size))
        robots = np.concatenate([robot, c_robot])
        order = np.argsort(robots, kind="stable")
        return LandmarkObservations(
            robot=robots[order],
            landmark=np.concatenate([landmark, c_id])[order],
            range=np.concatenate([z_range, c_range])[order],
            bearing=np.concatenate([z_bearing, c_bearing])[order],
            false=np.concatenate([np.zeros(robot.size, bool), np.ones(c_robot.size, bool)])[order],
        )
