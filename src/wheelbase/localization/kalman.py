"""What the EKF and the UKF share: parameters, the measurement update loop, gating, checks.

Both filters estimate the pose (x, y, θ) of N robots at once: the belief is a mean of shape
``(N, 3)`` and a covariance ``(N, 3, 3)`` (or ``(3,)`` and ``(3, 3)`` for one robot), passed in
and returned, never stored in the filter. Landmark measurements come as identities ``(N, M)``
(−1 for "no measurement in this slot") and (range [m], bearing [rad]) pairs ``(N, M, 2)``, e.g.
from :meth:`wheelbase.sensors.LandmarkObservations.padded`; they are applied one slot after the
other (the loop over features of Thrun, Burgard and Fox, Table 7.2).

Each measurement's innovation ν = z − ẑ (bearing wrapped) and its covariance S give the
normalised innovation squared NIS = νᵀS⁻¹ν; a measurement with NIS above the χ² quantile of
``gate_probability`` with 2 degrees of freedom (9.21 at 0.99) is rejected as an outlier
(a misread barcode, a false detection). With ``huber_k`` finite, an accepted measurement whose
Mahalanobis distance √NIS exceeds it counts with the Huber weight k/√NIS (R divided by the
weight, S recomputed), so heavy-tailed errors pull less. Accepted ones update the belief with the
gain
K = P Hᵀ S⁻¹ and the Joseph form P⁺ = (I − KH) P (I − KH)ᵀ + K R' Kᵀ, R' = S − H P Hᵀ, which stays
symmetric and positive definite under rounding. For the EKF H is the Jacobian of the
range–bearing model and R' = R; for the UKF H = P_xzᵀ P⁻¹ is the statistical linearisation of its
sigma points, and R' = S − H P Hᵀ (which is R plus the linearisation error) makes the Joseph
form equal to the UKF's P − K S Kᵀ.

Measurements with a NaN or negative range, a NaN bearing or an identity that names no landmark
are skipped and reported as ``invalid``; a covariance that stops being positive semi-definite
(a zero covariance, a known pose, is allowed) or a non-finite belief raises
:class:`~wheelbase.errors.EstimationError`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike
from scipy import stats

from wheelbase._validate import as_float_array, nonnegative, positive
from wheelbase.errors import ConfigError, EstimationError, InputError
from wheelbase.geometry import wrap_angle
from wheelbase.localization.motion import VelocityMotion

__all__ = ["KalmanFilter", "UpdateInfo", "chi2_gate"]


def chi2_gate(probability: float, dof: int = 2) -> float:
    """The χ² quantile that accepts ``probability`` of correct measurements.

    Parameters
    ----------
    probability : float
        In (0, 1]; 1 disables the gate (infinite threshold).
    dof : int
        Degrees of freedom (2 for range and bearing).

    Returns
    -------
    float
        Threshold on the NIS.

    Examples
    --------
    >>> round(chi2_gate(0.99), 3)
    9.21
    """
    p = positive("gate_probability", probability)
    if p > 1.0:
        raise ConfigError(f"gate_probability must be in (0, 1] (got {p:g})")
    return float("inf") if p == 1.0 else float(stats.chi2.ppf(p, dof))


@dataclass(frozen=True)
class UpdateInfo:
    """What became of each measurement slot of one update.

    Attributes
    ----------
    accepted : numpy.ndarray, shape (N, M)
        Applied to the belief.
    gated : numpy.ndarray, shape (N, M)
        Rejected by the χ² gate.
    invalid : numpy.ndarray, shape (N, M)
        Skipped: NaN or negative range, NaN bearing, or an unknown landmark identity.
    nis : numpy.ndarray, shape (N, M)
        Normalised innovation squared (NaN where not computed).
    """

    accepted: np.ndarray
    gated: np.ndarray
    invalid: np.ndarray
    nis: np.ndarray


def _inv2(s: np.ndarray) -> np.ndarray:
    """Inverses of 2×2 matrices ``(..., 2, 2)``."""
    det = s[..., 0, 0] * s[..., 1, 1] - s[..., 0, 1] * s[..., 1, 0]
    out = np.empty_like(s)
    out[..., 0, 0] = s[..., 1, 1]
    out[..., 1, 1] = s[..., 0, 0]
    out[..., 0, 1] = -s[..., 0, 1]
    out[..., 1, 0] = -s[..., 1, 0]
    return out / det[..., None, None]


@dataclass(frozen=True)
class KalmanFilter:
    """Parameters shared by :class:`~wheelbase.localization.EKF` and
    :class:`~wheelbase.localization.UKF` (module docstring).

    Parameters
    ----------
    landmarks : array_like, shape (L, 2)
        Known landmark positions [m]; identity ℓ is row ℓ.
    motion : VelocityMotion
        Motion model and its noise.
    range_std : float
        Standard deviation of a range measurement [m], > 0 (at zero range when
        ``range_std_per_m`` > 0).
    bearing_std : float
        Standard deviation of a bearing measurement [rad], > 0.
    gate_probability : float
        Probability mass of the χ² gate, in (0, 1]; 1 accepts everything.
    range_std_per_m : float
        Growth of the range's standard deviation with the range [m/m], >= 0: σ_r = range_std +
        range_std_per_m·r̂, r̂ the range predicted from the mean (a camera that ranges by the
        landmark's size in the image errs in proportion to the range).
    huber_k : float
        Huber weighting, > 0 (infinite: off): a measurement that passes the gate with a
        Mahalanobis distance √NIS above ``huber_k`` counts with the weight huber_k/√NIS (its R
        divided by it), which bounds the pull of heavy-tailed errors.
    """

    landmarks: np.ndarray
    motion: VelocityMotion = field(default_factory=VelocityMotion)
    range_std: float = 0.1
    bearing_std: float = 0.02
    gate_probability: float = 0.99
    range_std_per_m: float = 0.0
    huber_k: float = math.inf

    name = "Kalman filter"

    def __post_init__(self) -> None:
        landmarks = as_float_array("landmarks", self.landmarks, 2, min_ndim=2, max_ndim=2)
        landmarks.setflags(write=False)
        object.__setattr__(self, "landmarks", landmarks)
        if not isinstance(self.motion, VelocityMotion):
            raise ConfigError(f"motion must be a VelocityMotion (got {type(self.motion).__name__})")
        for name, unit in (("range_std", "m"), ("bearing_std", "rad")):
            std = positive(name, getattr(self, name), unit)
            if not 0.0 < std * std < math.inf:  # R holds the variance
                raise ConfigError(f"{name} must be in [1e-150, 1e150] {unit} (got {std:g})")
            object.__setattr__(self, name, std)
        object.__setattr__(
            self, "range_std_per_m", nonnegative("range_std_per_m", self.range_std_per_m, "m/m")
        )
        if not self.huber_k > 0.0:  # also rejects NaN
            raise ConfigError(f"huber_k must be > 0 (infinite: off) (got {self.huber_k!r})")
        chi2_gate(self.gate_probability)

    @property
    def gate(self) -> float:
        """NIS threshold of the gate (:func:`chi2_gate`)."""
        return chi2_gate(self.gate_probability)

    @property
    def measurement_covariance(self) -> np.ndarray:
        """R = diag(range_std², bearing_std²) (at zero range)."""
        return np.diag([self.range_std**2, self.bearing_std**2])

    def _noise(self, mean: np.ndarray, landmarks: np.ndarray) -> np.ndarray:
        """R of each measurement, ``(N, 2, 2)`` (or ``(2, 2)`` when it does not vary)."""
        if self.range_std_per_m == 0.0:
            return self.measurement_covariance
        r_hat = np.hypot(landmarks[:, 0] - mean[:, 0], landmarks[:, 1] - mean[:, 1])
        r_mat = np.zeros((mean.shape[0], 2, 2))
        r_mat[:, 0, 0] = (self.range_std + self.range_std_per_m * r_hat) ** 2
        r_mat[:, 1, 1] = self.bearing_std**2
        return r_mat

    # ------------------------------------------------------------------ the two steps
    def predict(
        self, mean: ArrayLike, cov: ArrayLike, control: ArrayLike, dt: float
    ) -> tuple[np.ndarray, np.ndarray]:
        """Propagate the belief over one step of the velocity motion model.

        Parameters
        ----------
        mean : array_like, shape (3,) or (N, 3)
            Pose means (x [m], y [m], θ [rad]).
        cov : array_like, shape (3, 3) or (N, 3, 3)
            Pose covariances.
        control : array_like, shape (2,) or (N, 2)
            (v [m/s], ω [rad/s]) held over the step; broadcast against the robots.
        dt : float
            Step [s], > 0.

        Returns
        -------
        mean, cov : numpy.ndarray
            The predicted belief, shaped as given.
        """
        mean_b, cov_b, single = self._belief(mean, cov)
        control = as_float_array("control", control, 2, min_ndim=1, max_ndim=2)
        control = np.broadcast_to(control, (*mean_b.shape[:-1], 2))
        dt = positive("dt", dt, "s")
        with np.errstate(all="ignore"):  # an overflow shows as a non-finite belief: checked
            new_mean, new_cov = self._predict(mean_b, cov_b, control, dt)
        self._check(new_mean, new_cov, "prediction")
        return (new_mean[0], new_cov[0]) if single else (new_mean, new_cov)

    def predict_sequence(
        self, mean: ArrayLike, cov: ArrayLike, controls: ArrayLike, dts: ArrayLike
    ) -> tuple[np.ndarray, np.ndarray]:
        """Several predictions in a row (a log of odometry between two measurements).

        The same as calling :meth:`predict` once per step, with the inputs checked once.

        Parameters
        ----------
        mean : array_like, shape (3,) or (N, 3)
            Pose means at the start.
        cov : array_like, shape (3, 3) or (N, 3, 3)
            Their covariances.
        controls : array_like, shape (T, 2) or (T, N, 2)
            (v [m/s], ω [rad/s]) of each step.
        dts : array_like, shape (T,)
            Step lengths [s], > 0.

        Returns
        -------
        means, covs : numpy.ndarray
            The belief after each step: shape (T, 3) and (T, 3, 3), or (T, N, 3) and
            (T, N, 3, 3).
        """
        mean_b, cov_b, single = self._belief(mean, cov)
        dts = as_float_array("dts", dts, min_ndim=1, max_ndim=1)
        if np.any(dts <= 0.0):
            raise ConfigError(f"dts must be > 0 s (got {dts.min():g})")
        controls = as_float_array("controls", controls, 2, min_ndim=2, max_ndim=3)
        if controls.shape[0] != dts.size:
            raise InputError(
                f"controls must have one row per step: {dts.size} (got {controls.shape[0]})"
            )
        controls = np.broadcast_to(
            controls.reshape(dts.size, -1, 2), (dts.size, *mean_b.shape[:-1], 2)
        )
        with np.errstate(all="ignore"):  # an overflow shows as a non-finite belief: checked
            means, covs = self._predict_sequence(mean_b, cov_b, controls, dts)
        self._check(means[-1], covs[-1], "prediction")
        return (means[:, 0], covs[:, 0]) if single else (means, covs)

    def _predict_sequence(
        self, mean: np.ndarray, cov: np.ndarray, controls: np.ndarray, dts: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """Beliefs after each step, ``(T, N, 3)`` and ``(T, N, 3, 3)``; inputs checked."""
        means = np.empty((dts.size, *mean.shape))
        covs = np.empty((dts.size, *cov.shape))
        for k in range(dts.size):
            mean, cov = self._predict(mean, cov, controls[k], float(dts[k]))
            means[k], covs[k] = mean, cov
        return means, covs

    def update(
        self,
        mean: ArrayLike,
        cov: ArrayLike,
        ids: ArrayLike,
        z: ArrayLike,
        noise_scale: ArrayLike | None = None,
    ) -> tuple[np.ndarray, np.ndarray, UpdateInfo]:
        """Correct the belief with range–bearing measurements of known landmarks.

        Parameters
        ----------
        mean : array_like, shape (3,) or (N, 3)
            Pose means.
        cov : array_like, shape (3, 3) or (N, 3, 3)
            Pose covariances.
        ids : array_like of int, shape (M,) or (N, M)
            Landmark identity of each measurement; −1 marks an empty slot.
        z : array_like, shape (M, 2) or (N, M, 2)
            (range [m], bearing [rad]) of each measurement.
        noise_scale : array_like, shape (M,) or (N, M), optional
            Factor > 0 on each measurement's noise covariance R (default 1): how much less
            a measurement is worth, e.g. one whose error is correlated with earlier ones
            (:func:`wheelbase.localization.mrclam.correlated_inflation`).

        Returns
        -------
        mean, cov : numpy.ndarray
            The corrected belief, shaped as given.
        info : UpdateInfo
            Accepted, gated and invalid slots and their NIS, shape (N, M) (or (M,)).
        """
        mean_b, cov_b, single = self._belief(mean, cov)
        ids = np.asarray(ids)
        if ids.size and not np.issubdtype(ids.dtype, np.integer):
            raise InputError(f"ids must be integers (got dtype {ids.dtype})")
        ids = ids.astype(np.int64).reshape((1, -1) if single else ids.shape)
        try:
            z = np.asarray(z, dtype=np.float64).reshape((*ids.shape, 2))
        except (TypeError, ValueError):
            raise InputError(
                f"z must hold one (range, bearing) pair per id: shape {(*ids.shape, 2)} "
                f"(got {np.shape(z)})"
            ) from None
        if ids.ndim != 2 or ids.shape[0] != mean_b.shape[0]:
            raise InputError(
                f"ids must have shape (N, M) with N = {mean_b.shape[0]} robots (got {ids.shape})"
            )
        shape = ids.shape
        scale = np.ones(shape)
        if noise_scale is not None:
            try:
                scale = np.broadcast_to(np.asarray(noise_scale, dtype=np.float64), shape)
            except (TypeError, ValueError):
                raise InputError(
                    f"noise_scale must have the shape of ids {shape} (got {np.shape(noise_scale)})"
                ) from None
            if not np.all(np.isfinite(scale) & (scale > 0.0)):
                raise InputError("noise_scale must be finite factors > 0")
        accepted = np.zeros(shape, bool)
        gated = np.zeros(shape, bool)
        nis_all = np.full(shape, np.nan)
        present = ids >= 0
        usable = (
            present
            & (ids < self.landmarks.shape[0])
            & np.isfinite(z).all(-1)
            & (np.nan_to_num(z[..., 0], nan=-1.0) >= 0.0)
        )
        mean_b, cov_b = mean_b.copy(), cov_b.copy()
        gate = self.gate
        for m in range(shape[1]):
            rows = np.flatnonzero(usable[:, m])
            if rows.size == 0:
                continue
            with np.errstate(all="ignore"):  # an overflow shows as a non-finite belief
                nis, ok = self._correct(
                    mean_b, cov_b, rows, ids[rows, m], z[rows, m], gate, scale[rows, m]
                )
            nis_all[rows, m] = nis
            accepted[rows[ok], m] = True
            gated[rows[~ok], m] = True
        self._check(mean_b, cov_b, "update")
        invalid = present & ~usable
        info = UpdateInfo(accepted, gated, invalid, nis_all)
        if single:
            info = UpdateInfo(*(a[0] for a in (accepted, gated, invalid, nis_all)))
            return mean_b[0], cov_b[0], info
        return mean_b, cov_b, info

    def _correct(
        self,
        mean: np.ndarray,
        cov: np.ndarray,
        rows: np.ndarray,
        ids: np.ndarray,
        z: np.ndarray,
        gate: float,
        scale: np.ndarray,
    ) -> tuple[np.ndarray, np.ndarray]:
        """Gate and apply one measurement per robot of ``rows`` to ``mean``/``cov`` in place,
        its R times ``scale``; return their NIS and which passed the gate."""
        mu, p = mean[rows], cov[rows]
        marks = self.landmarks[ids]
        r_mat = self._noise(mu, marks) * scale[:, None, None]
        z_hat, h, s = self._moments(mu, p, marks, r_mat)
        nu = z - z_hat
        nu[:, 1] = wrap_angle(nu[:, 1])
        s_inv = _inv2(s)
        nis = np.einsum("ni,nij,nj->n", nu, s_inv, nu)
        ok = nis <= gate
        heavy = ok & (nis > self.huber_k**2)
        if heavy.any():  # Huber weight w = k/√NIS: the measurement's R is divided by w
            w = self.huber_k / np.sqrt(nis[heavy])
            r_heavy = np.broadcast_to(r_mat, (rows.size, 2, 2))[heavy]
            s[heavy] = s[heavy] + (1.0 / w - 1.0)[:, None, None] * r_heavy
            s_inv[heavy] = _inv2(s[heavy])
        if ok.any():
            rows, mu, p, h, s, s_inv, nu = (a[ok] for a in (rows, mu, p, h, s, s_inv, nu))
            ht = np.swapaxes(h, -1, -2)
            k = p @ ht @ s_inv
            new_mean = mu + np.einsum("nij,nj->ni", k, nu)
            new_mean[:, 2] = wrap_angle(new_mean[:, 2])
            ikh = np.eye(3) - k @ h
            r_eff = s - h @ p @ ht  # R for the EKF; R + linearisation error for the UKF
            new_cov = ikh @ p @ np.swapaxes(ikh, -1, -2) + k @ r_eff @ np.swapaxes(k, -1, -2)
            mean[rows] = new_mean
            cov[rows] = 0.5 * (new_cov + np.swapaxes(new_cov, -1, -2))
        return nis, ok

    # ------------------------------------------------------------------ hooks and checks
    def _predict(self, mean, cov, control, dt):  # pragma: no cover - abstract
        raise NotImplementedError

    def _moments(self, mean, cov, landmarks, r_mat):  # pragma: no cover - abstract
        raise NotImplementedError

    def _belief(self, mean: ArrayLike, cov: ArrayLike) -> tuple[np.ndarray, np.ndarray, bool]:
        mean = as_float_array("mean", mean, 3, min_ndim=1, max_ndim=2)
        cov = as_float_array("cov", cov, 3, min_ndim=2, max_ndim=3)
        single = mean.ndim == 1
        mean_b = mean.reshape(-1, 3)
        cov_b = cov.reshape(-1, 3, 3)
        if cov_b.shape[0] != mean_b.shape[0]:
            raise InputError(
                f"cov must have shape {(*mean.shape[:-1], 3, 3)} to match mean (got {cov.shape})"
            )
        robot = self._not_psd(cov_b)
        if robot is not None:
            raise InputError(
                f"cov of robot {robot} is not positive semi-definite (or not symmetric)"
            )
        return mean_b, cov_b, single

    @staticmethod
    def _not_psd(cov: np.ndarray) -> int | None:
        """Index of the first covariance that is not symmetric positive semi-definite (an
        eigenvalue below −1e-9 of the largest counts as negative: rounding does not)."""
        sym = np.abs(cov - np.swapaxes(cov, -1, -2)).max((-1, -2)) <= 1e-9 * np.maximum(
            np.abs(cov).max((-1, -2)), 1e-300
        )
        eig = np.linalg.eigvalsh(cov)
        scale = np.maximum(np.abs(eig).max(-1), 1e-300)
        bad = np.flatnonzero(~sym | (eig[:, 0] < -1e-9 * scale))
        return int(bad[0]) if bad.size else None

    def _check(self, mean: np.ndarray, cov: np.ndarray, stage: str) -> None:
        """Raise unless every belief is finite with a positive semi-definite covariance."""
        finite = np.isfinite(mean).all(-1) & np.isfinite(cov).all((-1, -2))
        robot = int(np.flatnonzero(~finite)[0]) if not finite.all() else self._not_psd(cov)
        if robot is not None:
            raise EstimationError(
                f"{self.name}: the covariance of robot {robot} is not finite and positive "
                f"semi-definite after the {stage}; check the initial covariance, range_std = "
                f"{self.range_std:g} m, bearing_std = {self.bearing_std:g} rad and the motion "
                "noise"
            )
