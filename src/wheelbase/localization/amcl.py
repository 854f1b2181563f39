"""AMCL: adaptive Monte Carlo localisation as Nav2's ``nav2_amcl`` does it.

One filter update (:meth:`AMCL.update`) takes the robot's odometry pose and, optionally, a lidar
scan and landmark measurements:

1. **When to update.** Nothing happens until the odometry has moved ``update_min_d`` or turned
   ``update_min_a`` since the last update (Nav2's rule; 0 and 0 update on every call).
2. **Motion.** Every particle moves by the odometry's relative motion with independent noise
   (:class:`~wheelbase.localization.motion.OdometryMotion`).
3. **Measurement.** The weights are multiplied by the likelihood of the scan on the map's
   likelihood field (``max_beams`` beams, evenly subsampled) and of the landmark measurements
   (:mod:`wheelbase.localization.likelihood`).
4. **Recovery (augmented MCL, Thrun, Burgard and Fox Table 8.3).** Short- and long-term averages
   w_fast and w_slow (rates ``recovery_alpha_fast`` and ``recovery_alpha_slow``) of the
   measurement's evidence p(z | past data) = Σ w·p(z | x) (the book's w_avg) give the
   probability max(0, 1 − w_fast/w_slow) with which each resampled particle is replaced by a
   random pose in the free space: when the scans suddenly fit worse than they used to (a
   kidnapped robot) fresh guesses come in. Two departures from the book: the averages are of
   the *log*-evidence per measurement (a geometric mean over the beams, so that w_fast/w_slow
   means the same with 6 or 60 beams; with 60 beams the likelihoods span e^±100); and, as in
   Fox's KLD sampling and Nav2, the bins the random poses fill count towards the particle
   number, so that an injection grows the set (up to ``max_particles``) instead of thinning a
   set of 500. An earlier version averaged the *best* particle's fit: after a kidnapping one
   lucky guess among thousands on a near twin of the true pose (the maze has several) stopped
   the injection at once, and 2 of 10 kidnapped robots recovered within 30 s (5 with 60 beams);
   with the evidence, which stays low until the weight has gathered on poses that fit, and the
   growing set, 7 of 10, and all 10 once the maze had no corridor that is its own twin
   (:data:`GLOBAL_LOCALIZATION`). Unlike Nav2,
   which restarts both averages after every injection, the averages run on as in the book: the
   injection goes on while the fit stays worse.
5. **Resampling** every ``resample_interval`` updates: the KLD bound fixes the number of
   particles between ``min_particles`` and ``max_particles`` and one low-variance pass draws
   them (:mod:`wheelbase.localization.particles`).

The belief is an :class:`AMCLState` passed in and returned. :meth:`AMCL.estimate` reports the
heaviest cluster of particles as the pose, and every cluster: where the map is ambiguous the
weight is split between clusters (``ambiguous`` is true), rather than hidden in one mean.

Defaults are Nav2's (recovery off, as there), except two: the KLD quantile (see
:mod:`~wheelbase.localization.particles`) and the beams of the likelihood field, combined as
the book's product rather than Nav2's 1 + Σ p³ (``beam_combination="cubes"`` restores it): with
the sum of cubes a particle that explains nothing keeps 1/9 of the weight of one that explains
every beam, and in the bundled warehouse a tracked cloud leaked into a look-alike aisle within
12 m and jumped there.

For global localisation and the kidnapped robot use
``sensor_model="beam"`` (the ray-cast beam model of Thrun et al. §6.3, which also penalises
beams that pass through walls: the likelihood field ignores them, and the maze's corridors,
4 m apart, then look alike), ``min_ess`` about 0.3, and recovery rates such as 0.001 and 0.1
(Thrun's): :data:`GLOBAL_LOCALIZATION`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
from numpy.typing import ArrayLike

from wheelbase._validate import (
    as_float_array,
    as_rng,
    check_choice,
    integer,
    nonnegative,
    positive,
)
from wheelbase.errors import ConfigError, EstimationError, InputError, MapError
from wheelbase.geometry import compose, relative_pose, wrap_angle
from wheelbase.limits import MAX_BEAMS, MAX_PARTICLES
from wheelbase.localization.likelihood import (
    LikelihoodField,
    landmark_log_likelihood,
    likelihood_field,
    scan_log_likelihood,
)
from wheelbase.localization.motion import OdometryMotion, VelocityMotion, odometry_delta
from wheelbase.localization.particles import (
    Cluster,
    clusters,
    kld_particles,
    low_variance_resample,
)
from wheelbase.planning import OccupancyGrid
from wheelbase.sensors import BeamModel, Lidar, scan_rays

__all__ = [
    "AMCL",
    "BEAM_COMBINATIONS",
    "GLOBAL_LOCALIZATION",
    "SENSOR_MODELS",
    "AMCLInfo",
    "AMCLState",
    "PoseEstimate",
]

SENSOR_MODELS: tuple[str, ...] = ("likelihood_field", "beam")
"""Lidar models of :class:`AMCL` (its docstring)."""
BEAM_COMBINATIONS: tuple[str, ...] = ("product", "cubes")
"""How the likelihood field combines beams: the book's Π p or Nav2's 1 + Σ p³."""
GLOBAL_LOCALIZATION: dict[str, object] = {
    "sensor_model": "beam",
    "min_particles": 2000,
    "max_particles": 20000,
    "max_beams": 120,
    "min_ess": 0.3,
    "z_hit": 0.9,
    "z_short": 0.05,
    "z_rand": 0.05,
    "lambda_short": 0.5,
    "recovery_alpha_slow": 0.001,
    "recovery_alpha_fast": 0.1,
}
"""Options of :class:`AMCL` for global localisation and the kidnapped robot (module
docstring): ``AMCL(grid=..., lidar=..., **GLOBAL_LOCALIZATION)``. On the maze with a 30 m,
360-beam lidar, 20 of 20 wandering robots were within 0.2 m for good within 10 m of travel
(``benchmarks/sensors.py``), and 80 of 80 on other seeds (100–139, 200–239); kidnapped robots
(``kidnapped_run`` of ``benchmarks/amcl_trials.py``) recovered within 30 s in 10 of 10 runs
(2.8–11.1 s), and 20 of 20 on seeds 10–29.

What makes the maze hard are its near twins: a corridor 8 m away that differs by 0.3 m of
width, and each corridor turned by a half turn about its own centre (its gaps are at
opposite ends). What tells them apart are the stubs, 0.2 m wide, one per corridor: Nav2's
60 beams, 6° apart, miss them beyond 2 m (with 60 beams 2 of 20 and 3 of 40 routes settled on
a twin); 120 beams, 3° apart, for about twice the time. While the weight sits on a twin the
set shrinks towards ``min_particles``, and the true pose's cluster must survive in what is
left until the stubs come into view: with Nav2's 500, 2 of 100 routes lost it (19 of 20, 39
of 40, 40 of 40 on the three seed sets) for 2,000, at 1.4 times the time. The maze's fourth
corridor had no stub until the kidnapped robots showed it: carried there, 3 of 10 settled on
its half-turn twin, which no scan inside it can tell apart."""


@dataclass(frozen=True)
class AMCLState:
    """The particle filter's belief.

    Attributes
    ----------
    particles : numpy.ndarray, shape (P, 3)
        Particle poses (x [m], y [m], θ [rad]).
    weights : numpy.ndarray, shape (P,)
        Normalised weights.
    odom : numpy.ndarray, shape (3,)
        Odometry pose at the last filter update.
    log_w_slow, log_w_fast : float
        Logarithms of the long- and short-term likelihood averages (−inf: not started).
    updates : int
        Filter updates so far.
    time : float
        Time [s] of the last update, when the caller gives times (NaN otherwise).
    """

    particles: np.ndarray
    weights: np.ndarray
    odom: np.ndarray
    log_w_slow: float = -math.inf
    log_w_fast: float = -math.inf
    updates: int = 0
    time: float = math.nan


@dataclass(frozen=True)
class AMCLInfo:
    """What one call of :meth:`AMCL.update` did.

    Attributes
    ----------
    updated : bool
        Whether the filter updated (the odometry moved enough).
    beams_used : int
        Lidar readings that weighted the particles.
    beams_skipped : int
        Beams of the ``max_beams`` chosen that were not used: NaN or negative readings, and
        for the likelihood field max-range readings (no return); used + skipped = the beams
        chosen.
    landmarks_used : int
        Landmark measurements that weighted the particles.
    landmarks_skipped : int
        Measurements skipped: unknown identity, NaN or negative range, NaN bearing.
    injected : int
        Random particles added by recovery.
    particles : int
        Particles after the update.
    """

    updated: bool
    beams_used: int = 0
    beams_skipped: int = 0
    landmarks_used: int = 0
    landmarks_skipped: int = 0
    injected: int = 0
    particles: int = 0


@dataclass(frozen=True)
class PoseEstimate:
    """The filter's answer: the heaviest cluster's mean, and all clusters.

    Attributes
    ----------
    pose : numpy.ndarray, shape (3,)
        Mean of the heaviest cluster.
    cov : numpy.ndarray, shape (3, 3)
        Its covariance.
    clusters : list of Cluster
        Every cluster, heaviest first, weights summing to 1.
    ambiguous : bool
        True when the clusters other than the heaviest hold at least ``ambiguity_weight`` of
        the weight together (one rival, or the weight spread over many small ones).
    """

    pose: np.ndarray
    cov: np.ndarray
    clusters: list[Cluster]
    ambiguous: bool


@dataclass(frozen=True, eq=False)
class AMCL:
    """Adaptive Monte Carlo localisation (module docstring).

    Parameters
    ----------
    grid : OccupancyGrid or None
        The map: needed for lidar scans and for random particles (global localisation,
        recovery).
    lidar : Lidar or None
        The lidar whose scans are given (beam angles, range limits, mount).
    landmarks : array_like or None, shape (L, 2)
        Known landmark positions [m] for range–bearing measurements.
    motion : OdometryMotion or VelocityMotion
        Odometry noise: Nav2's ``alpha1``–``alpha4``, or noise linear in the odometry's arc
        (Δs, Δθ) between updates, as the Kalman filters' (for frequent updates, where the
        quadratic α terms vanish).
    min_particles, max_particles : int
        Limits of the KLD-adapted particle count (Nav2 500 and 2,000).
    kld_err : float
        ε of KLD sampling (Nav2 ``pf_err``, 0.05).
    kld_delta : float
        δ of KLD sampling: the bound holds with probability 1 − δ (0.01).
    bin_size : tuple of float
        KLD and cluster bins (x [m], y [m], θ [rad]); Nav2 0.5 m, 0.5 m, 10°.
    max_beams : int
        Beams used per scan (Nav2 60).
    z_hit, z_rand : float
        Weights of the likelihood field (Nav2 0.5, 0.5); z_hit > 0.
    sigma_hit : float
        σ_hit of the likelihood field [m] (Nav2 0.2).
    likelihood_max_dist : float
        Distance cap of the likelihood field [m] (Nav2 ``laser_likelihood_max_dist`` 2.0).
    sensor_model : {"likelihood_field", "beam"}
        Lidar model: Nav2's likelihood field (:mod:`~wheelbase.localization.likelihood`), or
        the beam model of Thrun et al. §6.3 on ranges ray-cast from every particle
        (:func:`wheelbase.sensors.scan_rays`; about 10× the cost).
    beam_combination : {"product", "cubes"}
        How the likelihood field combines beams: the book's product or Nav2's 1 + Σ p³.
    z_short : float
        Weight of short readings in the beam model (Nav2 0.05).
    z_max : float
        Weight of missed returns in the beam model (Nav2 0.05): a reading at ``max_range``
        scores z_max, plus z_hit where the particle expects nothing within range (Nav2's
        ``z_max`` term; the likelihood field skips such readings, as Nav2's does).
    lambda_short : float
        Rate of short readings in the beam model [1/m] (Nav2 0.1).
    min_ess : float
        Tempering, in [0, 1): when an update would leave fewer than ``min_ess``·P effective
        particles, the likelihood is raised to the largest power β < 1 that keeps that many
        (annealing; it keeps several hypotheses alive while the particles are spread). 0: off.
    landmark_range_std, landmark_bearing_std : float
        Standard deviations of landmark range [m] and bearing [rad].
    landmark_z_rand : float
        Weight of the uniform floor of the landmark likelihood (robustness to outliers), in
        [0, 1); the Gaussian has weight 1 − landmark_z_rand.
    landmark_max_range : float
        Range [m] over which that floor is spread.
    recovery_alpha_slow, recovery_alpha_fast : float
        Averaging rates of w_slow and w_fast, 0 <= slow < fast <= 1; 0 and 0 disable recovery.
    update_min_d : float
        Translation [m] that triggers an update (Nav2 0.25).
    update_min_a : float
        Rotation [rad] that triggers an update (Nav2 0.2).
    resample_interval : int
        Resample every this many updates (Nav2 1).
    """

    grid: OccupancyGrid | None = None
    lidar: Lidar | None = None
    landmarks: np.ndarray | None = None
    motion: OdometryMotion = field(default_factory=OdometryMotion)
    min_particles: int = 500
    max_particles: int = 2000
    kld_err: float = 0.05
    kld_delta: float = 0.01
    bin_size: tuple[float, float, float] = (0.5, 0.5, math.radians(10.0))
    max_beams: int = 60
    z_hit: float = 0.5
    z_rand: float = 0.5
    sigma_hit: float = 0.2
    likelihood_max_dist: float = 2.0
    sensor_model: str = "likelihood_field"
    beam_combination: str = "product"
    z_short: float = 0.05
    z_max: float = 0.05
    lambda_short: float = 0.1
    min_ess: float = 0.0
    landmark_range_std: float = 0.1
    landmark_bearing_std: float = 0.05
    landmark_z_rand: float = 0.0
    landmark_max_range: float = 10.0
    recovery_alpha_slow: float = 0.0
    recovery_alpha_fast: float = 0.0
    update_min_d: float = 0.25
    update_min_a: float = 0.2
    resample_interval: int = 1

    def __post_init__(self) -> None:
        if self.grid is not None and not isinstance(self.grid, OccupancyGrid):
            raise ConfigError(f"grid must be an OccupancyGrid (got {type(self.grid).__name__})")
        if self.lidar is not None:
            if not isinstance(self.lidar, Lidar):
                raise ConfigError(f"lidar must be a Lidar (got {type(self.lidar).__name__})")
            if self.grid is None:
                raise ConfigError("a lidar needs a grid: the likelihood field is built on it")
        if self.landmarks is not None:
            marks = as_float_array("landmarks", self.landmarks, 2, min_ndim=2, max_ndim=2)
            object.__setattr__(self, "landmarks", marks)
        if not isinstance(self.motion, OdometryMotion | VelocityMotion):
            raise ConfigError(
                "motion must be an OdometryMotion or a VelocityMotion "
                f"(got {type(self.motion).__name__})"
            )
        lo = integer("min_particles", self.min_particles, minimum=1, maximum=MAX_PARTICLES)
        hi = integer("max_particles", self.max_particles, minimum=1, maximum=MAX_PARTICLES)
        if lo > hi:
            raise ConfigError(f"min_particles must be <= max_particles = {hi} (got {lo})")
        delta = positive("kld_delta", self.kld_delta)
        if not 1e-12 <= delta < 1.0:  # below 1e-12 the normal quantile is no longer finite
            raise ConfigError(f"kld_delta must be in [1e-12, 1) (got {delta:g})")
        size = as_float_array("bin_size", self.bin_size, 3, max_ndim=1)
        if np.any(size <= 0):
            raise ConfigError(f"bin_size must be > 0 (x [m], y [m], θ [rad]) (got {size})")
        object.__setattr__(self, "bin_size", tuple(float(v) for v in size))
        # the checked numbers are kept, not what was given (a string "2" passed and then
        # failed inside NumPy; 1e10 as max_particles could not slice)
        checked: dict[str, object] = {
            "min_particles": lo,
            "max_particles": hi,
            "max_beams": integer("max_beams", self.max_beams, minimum=1, maximum=MAX_BEAMS),
            "resample_interval": integer("resample_interval", self.resample_interval, minimum=1),
            "kld_delta": delta,
        }
        positives = (
            "kld_err",
            "z_hit",
            "landmark_range_std",
            "landmark_bearing_std",
            "sigma_hit",
            "likelihood_max_dist",
            "landmark_max_range",
            "lambda_short",
        )
        for name in positives:
            checked[name] = positive(name, getattr(self, name))
        for name in ("sigma_hit", "landmark_range_std", "landmark_bearing_std"):
            variance = checked[name] * checked[name]  # type: ignore[operator]
            if not 0.0 < variance < math.inf:  # Gaussians divide by it
                raise ConfigError(f"{name} must be in [1e-150, 1e150] (got {checked[name]:g})")
        for name in ("z_rand", "z_short", "z_max", "update_min_d", "update_min_a"):
            checked[name] = nonnegative(name, getattr(self, name))
        for name, value in checked.items():
            object.__setattr__(self, name, value)
        check_choice("sensor_model", self.sensor_model, SENSOR_MODELS)
        check_choice("beam_combination", self.beam_combination, BEAM_COMBINATIONS)
        ess = nonnegative("min_ess", self.min_ess)
        if ess >= 1.0:
            raise ConfigError(f"min_ess must be in [0, 1) (got {ess:g})")
        z = nonnegative("landmark_z_rand", self.landmark_z_rand)
        if z >= 1.0:
            raise ConfigError(f"landmark_z_rand must be in [0, 1) (got {z:g})")
        slow = nonnegative("recovery_alpha_slow", self.recovery_alpha_slow)
        fast = nonnegative("recovery_alpha_fast", self.recovery_alpha_fast)
        if fast > 1.0 or slow > fast or (slow == fast and slow > 0.0):
            raise ConfigError(
                "recovery rates must satisfy 0 <= recovery_alpha_slow < recovery_alpha_fast <= 1 "
                f"(got {slow:g} and {fast:g}); 0 and 0 disable recovery"
            )

    # ------------------------------------------------------------------ derived maps
    @cached_property
    def _field(self) -> LikelihoodField:
        assert self.grid is not None and self.lidar is not None
        return likelihood_field(
            self.grid, self.z_hit, self.z_rand, self.sigma_hit, self.likelihood_max_dist,
            self.lidar.max_range,
        )  # fmt: skip

    @cached_property
    def _log_field(self) -> LikelihoodField:
        return self._field.log()

    @cached_property
    def _beam_model(self) -> BeamModel:
        total = self.z_hit + self.z_short + self.z_max + self.z_rand
        return BeamModel(
            z_hit=self.z_hit / total,
            z_short=self.z_short / total,
            z_max=self.z_max / total,
            z_rand=self.z_rand / total,
            lambda_short=self.lambda_short,
        )

    @cached_property
    def _outside(self) -> float:
        assert self.lidar is not None
        d = self.likelihood_max_dist
        return self.z_hit * math.exp(-d * d / (2.0 * self.sigma_hit * self.sigma_hit)) + (
            self.z_rand / self.lidar.max_range
        )

    @cached_property
    def _beam_index(self) -> np.ndarray:
        assert self.lidar is not None
        count = self.lidar.beams
        if self.max_beams >= count:
            return np.arange(count)
        return np.unique(np.round(np.linspace(0, count - 1, self.max_beams)).astype(np.int64))

    @cached_property
    def _free_cells(self) -> np.ndarray:
        if self.grid is None:
            raise ConfigError("random particles need a grid: pass grid= to AMCL")
        free = np.argwhere(~self.grid.occupied)
        if free.size == 0:
            raise MapError("the map has no free cell: global localisation has nowhere to look")
        return free

    @cached_property
    def _free_bins(self) -> float:
        """KLD bins (x, y, θ) that random poses spread over: the free area in bins × headings."""
        assert self.grid is not None
        area = self._free_cells.shape[0] * self.grid.resolution**2
        headings = max(1, round(2.0 * math.pi / self.bin_size[2]))
        return max(1.0, area / (self.bin_size[0] * self.bin_size[1]) * headings)

    def random_poses(self, n: int, rng: np.random.Generator | int | None = None) -> np.ndarray:
        """Poses uniformly distributed over the free cells of the map, any heading.

        Parameters
        ----------
        n : int
            Number of poses.
        rng : numpy.random.Generator, int or None
            Source of randomness.

        Returns
        -------
        numpy.ndarray, shape (n, 3)
        """
        rng = as_rng(rng)
        free = self._free_cells
        assert self.grid is not None
        cells = free[rng.integers(len(free), size=n)].astype(np.float64)
        xy = np.asarray(self.grid.origin) + (cells[:, ::-1] + rng.random((n, 2))) * (
            self.grid.resolution
        )
        return np.column_stack([xy, rng.uniform(-math.pi, math.pi, n)])

    # ------------------------------------------------------------------ initial beliefs
    def initial_state(
        self,
        pose: ArrayLike,
        cov: ArrayLike,
        odom: ArrayLike = (0.0, 0.0, 0.0),
        rng: np.random.Generator | int | None = None,
    ) -> AMCLState:
        """``max_particles`` particles drawn from a Gaussian around a pose (Nav2's initial pose).

        Parameters
        ----------
        pose : array_like, shape (3,)
            Mean pose.
        cov : array_like, shape (3, 3)
            Covariance (positive semi-definite).
        odom : array_like, shape (3,)
            The odometry pose at this moment.
        rng : numpy.random.Generator, int or None
            Source of randomness.

        Returns
        -------
        AMCLState
        """
        pose = as_float_array("pose", pose, 3, max_ndim=1)
        cov = as_float_array("cov", cov, 3, min_ndim=2, max_ndim=2)
        if cov.shape != (3, 3) or np.linalg.eigvalsh(0.5 * (cov + cov.T))[0] < -1e-12:
            raise InputError("cov must be a 3×3 positive semi-definite matrix")
        rng = as_rng(rng)
        particles = rng.multivariate_normal(pose, cov, self.max_particles, method="eigh")
        particles[:, 2] = wrap_angle(particles[:, 2])
        return self._state(particles, odom)

    def global_state(
        self, odom: ArrayLike = (0.0, 0.0, 0.0), rng: np.random.Generator | int | None = None
    ) -> AMCLState:
        """``max_particles`` particles spread uniformly over the free space (global localisation).

        Parameters
        ----------
        odom : array_like, shape (3,)
            The odometry pose at this moment.
        rng : numpy.random.Generator, int or None
            Source of randomness.

        Returns
        -------
        AMCLState
        """
        return self._state(self.random_poses(self.max_particles, rng), odom)

    def _state(self, particles: np.ndarray, odom: ArrayLike) -> AMCLState:
        odom = as_float_array("odom", odom, 3, max_ndim=1)
        n = particles.shape[0]
        return AMCLState(particles, np.full(n, 1.0 / n), odom.copy())

    # ------------------------------------------------------------------ the update
    def needs_update(self, state: AMCLState, odom: ArrayLike) -> bool:
        """Whether the odometry moved ``update_min_d`` or turned ``update_min_a`` since the
        last update.

        Parameters
        ----------
        state : AMCLState
            The belief.
        odom : array_like, shape (3,)
            Odometry pose now.

        Returns
        -------
        bool
        """
        odom = np.asarray(odom, dtype=np.float64)
        moved = math.hypot(odom[0] - state.odom[0], odom[1] - state.odom[1])
        turned = abs(math.remainder(odom[2] - state.odom[2], 2.0 * math.pi))
        return moved >= self.update_min_d or turned >= self.update_min_a

    def update(
        self,
        state: AMCLState,
        odom: ArrayLike,
        rng: np.random.Generator | int | None = None,
        *,
        scan: ArrayLike | None = None,
        landmark_ids: ArrayLike | None = None,
        landmark_z: ArrayLike | None = None,
        force: bool = False,
        time: float | None = None,
    ) -> tuple[AMCLState, AMCLInfo]:
        """One filter update from the odometry pose and the measurements taken there.

        Parameters
        ----------
        state : AMCLState
            The belief.
        odom : array_like, shape (3,)
            Odometry pose now (x [m], y [m], θ [rad]) in the odometry frame.
        rng : numpy.random.Generator, int or None
            Source of randomness.
        scan : array_like or None, shape (beams,)
            Lidar ranges [m] from the :attr:`lidar`.
        landmark_ids : array_like of int or None, shape (M,)
            Identities of measured landmarks (rows of :attr:`landmarks`).
        landmark_z : array_like or None, shape (M, 2)
            Their (range [m], bearing [rad]).
        force : bool
            Update even if the robot has not moved ``update_min_d`` / ``update_min_a``.
        time : float or None
            Time [s] now: with a :class:`VelocityMotion`, its per-second noise grows over the
            time since the last update.

        Returns
        -------
        state : AMCLState
            The new belief (the same object when nothing happened).
        info : AMCLInfo
            What was done.
        """
        odom = as_float_array("odom", odom, 3, max_ndim=1)
        if not (force or self.needs_update(state, odom)):
            return state, AMCLInfo(updated=False, particles=state.particles.shape[0])
        delta = odometry_delta(state.odom, odom)
        rng = as_rng(rng)
        if isinstance(self.motion, VelocityMotion):
            elapsed = 0.0 if time is None or not np.isfinite(state.time) else time - state.time
            relative = relative_pose(state.odom, odom)
            particles = self.motion.sample_relative(
                state.particles, relative, max(elapsed, 0.0), rng
            )
        else:
            particles = self.motion.sample(state.particles, delta, rng)
        log_lik = np.zeros(particles.shape[0])
        beams_used = beams_skipped = marks_used = marks_skipped = 0
        if scan is not None:
            log_scan, beams_used, beams_skipped = self._scan_likelihood(particles, scan)
            log_lik += log_scan
        if landmark_ids is not None or landmark_z is not None:
            log_marks, marks_used, marks_skipped = self._landmark_likelihood(
                particles, landmark_ids, landmark_z
            )
            log_lik += log_marks
        measured = beams_used + marks_used > 0
        log_prior = np.log(np.maximum(state.weights, 1e-300))
        log_w = log_prior + log_lik
        top = float(log_w.max())
        if not np.isfinite(top):
            raise EstimationError(
                "AMCL: every particle weight is zero or not finite; check sigma_hit, "
                "landmark_range_std and landmark_bearing_std"
            )
        # the evidence p(z | past data) = Σ w_prior·p(z | x), per measurement (the book's w_avg)
        log_evidence = (top + math.log(float(np.exp(log_w - top).sum()))) / max(
            1, beams_used + marks_used
        )
        if measured and self.min_ess > 0.0:
            log_w = log_prior + _tempering(log_prior, log_lik, self.min_ess) * log_lik
            top = float(log_w.max())
        weights = np.exp(log_w - top)
        weights /= weights.sum()
        log_slow, log_fast = state.log_w_slow, state.log_w_fast
        if measured:
            log_slow = _average(log_slow, log_evidence, self.recovery_alpha_slow)
            log_fast = _average(log_fast, log_evidence, self.recovery_alpha_fast)
        updates = state.updates + 1
        injected = 0
        if measured and updates % self.resample_interval == 0:
            particles, weights, injected, log_slow, log_fast = self._resample(
                particles, weights, log_slow, log_fast, rng
            )
        stamp = math.nan if time is None else float(time)
        new = AMCLState(particles, weights, odom.copy(), log_slow, log_fast, updates, stamp)
        info = AMCLInfo(
            True, beams_used, beams_skipped, marks_used, marks_skipped, injected,
            particles.shape[0],
        )  # fmt: skip
        return new, info

    def _scan_likelihood(
        self, particles: np.ndarray, scan: ArrayLike
    ) -> tuple[np.ndarray, int, int]:
        if self.lidar is None:
            raise ConfigError(
                "a scan needs the lidar that took it: pass lidar= (and grid=) to AMCL"
            )
        try:
            ranges = np.asarray(scan, dtype=np.float64).reshape(-1)
        except (TypeError, ValueError):
            raise InputError(
                f"scan must be {self.lidar.beams} ranges [m] (got {scan!r:.80})"
            ) from None
        if ranges.size != self.lidar.beams:
            raise InputError(f"scan must have {self.lidar.beams} ranges (got {ranges.size})")
        chosen = self._beam_index
        r = ranges[chosen]
        limit = self.lidar.max_range
        keep = np.isfinite(r) & (r >= 0.0)  # NaN (blind zone) and negative: no reading
        if self.sensor_model != "beam":
            keep &= r < limit  # the likelihood field skips max-range readings (no return)
        skipped = int(chosen.size - keep.sum())  # of the beams chosen, those never used
        if not keep.any():
            return np.zeros(particles.shape[0]), 0, skipped
        angles = self.lidar.beam_angles[chosen][keep]
        if self.sensor_model == "beam":
            sensor = compose(particles, np.asarray(self.lidar.mount))
            expected = scan_rays(self.grid, sensor[:, :2], sensor[:, 2], angles, limit)
            no_return = expected >= limit  # the particle expects nothing within range
            # a return where none is expected is scored as if the wall were at the limit
            expected = np.minimum(expected, np.nextafter(limit, 0.0))
            reading = np.broadcast_to(np.minimum(r[keep], limit), expected.shape)
            model = self._beam_model
            density = model.pdf(reading, expected, self.sigma_hit, limit)
            # a max-range reading: the probability of exactly z_max, a missed return (z_max)
            # or a hit with nothing to hit (Nav2 adds z_max·1 for such a reading)
            at_max = reading >= limit
            mass = model.z_max + model.z_hit * no_return
            density = np.where(at_max, mass, density)
            log_p = np.log(np.maximum(density, 1e-300)).sum(axis=1)
        else:
            product = self.beam_combination == "product"
            log_p = scan_log_likelihood(
                self._log_field if product else self._field, self.grid, particles,
                np.asarray(self.lidar.mount), r[keep], angles,
                math.log(max(self._outside, 2.2e-308)) if product else self._outside, product,
            )  # fmt: skip
        return log_p, int(keep.sum()), skipped

    def _landmark_likelihood(
        self, particles: np.ndarray, ids: ArrayLike | None, z: ArrayLike | None
    ) -> tuple[np.ndarray, int, int]:
        if self.landmarks is None:
            raise ConfigError("landmark measurements need landmarks=: pass them to AMCL")
        if ids is None or z is None:
            raise InputError("landmark_ids and landmark_z come together")
        ids = np.asarray(ids).reshape(-1)
        if ids.size and not np.issubdtype(ids.dtype, np.integer):
            raise InputError(f"landmark_ids must be integers (got dtype {ids.dtype})")
        z = np.asarray(z, dtype=np.float64).reshape(-1, 2)
        if z.shape[0] != ids.size:
            raise InputError(f"landmark_z must have shape ({ids.size}, 2) (got {z.shape})")
        ok = (
            (ids >= 0)
            & (ids < self.landmarks.shape[0])
            & np.isfinite(z).all(1)
            & (np.nan_to_num(z[:, 0], nan=-1.0) >= 0.0)
        )
        if not ok.any():
            return np.zeros(particles.shape[0]), 0, int(ids.size)
        log_p = landmark_log_likelihood(
            particles,
            self.landmarks[ids[ok]],
            z[ok],
            self.landmark_range_std,
            self.landmark_bearing_std,
            1.0 - self.landmark_z_rand,
            self.landmark_z_rand,
            self.landmark_max_range,
        )
        return log_p, int(ok.sum()), int((~ok).sum())

    def _resample(self, particles, weights, log_slow, log_fast, rng):
        p_random = 0.0
        if self.recovery_alpha_slow > 0.0 and np.isfinite(log_slow) and self.grid is not None:
            p_random = max(0.0, 1.0 - math.exp(log_fast - log_slow))
        n = kld_particles(
            particles, weights, self.bin_size, self.kld_err, self.kld_delta,
            self.min_particles, self.max_particles, p_random, self._free_bins if p_random else 0.0,
        )  # fmt: skip
        new = particles[low_variance_resample(weights, n, rng)]
        injected = 0
        if p_random > 0.0:
            swap = rng.random(n) < p_random
            injected = int(swap.sum())
            new[swap] = self.random_poses(injected, rng)
        return new, np.full(n, 1.0 / n), injected, log_slow, log_fast

    # ------------------------------------------------------------------ the answer
    def estimate(self, state: AMCLState, ambiguity_weight: float = 0.1) -> PoseEstimate:
        """The pose of the heaviest cluster of particles, and every cluster.

        Parameters
        ----------
        state : AMCLState
            The belief.
        ambiguity_weight : float
            Weight the clusters besides the heaviest must hold together for the estimate to be
            ambiguous, in (0, 0.5].

        Returns
        -------
        PoseEstimate
        """
        share = positive("ambiguity_weight", ambiguity_weight)
        found = clusters(state.particles, state.weights, self.bin_size)
        best = found[0]
        ambiguous = len(found) > 1 and 1.0 - best.weight >= share
        return PoseEstimate(best.mean.copy(), best.cov.copy(), found, ambiguous)


def _average(log_old: float, log_new: float, rate: float) -> float:
    """Exponential average of log-likelihoods, (1 − rate)·old + rate·new, started at new."""
    if not np.isfinite(log_old):
        return log_new
    return (1.0 - rate) * log_old + rate * log_new


def _ess_fraction(log_w: np.ndarray) -> float:
    w = np.exp(log_w - log_w.max())
    return float(w.sum() ** 2 / (w @ w) / w.size)


def _tempering(log_prior: np.ndarray, log_lik: np.ndarray, rho: float) -> float:
    """Largest β in [0, 1] with ESS(prior · lik^β) >= rho·P (bisection to 2⁻³⁰)."""
    if _ess_fraction(log_prior + log_lik) >= rho:
        return 1.0
    lo, hi = 0.0, 1.0
    for _ in range(30):
        mid = 0.5 * (lo + hi)
        if _ess_fraction(log_prior + mid * log_lik) >= rho:
            lo = mid
        else:
            hi = mid
    return lo
