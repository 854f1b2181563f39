"""Unscented Kalman filter localisation with known landmarks (Thrun, Burgard and Fox, Table 7.4).

Sigma points of the scaled unscented transform (Julier 2002; Wan and van der Merwe 2000):
2n + 1 points μ and μ ± √(n + λ)·Lᵢ (columns of a square root L of the covariance),
λ = α²(n + κ) − n, mean weights W₀ = λ/(n + λ), Wᵢ = 1/(2(n + λ)) and covariance weights
W₀ᶜ = W₀ + 1 − α² + β. Prediction augments the pose with the two increment errors (n = 5), as
the book does, so the motion noise goes through the nonlinear motion itself; the correction
uses the pose alone (n = 3) with additive measurement noise. Angles are averaged as wrapped
differences from the first sigma point, so the mean never jumps across ±π.

The correction's gain and Joseph form use H = P_xzᵀ P⁻¹ (:mod:`wheelbase.localization.kalman`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from wheelbase._validate import nonnegative, positive
from wheelbase.errors import ConfigError
from wheelbase.geometry import wrap_angle
from wheelbase.localization.kalman import KalmanFilter
from wheelbase.localization.motion import arc_move
from wheelbase.sensors.landmarks import range_bearing

__all__ = ["UKF", "sigma_weights"]


def sigma_weights(
    n: int, alpha: float, beta: float, kappa: float
) -> tuple[float, np.ndarray, np.ndarray]:
    """Spread and weights of the scaled unscented transform.

    Parameters
    ----------
    n : int
        State dimension.
    alpha : float
        Spread of the points, > 0.
    beta : float
        Prior knowledge of the distribution (2 is optimal for a Gaussian).
    kappa : float
        Secondary scaling, with n + κ > 0.

    Returns
    -------
    spread : float
        √(n + λ).
    wm, wc : numpy.ndarray, shape (2n + 1,)
        Mean and covariance weights.
    """
    lam = alpha * alpha * (n + kappa) - n
    wm = np.full(2 * n + 1, 0.5 / (n + lam))
    wc = wm.copy()
    wm[0] = lam / (n + lam)
    wc[0] = wm[0] + 1.0 - alpha * alpha + beta
    return float(np.sqrt(n + lam)), wm, wc


def _sqrt_psd(p: np.ndarray) -> np.ndarray:
    """Lower square roots of positive semi-definite matrices ``(..., n, n)``: Cholesky, or
    through the eigenvalues (negatives clipped) where Cholesky fails (a singular covariance)."""
    try:
        return np.linalg.cholesky(p)
    except np.linalg.LinAlgError:
        w, v = np.linalg.eigh(p)
        return v * np.sqrt(np.maximum(w, 0.0))[..., None, :]


def _mean_and_deviation(
    points: np.ndarray, wm: np.ndarray, angle: int
) -> tuple[np.ndarray, np.ndarray]:
    """Weighted mean of sigma points ``(N, K, d)`` and their deviations from it; component
    ``angle`` is averaged as wrapped differences from point 0."""
    ref = points[:, :1, angle]
    rel = points.copy()
    rel[..., angle] = wrap_angle(points[..., angle] - ref)
    mean = np.einsum("k,nkd->nd", wm, rel)
    dev = rel - mean[:, None, :]
    mean[:, angle] = wrap_angle(mean[:, angle] + ref[:, 0])
    return mean, dev


@dataclass(frozen=True)
class UKF(KalmanFilter):
    """Unscented Kalman filter for a batch of robots (module docstring).

    Parameters
    ----------
    landmarks, motion, range_std, bearing_std, gate_probability
        As for :class:`~wheelbase.localization.kalman.KalmanFilter`.
    alpha : float
        Spread of the sigma points, > 0 (default 1: the points sit at √n standard deviations).
    beta : float
        Weight of the centre point in the covariance, >= 0 (2 for Gaussians).
    kappa : float
        Secondary scaling; n + κ > 0 for n = 3 and 5.

    Examples
    --------
    >>> ukf = UKF(landmarks=[[2.0, 0.0]], range_std=0.1, bearing_std=0.05)
    >>> mean, cov = ukf.predict([0.0, 0.0, 0.0], np.eye(3) * 0.01, [1.0, 0.0], 0.1)
    >>> mean.round(3).tolist()
    [0.1, 0.0, 0.0]
    """

    alpha: float = 1.0
    beta: float = 2.0
    kappa: float = 0.0

    name = "UKF"

    def __post_init__(self) -> None:
        super().__post_init__()
        positive("alpha", self.alpha)
        nonnegative("beta", self.beta)
        if not np.isfinite(self.kappa) or 3 + self.kappa <= 0:
            raise ConfigError(f"kappa must be finite with 3 + kappa > 0 (got {self.kappa!r})")

    def _points(self, mean: np.ndarray, root: np.ndarray, spread: float) -> np.ndarray:
        offsets = spread * np.swapaxes(root, -1, -2)  # rows: the columns of the root
        return np.concatenate(
            [mean[:, None, :], mean[:, None, :] + offsets, mean[:, None, :] - offsets], axis=1
        )

    def _predict(self, mean, cov, control, dt):
        n_robots = mean.shape[0]
        spread, wm, wc = sigma_weights(5, self.alpha, self.beta, self.kappa)
        m = self.motion.covariance(control, dt)
        root = np.zeros((n_robots, 5, 5))
        root[:, :3, :3] = _sqrt_psd(cov)
        root[:, 3, 3] = np.sqrt(m[:, 0, 0])
        root[:, 4, 4] = np.sqrt(m[:, 1, 1])
        centre = np.concatenate([mean, np.zeros((n_robots, 2))], -1)
        points = self._points(centre, root, spread)  # (N, 11, 5)
        inc = control[:, None, :] * dt + points[..., 3:]
        moved = arc_move(points[..., :3], inc)
        new_mean, dev = _mean_and_deviation(moved, wm, 2)
        new_cov = np.einsum("k,nki,nkj->nij", wc, dev, dev)
        return new_mean, 0.5 * (new_cov + np.swapaxes(new_cov, -1, -2))

    def _moments(self, mean, cov, landmarks, r_mat):
        spread, wm, wc = sigma_weights(3, self.alpha, self.beta, self.kappa)
        points = self._points(mean, _sqrt_psd(cov), spread)  # (N, 7, 3)
        z_points = range_bearing(points, landmarks[:, None, :])  # (N, 7, 2)
        z_hat, dz = _mean_and_deviation(z_points, wm, 1)
        dx = points - mean[:, None, :]
        dx[..., 2] = wrap_angle(dx[..., 2])
        s = np.einsum("k,nki,nkj->nij", wc, dz, dz) + r_mat
        pxz = np.einsum("k,nki,nkj->nij", wc, dx, dz)
        # H = P_xzᵀ P⁻¹, solved rather than inverted (P is the prior, positive definite here)
        h = np.swapaxes(_solve(cov, pxz), -1, -2)
        return z_hat, h, s


def _solve(p: np.ndarray, b: np.ndarray) -> np.ndarray:
    """P⁻¹B for a batch, through the pseudo-inverse where P is singular."""
    try:
        return np.linalg.solve(p, b)
    except np.linalg.LinAlgError:
        return np.linalg.pinv(p) @ b
