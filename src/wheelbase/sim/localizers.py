"""Estimators of the closed loop that fuse wheel odometry with the lidar and the landmarks.

Both follow the estimator protocol of :mod:`wheelbase.sim.sensing` (``encoder``, ``start``,
``update``) and also take the step's sensor :class:`~wheelbase.sim.sensors.Readings`:

:class:`KalmanLocalizer` (EKF or UKF, batched)
    Every step predicts the belief of all running robots at once with the step's odometry
    increments as the control (v, ω) = (Δs/dt, Δθ/dt) of the filter's velocity motion model;
    landmark readings, when the sensor was read, correct it (χ² gate, Joseph form:
    :mod:`wheelbase.localization.kalman`). The lidar is not used by these filters (they know
    landmarks, not maps).

:class:`ParticleLocalizer` (AMCL, one filter per robot)
    As Nav2 runs AMCL beside odometry: the encoders dead-reckon a pose in the *odometry* frame
    every step; the particle filter updates when a reading came and the odometry moved
    ``update_min_d`` or turned ``update_min_a`` since its last update, and its estimate (the
    mean of the heaviest cluster) fixes the correction map ← odom. Between updates the
    estimate is that correction composed with the odometry pose, so the controller sees a
    smooth pose that jumps only by the corrections.
    With ``global_start`` the filter knows nothing of the start pose: the odometry frame
    starts at the origin, the particles spread over the free space, and the first estimate
    (the one the controller sees before any update) is the heaviest cluster of that spread,
    flagged not converged (signal ``loc_converged`` 0) until the clusters besides the heaviest
    hold less than a tenth of the weight (``PoseEstimate.ambiguous`` false). The engine asks
    the estimator for that first estimate (``first_estimate``) instead of handing the
    controller the true start.
    Each update is given the robot's time (its steps × dt), so that a
    :class:`~wheelbase.localization.VelocityMotion`'s per-second noise grows over the time
    between updates.

Random numbers are counter-based (:mod:`wheelbase.sim.streams`): robot i's particle filter
draws its start from (seed_i, :data:`PARTICLE_STREAM`, 0) and its update after step k from
(seed_i, :data:`PARTICLE_STREAM`, k), so robot i of a batch equals the single run with seed i
and updating one state twice gives the same belief.

Failures: nothing a robot does raises. A filter that fails for a robot (an
:class:`~wheelbase.errors.EstimationError`: a covariance that stops being positive definite,
every particle weight zero) gives that robot a NaN estimate, and the engine ends it
``diverged`` (the controller never sees a NaN); the other robots run on. The counts of used,
gated and skipped measurements (NaN or negative ranges, unknown landmark identities) are
signals of the log (``loc_*`` columns) and the run's metrics.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from wheelbase._validate import as_float_array, nonnegative
from wheelbase.errors import ConfigError, EstimationError, InputError
from wheelbase.geometry import compose, inverse_pose, wrap_angle
from wheelbase.sim.sensing import EncoderOdometry
from wheelbase.sim.streams import counter_stream

__all__ = [
    "COUNTS",
    "PARTICLE_STREAM",
    "KalmanLocalizer",
    "KalmanState",
    "ParticleLocalizer",
    "ParticleState",
    "covariance_signals",
]

PARTICLE_STREAM = 3
"""Stream of a robot's particle filter (:func:`~wheelbase.sim.streams.counter_stream`)."""

COUNTS: tuple[str, ...] = (
    "loc_updates",
    "loc_landmarks_used",
    "loc_landmarks_rejected",
    "loc_landmarks_skipped",
    "loc_beams_used",
    "loc_beams_skipped",
)
"""Cumulative counts per robot in the estimators' signals: filter corrections, landmark
measurements applied, rejected by the χ² gate, skipped (NaN or negative range, NaN bearing,
unknown identity), lidar beams used and skipped (of the beams the filter chose, those not
used: NaN or negative readings, and max-range ones under the likelihood field)."""

_COV_NAMES = (("xx", 0, 0), ("xy", 0, 1), ("xtheta", 0, 2), ("yy", 1, 1), ("ytheta", 1, 2),
              ("thetatheta", 2, 2))  # fmt: skip


def covariance_signals(cov: np.ndarray) -> dict[str, np.ndarray]:
    """The six distinct entries of pose covariances ``(N, 3, 3)`` as named signals ``(N,)``.

    Parameters
    ----------
    cov : numpy.ndarray, shape (N, 3, 3)
        Covariances of (x [m], y [m], θ [rad]).

    Returns
    -------
    dict of str to numpy.ndarray
        ``est_cov_xx`` [m²], ``est_cov_xy`` [m²], ``est_cov_xtheta`` [m·rad], ``est_cov_yy``,
        ``est_cov_ytheta``, ``est_cov_thetatheta`` [rad²].
    """
    return {f"est_cov_{name}": cov[:, i, j].copy() for name, i, j in _COV_NAMES}


def _initial_cov(std: Any, n: int) -> tuple[tuple[float, float, float], np.ndarray]:
    values = as_float_array("initial_std", std, 3, max_ndim=1)
    for name, value, unit in zip(("x", "y", "θ"), values, ("m", "m", "rad"), strict=True):
        nonnegative(f"initial_std {name}", float(value), unit)
    return tuple(float(v) for v in values), np.broadcast_to(np.diag(values**2), (n, 3, 3))


class _FusesOdometry:
    """What both filters share: the wheel odometry they read, the spread of the start belief,
    and their signals for the log."""

    odometry: EncoderOdometry
    initial_std: tuple[float, float, float]

    def _check_odometry_and_std(self) -> None:
        if not isinstance(self.odometry, EncoderOdometry):
            raise ConfigError(
                f"odometry must be an EncoderOdometry (got {type(self.odometry).__name__}): "
                "the filters fuse wheel-encoder odometry with the sensors"
            )
        std, _ = _initial_cov(self.initial_std, 1)
        object.__setattr__(self, "initial_std", std)

    @property
    def encoder(self) -> Any:
        """The encoders read by the odometry."""
        return self.odometry.encoder

    def signals(self, state: Any) -> dict[str, np.ndarray]:
        """Every robot's covariance, odometry pose (``odom_pose``, in the odometry frame) and
        cumulative counts (and particles held), for the log.

        Parameters
        ----------
        state : KalmanState or ParticleState
            The filter's state.
        """
        out = covariance_signals(state.cov)
        out["odom_pose"] = state.odom.copy()
        if hasattr(state, "particles"):
            out["loc_particles"] = state.particles.copy()
            out["loc_converged"] = state.converged.astype(np.int64)
        out.update({name: state.counts[:, k].copy() for k, name in enumerate(COUNTS)})
        return out


# --------------------------------------------------------------------------- Kalman filters
@dataclass
class KalmanState:
    """What a :class:`KalmanLocalizer` keeps besides the estimate (the mean).

    Attributes
    ----------
    cov : numpy.ndarray, shape (N, 3, 3)
        Pose covariances.
    counts : numpy.ndarray of int64, shape (N, len(COUNTS))
        Cumulative counts (:data:`COUNTS`).
    odom : numpy.ndarray, shape (N, 3)
        The wheel odometry dead-reckoned alone in the odometry frame (which starts at the
        start pose): with the mean, it gives the correction map ← odom (REP 105).
    """

    cov: np.ndarray
    counts: np.ndarray
    odom: np.ndarray


@dataclass(frozen=True, eq=False)
class KalmanLocalizer(_FusesOdometry):
    """EKF or UKF localisation on wheel odometry and landmarks, for a batch (module docstring).

    Parameters
    ----------
    filter : EKF or UKF
        The filter: its landmarks, motion noise, measurement noise and gate.
    odometry : EncoderOdometry
        The encoders and the dead reckoning whose increments drive the prediction.
    initial_std : tuple of float
        Standard deviations (x [m], y [m], θ [rad]) of the start pose's belief, >= 0.
    """

    filter: Any
    odometry: EncoderOdometry
    initial_std: tuple[float, float, float] = (0.01, 0.01, math.radians(1.0))

    def __post_init__(self) -> None:
        from wheelbase.localization import KalmanFilter

        if not isinstance(self.filter, KalmanFilter):
            raise ConfigError(f"filter must be an EKF or a UKF (got {type(self.filter).__name__})")
        self._check_odometry_and_std()

    def start(self, poses: np.ndarray, seeds: np.ndarray) -> KalmanState:
        """The belief at the start poses: covariance ``diag(initial_std²)``.

        Parameters
        ----------
        poses : numpy.ndarray, shape (N, 3)
            Start poses.
        seeds : numpy.ndarray
            The robots' seeds (unused: the filter draws no random numbers).
        """
        n = poses.shape[0]
        _, cov = _initial_cov(self.initial_std, n)
        counts = np.zeros((n, len(COUNTS)), dtype=np.int64)
        return KalmanState(cov.copy(), counts, poses.copy())

    def update(self, estimate, ticks, dt, pose, twist, *, state, index, readings=None):
        """Predict with the step's odometry; correct with landmark readings when there are any.

        Parameters
        ----------
        estimate : numpy.ndarray, shape (M, 3)
            The means at the start of the step, of robots ``index``.
        ticks : numpy.ndarray, shape (M, 2)
            Tick differences counted during the step.
        dt : float
            Step [s].
        pose, twist : numpy.ndarray, shape (M, 3)
            The truth (unused).
        state : KalmanState
            Every robot's covariance and counts.
        index : numpy.ndarray of int, shape (M,)
            Which robots these are.
        readings : Readings, optional
            What the sensors read after the step (rows as ``index``).

        Returns
        -------
        estimate : numpy.ndarray, shape (M, 3)
            The new means (NaN for a robot whose filter failed).
        twist : numpy.ndarray, shape (M, 3)
            The odometry's twist over the step.
        state : KalmanState
        """
        odom_now, odo_twist, _ = self.odometry.update(state.odom[index], ticks, dt, pose, twist)
        odom = state.odom.copy()
        odom[index] = odom_now
        control = odo_twist[:, [0, 2]]
        ids = z = None
        if readings is not None and readings.landmark_ids is not None:
            ids, z = readings.landmark_ids, readings.landmark_z
        cov = state.cov.copy()
        counts = state.counts.copy()
        mean = np.empty_like(estimate)
        try:
            mean[:], cov[index], found = self._step(estimate, state.cov[index], control, dt, ids, z)
            counts[index] += found
        except (EstimationError, InputError):  # one robot at a time: only the failing ones stop
            for row, i in enumerate(index):
                one = (slice(row, row + 1),)
                try:
                    m, c, found = self._step(
                        estimate[one], state.cov[i : i + 1], control[one], dt,
                        None if ids is None else ids[one], None if z is None else z[one],
                    )  # fmt: skip
                    mean[row], cov[i] = m[0], c[0]
                    counts[i] += found[0]
                except (EstimationError, InputError):
                    mean[row] = np.nan
        return mean, odo_twist, KalmanState(cov, counts, odom)

    def _step(self, mean, cov, control, dt, ids, z):
        found = np.zeros((mean.shape[0], len(COUNTS)), dtype=np.int64)
        mean, cov = self.filter.predict(mean, cov, control, dt)
        if ids is not None and ids.shape[1] > 0:
            mean, cov, info = self.filter.update(mean, cov, ids, z)
            found[:, 1] = info.accepted.sum(1)
            found[:, 2] = info.gated.sum(1)
            found[:, 3] = info.invalid.sum(1)
            found[:, 0] = info.accepted.any(1)
        return mean, cov, found


# --------------------------------------------------------------------------- particle filter
@dataclass
class ParticleState:
    """What a :class:`ParticleLocalizer` keeps: one AMCL belief per robot and the odometry.

    Attributes
    ----------
    filters : list of AMCLState
        Each robot's particles.
    seeds : numpy.ndarray of int64, shape (N,)
        Each robot's seed (of its filter's random stream).
    odom : numpy.ndarray, shape (N, 3)
        Dead-reckoned poses in the odometry frame (which starts at the start pose).
    correction : numpy.ndarray, shape (N, 3)
        The transform map ← odom from each robot's last filter update.
    cov : numpy.ndarray, shape (N, 3, 3)
        Covariance of each robot's heaviest cluster at its last update.
    particles : numpy.ndarray of int64, shape (N,)
        Particles each filter holds.
    counts : numpy.ndarray of int64, shape (N, len(COUNTS))
        Cumulative counts (:data:`COUNTS`).
    converged : numpy.ndarray of bool, shape (N,)
        Whether each filter's belief is one cluster (not ambiguous) at its last update (or
        at the start: true around a known start pose, false for a global start).
    steps : numpy.ndarray of int64, shape (N,)
        Steps of odometry each robot has taken: its time is ``steps·dt``, handed to
        :meth:`~wheelbase.localization.AMCL.update` (a :class:`VelocityMotion`'s per-second
        noise grows with the time between updates).
    """

    filters: list
    seeds: np.ndarray
    odom: np.ndarray
    correction: np.ndarray
    cov: np.ndarray
    particles: np.ndarray
    counts: np.ndarray
    converged: np.ndarray
    steps: np.ndarray


@dataclass(frozen=True, eq=False)
class ParticleLocalizer(_FusesOdometry):
    """AMCL on wheel odometry, the lidar and the landmarks, one filter per robot (module
    docstring).

    Parameters
    ----------
    amcl : AMCL
        The particle filter (its map, lidar, landmarks, motion noise, particle counts).
    odometry : EncoderOdometry
        The encoders and the dead reckoning of the odometry frame.
    initial_std : tuple of float
        Standard deviations (x [m], y [m], θ [rad]) of the particles drawn around the start
        pose, >= 0.
    global_start : bool
        Spread the particles over the map's free space instead (global localisation: the
        start pose is unknown to the filter, and its first estimate is its heaviest cluster,
        not converged).
    """

    amcl: Any
    odometry: EncoderOdometry
    initial_std: tuple[float, float, float] = (0.02, 0.02, math.radians(1.0))
    global_start: bool = False

    def __post_init__(self) -> None:
        from wheelbase.localization import AMCL

        if not isinstance(self.amcl, AMCL):
            raise ConfigError(f"amcl must be an AMCL (got {type(self.amcl).__name__})")
        if self.amcl.lidar is None and self.amcl.landmarks is None:
            raise ConfigError("the AMCL needs a lidar (and its map) or landmarks to correct with")
        self._check_odometry_and_std()
        if self.global_start:
            self.amcl.random_poses(1, 0)  # a map without free space fails here, at set-up

    def start(self, poses: np.ndarray, seeds: np.ndarray) -> ParticleState:
        """Particles around each start pose, odometry at the start; or, with
        ``global_start``, particles over the free space and the odometry frame at the origin
        (the start poses are not looked at).

        Parameters
        ----------
        poses : numpy.ndarray, shape (N, 3)
            Start poses.
        seeds : numpy.ndarray of int, shape (N,)
            The robots' seeds (their particle filters' random streams).
        """
        n = poses.shape[0]
        generators = [counter_stream(s, PARTICLE_STREAM, 0) for s in seeds]
        _, cov = _initial_cov(self.initial_std, 1)
        covs = np.broadcast_to(cov, (n, 3, 3)).copy()
        correction = np.zeros((n, 3))
        filters = []
        if self.global_start:  # nothing of the truth: the first estimate is the filter's
            odom = np.zeros((n, 3))
            for i in range(n):
                belief = self.amcl.global_state(odom[i], generators[i])
                found = self.amcl.estimate(belief)
                correction[i], covs[i] = found.pose, found.cov
                filters.append(replace(belief, time=0.0))
            converged = np.zeros(n, dtype=bool)
        else:
            odom = poses.copy()
            for i in range(n):
                belief = self.amcl.initial_state(poses[i], cov[0], poses[i], generators[i])
                filters.append(replace(belief, time=0.0))  # stamped: the first update's time
            converged = np.ones(n, dtype=bool)
        return ParticleState(
            filters=filters,
            seeds=np.array(seeds, dtype=np.int64),
            odom=odom,
            correction=correction,
            cov=covs,
            particles=np.array([f.particles.shape[0] for f in filters], dtype=np.int64),
            counts=np.zeros((n, len(COUNTS)), dtype=np.int64),
            converged=converged,
            steps=np.zeros(n, dtype=np.int64),
        )

    def first_estimate(self, state: ParticleState) -> np.ndarray:
        """The estimate ``(N, 3)`` the controller sees at t = 0: correction ∘ odometry (the
        start pose given, or the heaviest cluster of a global start).

        Parameters
        ----------
        state : ParticleState
            :meth:`start`'s state.
        """
        estimate = compose(state.correction, state.odom)
        estimate[:, 2] = wrap_angle(estimate[:, 2])
        return estimate

    def update(self, estimate, ticks, dt, pose, twist, *, state, index, readings=None):
        """Dead-reckon the odometry; run the filters of robots with readings that moved enough.

        Parameters
        ----------
        estimate : numpy.ndarray, shape (M, 3)
            The estimates at the start of the step (unused: the odometry and the correction
            make the estimate).
        ticks : numpy.ndarray, shape (M, 2)
            Tick differences counted during the step.
        dt : float
            Step [s].
        pose, twist : numpy.ndarray, shape (M, 3)
            The truth (unused).
        state : ParticleState
            Every robot's filter.
        index : numpy.ndarray of int, shape (M,)
            Which robots these are.
        readings : Readings, optional
            What the sensors read after the step (rows as ``index``).

        Returns
        -------
        estimate : numpy.ndarray, shape (M, 3)
            correction ∘ odometry (NaN for a robot whose filter failed).
        twist : numpy.ndarray, shape (M, 3)
            The odometry's twist over the step.
        state : ParticleState
        """
        odom_now, odo_twist, _ = self.odometry.update(state.odom[index], ticks, dt, pose, twist)
        odom = state.odom.copy()
        odom[index] = odom_now
        filters = list(state.filters)
        correction, cov = state.correction.copy(), state.cov.copy()
        particles, counts = state.particles.copy(), state.counts.copy()
        converged, steps = state.converged.copy(), state.steps.copy()
        steps[index] += 1
        failed = np.zeros(index.size, dtype=bool)
        if readings is not None and not readings.empty:
            amcl = self.amcl
            use_scan = readings.scan is not None and amcl.lidar is not None
            use_marks = readings.landmark_ids is not None and amcl.landmarks is not None
            for row, i in enumerate(index):
                if not (use_scan or use_marks) or not amcl.needs_update(filters[i], odom_now[row]):
                    continue
                try:
                    new, info = amcl.update(
                        filters[i], odom_now[row],
                        counter_stream(state.seeds[i], PARTICLE_STREAM, steps[i]), force=True,
                        scan=readings.scan[row] if use_scan else None,
                        landmark_ids=readings.landmark_ids[row] if use_marks else None,
                        landmark_z=readings.landmark_z[row] if use_marks else None,
                        time=float(steps[i]) * dt,
                    )  # fmt: skip
                    found = amcl.estimate(new)
                except (EstimationError, InputError):
                    failed[row] = True
                    continue
                filters[i] = new
                correction[i] = compose(found.pose, inverse_pose(odom_now[row]))
                cov[i] = found.cov
                converged[i] = not found.ambiguous
                particles[i] = info.particles
                counts[i] += (1, info.landmarks_used, 0, info.landmarks_skipped,
                              info.beams_used, info.beams_skipped)  # fmt: skip
        new_estimate = compose(correction[index], odom_now)
        new_estimate[:, 2] = wrap_angle(new_estimate[:, 2])
        new_estimate[failed] = np.nan
        return (
            new_estimate,
            odo_twist,
            ParticleState(
                filters, state.seeds, odom, correction, cov, particles, counts, converged, steps
            ),
        )

    def particles_of(self, state: ParticleState, robot: int) -> np.ndarray:
        """Robot ``robot``'s particle poses ``(P, 3)`` in the map frame (for drawing).

        Parameters
        ----------
        state : ParticleState
            The filters' state.
        robot : int
            Which robot.
        """
        return state.filters[robot].particles
