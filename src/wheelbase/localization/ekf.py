"""Extended Kalman filter localisation with known landmarks (Thrun, Burgard and Fox, Table 7.2).

Prediction linearises the velocity motion model of :mod:`wheelbase.localization.motion` about
the mean: μ' = g(μ, u), P' = G P Gᵀ + V M Vᵀ with G = ∂g/∂x, V = ∂g/∂(Δs, Δθ) and M the
covariance of the increments. The correction linearises the range–bearing model
ẑ = (‖m − p‖, atan2(m_y − y, m_x − x) − θ) with

    H = [[−dx/r, −dy/r, 0], [dy/r², −dx/r², −1]],   (dx, dy) = m − p,

then gates and applies the Joseph form (:mod:`wheelbase.localization.kalman`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np

from wheelbase.localization.kalman import KalmanFilter
from wheelbase.localization.motion import arc_move
from wheelbase.odometry.dead_reckoning import integrate_increments
from wheelbase.sensors.landmarks import range_bearing

__all__ = ["EKF"]


@dataclass(frozen=True)
class EKF(KalmanFilter):
    """Extended Kalman filter for a batch of robots (parameters: :class:`KalmanFilter`).

    Examples
    --------
    >>> ekf = EKF(landmarks=[[2.0, 0.0]], range_std=0.1, bearing_std=0.05)
    >>> mean, cov = ekf.predict([0.0, 0.0, 0.0], np.eye(3) * 0.01, [1.0, 0.0], 0.1)
    >>> mean.round(3).tolist()
    [0.1, 0.0, 0.0]
    >>> mean, cov, info = ekf.update(mean, cov, [0], [[1.85, 0.0]])
    >>> bool(info.accepted[0]), bool(mean[0] > 0.1)
    (True, True)
    """

    name = "EKF"

    def _predict(self, mean, cov, control, dt):
        inc = control * dt
        g, v = self.motion.jacobians(mean, inc)
        m = self.motion.covariance(control, dt)
        new_mean = arc_move(mean, inc)
        gt = np.swapaxes(g, -1, -2)
        new_cov = g @ cov @ gt + v @ m @ np.swapaxes(v, -1, -2)
        return new_mean, 0.5 * (new_cov + np.swapaxes(new_cov, -1, -2))

    def _predict_sequence(self, mean, cov, controls, dts):
        """Without measurements the EKF's mean is dead reckoning: the means and Jacobians of
        all steps are computed at once and only P ← G P Gᵀ + V M Vᵀ runs step by step
        (compiled). The same as the loop of :meth:`KalmanFilter._predict_sequence`."""
        inc = controls * dts[:, None, None]
        poses = integrate_increments(mean, inc[..., 0], inc[..., 1])  # (T + 1, N, 3)
        g, v = self.motion.jacobians(poses[:-1], inc)
        m = self.motion.increment_covariance(inc, dts[:, None])
        q = v @ m @ np.swapaxes(v, -1, -2)
        covs = np.empty((dts.size, *cov.shape))
        _propagate(np.ascontiguousarray(g), np.ascontiguousarray(q), cov, covs)
        return poses[1:], covs

    def _moments(self, mean, cov, landmarks, r_mat):
        z_hat = range_bearing(mean, landmarks)
        dx = landmarks[:, 0] - mean[:, 0]
        dy = landmarks[:, 1] - mean[:, 1]
        q = np.maximum(dx * dx + dy * dy, 1e-12)
        r = np.sqrt(q)
        h = np.zeros((mean.shape[0], 2, 3))
        h[:, 0, 0] = -dx / r
        h[:, 0, 1] = -dy / r
        h[:, 1, 0] = dy / q
        h[:, 1, 1] = -dx / q
        h[:, 1, 2] = -1.0
        s = h @ cov @ np.swapaxes(h, -1, -2) + r_mat
        return z_hat, h, s


@numba.njit(cache=True)
def _propagate(g, q, p0, out):
    """out[k] = G_k out[k−1] G_kᵀ + Q_k from out[−1] = P0, for every robot (symmetrised)."""
    steps, robots = g.shape[0], g.shape[1]
    for n in range(robots):
        p = p0[n].copy()
        for k in range(steps):
            gk = g[k, n]
            gp = gk @ p
            p = gp @ gk.T + q[k, n]
            p = 0.5 * (p + p.T)
            out[k, n] = p
