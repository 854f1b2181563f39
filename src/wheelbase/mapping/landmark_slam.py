"""Landmark SLAM on range–bearing data: EKF-SLAM with known correspondences, then smoothing.

The data are those of :func:`wheelbase.localization.mrclam.localize` (UTIAS MRCLAM: velocity
odometry, camera sightings of barcoded landmarks, Vicon ground truth), prepared the same way
(odometry resampled every 10 ms with its lags, camera images retrodicted by the camera lag,
one parameter set :data:`~wheelbase.localization.mrclam.MRCLAM_PARAMETERS`), but the
landmark positions are **unknown**: the filter estimates them. Their identities (the barcodes)
are known.

**EKF-SLAM** (Thrun, Burgard and Fox, *Probabilistic Robotics*, 2005, §10.2, Table 10.1) with
the state (x, y, θ, κ, m₁, …, m_L): the pose, the camera's range scale κ (the camera measures
depth along its axis, z_d = κ·r·cos β, see :mod:`wheelbase.localization.mrclam`; κ's prior
1 ± ``range_scale_std``) and the landmarks seen so far, each appended at its first sighting
with the covariance of the inverse measurement (the initialisation of Table 10.1, line 9, with
the cross-covariances that keep the filter consistent). A sighting at image pose X_c = X ⊕ c
(c: the retrodiction over the camera lag, a constant from the odometry) of landmark m gives
q = R(θ_c)ᵀ(m − t_c) and the prediction (κ·q_x, atan2(q_y, q_x)): q_x is the depth. The
noise is σ_d = range_std + range_std_per_m·r, σ_β = bearing_std; updates are χ²-gated at
``gate_probability`` and Huber-weighted beyond ``huber_k``, and each sighting's R is multiplied
by :func:`~wheelbase.localization.mrclam.correlated_inflation` of the earlier sightings of its
landmark (``correlation``, ``correlation_time_s``), as the localisation filters. Without that
discount the filter took the dozens of sightings of one landmark from one viewpoint (the
stationary start, the long looks at the first landmarks) as independent, grew sure of a map
turned 3.3° against the survey, and read 0.33 m robot and 0.40 m landmark RMSE on robot 1 of
data set 6 (0.18 m and 0.23 m with it).

**The gauge.** The map's frame is the ground truth's: the first pose is the Vicon pose at the
first odometry sample (as :func:`~wheelbase.localization.mrclam.localize` starts from), held
exactly. That pose is not noisy (Vicon's heading scatters by 0.01° while the robot stands
still before the recording), and the landmarks are never aligned to the survey. Everything
else in the problem (odometry between poses, sightings) is unchanged by a rigid motion of the
whole solution, so the map's frame is the anchor moved by the odometry to the first sighting,
with that stretch's odometry error: on data set 6, 0.07 m and +0.6° on robot 1 (2.1 s, a
0.68 rad turn), −0.7° (2), +1.3° (3), +5.2° (4: 8.9 s, 1.5 rad turned) and −6.9° (5: short
turn commands that the robot follows by 60 %), which no estimator can take back. The rest
of a map's turn against the survey comes from how it is tied together: the 15 landmarks
stand in five tight groups along one 9 m line, each group seen from afar as nearly one point,
so the groups' relative orientation is carried across the robot's turns by the odometry's
heading.

**The heading noise.** The filters' heading variance per radian turned (``heading_per_rad``
0.12 rad²/rad) is a filter's inflation: a heading held too sure after a turn cannot be
corrected later. In the smoothing every pose is re-estimated from all sightings, and that
inflation let the relative heading across a half-turn float by ±35°, so that the groups of
landmarks on either side of a turn were placed by the translations alone (robot 1's map
turned 2.1°, robot 3's 5.5°). The smoothing weighs the odometry by its measured heading
errors instead, ``smoothing_heading_per_rad`` 0.01 rad²/rad (the mean squared error of the
commanded turn per radian turned, 0.007–0.010 on each of robots 1–5 of data set 6, over 1 s
and 3 s windows; the EKF keeps the filters' value: with 0.01 it grows sure of a wrong
heading, robot 1 0.42 m landmark RMSE).

**Outliers.** The EKF's χ² gate rejects the sightings that disagree with its belief (0, 8,
39, 55 and 5 on robots 1–5 of data set 6, among them the gross misreads: a barcode read
150–170° away from its landmark's bearing, 4 on robot 3 and 5 on robot 5), and the smoothing
keeps the filter's decisions: a sighting the gate rejected is left out of the smoothing
problem too, where under the Huber loss alone they still shaped the minimum that the
Gauss–Newton iterations reach from the EKF's estimates (robot 3: 0.43 m landmark RMSE with
them, 0.16 m without; cutting the loss off at 10σ, which drops the gross misreads only, left
0.43 m; robot 4, whose EKF rejects inliers too, loses 0.04 m).

**Smoothing** (the full SLAM problem, Thrun et al. §11; Dellaert and Kaess, "Square Root SAM",
IJRR 2006): the poses at every sighting time, the landmarks and κ are estimated together by
nonlinear least squares over odometry factors between consecutive poses (the odometry
increments with the motion model's covariance, accumulated between the two times, with the
heading noise above) and the sighting factors above, robustified by the Huber loss, solved by
Gauss–Newton with Levenberg–Marquardt damping on the sparse normal equations, started from the
EKF's estimates. The sightings are taken as independent there (spread over a batch solution,
the filter's discount of the later ones of a run would weigh the first one most). The gauge is
a prior on the pose of the first sighting: the anchor moved by the odometry, with the motion
model's covariance over that stretch expressed in that pose's frame
(``_relative_information``, the odometry edges' too). Poses between sightings follow the
odometry from the previous one.

On data set 6 (landmark RMSE against the survey, robot RMSE against Vicon), robots 1–5:
smoothing 0.109, 0.074, 0.159, 0.518, 0.580 m landmarks and 0.118, 0.147, 0.150, 0.419,
0.370 m robot (before the heading noise and the outlier rule: 0.172, 0.062, 0.592, 0.524,
0.746 m and 0.132, 0.145, 0.334, 0.417, 0.439 m); EKF 0.235, 0.327, 0.780, 2.271, 0.241 m
landmarks. After a rigid fit to the survey (a diagnosis, not the metric) the smoothing's maps
are within 0.024, 0.059, 0.072, 0.226, 0.059 m: what is left is mostly the frame's turn
(−1.3°, −0.3°, +0.7°, −6.6°, +7.3°), on robots 4 and 5 that of the odometry before the first
sighting.
"""

from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass, field
from pathlib import Path

import numba
import numpy as np

from wheelbase.errors import ConfigError
from wheelbase.geometry import compose, inverse_pose, relative_pose, wrap_angle

__all__ = [
    "LANDMARK_SLAM_METHODS",
    "LANDMARK_SLAM_PARAMETERS",
    "LandmarkSlamResult",
    "landmark_slam",
]

LANDMARK_SLAM_METHODS: tuple[str, ...] = ("ekf", "smoothing")
"""``ekf``: EKF-SLAM alone; ``smoothing``: EKF-SLAM, then the smoothing solution."""

LANDMARK_SLAM_PARAMETERS: dict[str, float] = {
    # the smoothing's odometry heading variance per radian turned [rad²/rad]: what the
    # odometry's heading errors measure (bias included), not the filters' inflated
    # heading_per_rad (module docstring, "The heading noise"). Over 1 s and 3 s windows of
    # data set 6, the mean of (true − commanded turn)² per radian turned is 0.0085/0.0098
    # (robot 1), 0.0085/0.0087 (2), 0.0072/0.0095 (3), 0.0094/0.0100 (4), 0.0092/0.0082 (5)
    "smoothing_heading_per_rad": 0.01,
}
"""Landmark SLAM's own parameters (beside those of
:data:`~wheelbase.localization.mrclam.MRCLAM_PARAMETERS`)."""


@dataclass(frozen=True)
class LandmarkSlamResult:
    """A landmark SLAM run over one MRCLAM robot.

    Attributes
    ----------
    method : str
        ``ekf`` or ``smoothing``.
    t : numpy.ndarray, shape (T,)
        Times [s] since the start (the 10 ms grid).
    estimate : numpy.ndarray, shape (T, 3)
        Pose estimate (the EKF's is causal: the belief before that instant's sightings).
    truth : numpy.ndarray, shape (T, 3)
        Vicon ground truth.
    dead_reckoning : numpy.ndarray, shape (T, 3)
        Odometry alone.
    subjects : numpy.ndarray, shape (L,)
        Subject number of each landmark row.
    landmarks : numpy.ndarray, shape (L, 2)
        Estimated positions [m] (NaN for a landmark never seen).
    landmark_cov : numpy.ndarray, shape (L, 2, 2)
        Their covariances (the EKF's; NaN when not seen).
    true_landmarks : numpy.ndarray, shape (L, 2)
        Surveyed positions (for evaluation only).
    range_scale : float
        The estimated camera scale κ.
    used, gated, unknown : int
        Sightings applied, rejected by the gate, and of barcodes that name no landmark.
    processing_time_s : float
        Wall time [s].
    parameters : dict
        The parameter set.
    """

    method: str
    t: np.ndarray
    estimate: np.ndarray
    truth: np.ndarray
    dead_reckoning: np.ndarray
    subjects: np.ndarray
    landmarks: np.ndarray
    landmark_cov: np.ndarray
    true_landmarks: np.ndarray
    range_scale: float
    used: int
    gated: int
    unknown: int
    processing_time_s: float
    parameters: dict = field(default_factory=dict, repr=False)

    def metrics(self) -> dict[str, float | int | str]:
        """``position_rmse_m``, ``landmark_rmse_m`` (over the landmarks seen),
        ``landmarks_seen``, ``heading_rmse_deg``, ``dead_reckoning_rmse_m``, counts, time."""
        err = np.hypot(*(self.estimate[:, :2] - self.truth[:, :2]).T)
        heading = wrap_angle(self.estimate[:, 2] - self.truth[:, 2])
        seen = np.isfinite(self.landmarks[:, 0])
        lm = np.hypot(*(self.landmarks[seen] - self.true_landmarks[seen]).T)
        drift = np.hypot(*(self.dead_reckoning[:, :2] - self.truth[:, :2]).T)
        return {
            "method": self.method,
            "position_rmse_m": float(np.sqrt(np.mean(err**2))),
            "position_max_m": float(err.max()),
            "heading_rmse_deg": float(np.degrees(np.sqrt(np.mean(heading**2)))),
            "landmark_rmse_m": float(np.sqrt(np.mean(lm**2))) if lm.size else math.nan,
            "landmark_max_m": float(lm.max()) if lm.size else math.nan,
            "landmarks_seen": int(seen.sum()),
            "dead_reckoning_rmse_m": float(np.sqrt(np.mean(drift**2))),
            "camera_range_scale": self.range_scale,
            "measurements_used": self.used,
            "measurements_gated": self.gated,
            "measurements_unknown": self.unknown,
            "duration_s": float(self.t[-1] - self.t[0]),
            "processing_time_s": self.processing_time_s,
        }


@numba.njit(cache=True)
def _accumulate(g, q):
    """G_tot = G_k⋯G_1 and Q_tot with Q ← G_k Q G_kᵀ + Q_k over a run of steps."""
    gt = np.eye(3)
    qt = np.zeros((3, 3))
    for k in range(g.shape[0]):
        gt = g[k] @ gt
        qt = g[k] @ qt @ g[k].T + q[k]
    return gt, 0.5 * (qt + qt.T)


def _steps(motion, pose, inc, dts):
    """Dead-reckon a run of increments; return the end pose, G_tot and Q_tot."""
    from wheelbase.odometry.dead_reckoning import integrate_increments

    poses = integrate_increments(pose, inc[:, 0], inc[:, 1])
    g, v = motion.jacobians(poses[:-1], inc)
    m = motion.increment_covariance(inc, dts)
    q = v @ m @ np.swapaxes(v, -1, -2)
    gt, qt = _accumulate(np.ascontiguousarray(g), np.ascontiguousarray(q))
    return poses, gt, qt


def _observe(pose, c, kappa, m):
    """Prediction (κ q_x, atan2(q_y, q_x)) of landmark m from image pose X ⊕ c, and its
    Jacobians with respect to the pose (3), κ (1) and m (2)."""
    th = pose[2] + c[2]
    cs, sn = math.cos(pose[2]), math.sin(pose[2])
    tx = pose[0] + cs * c[0] - sn * c[1]
    ty = pose[1] + sn * c[0] + cs * c[1]
    ci, si = math.cos(th), math.sin(th)
    dx, dy = m[0] - tx, m[1] - ty
    qx, qy = ci * dx + si * dy, -si * dx + ci * dy
    r2 = max(qx * qx + qy * qy, 1e-12)
    # ∂q/∂m = Rᵀ; ∂q/∂t = −Rᵀ; ∂q/∂θ: from R(θ_c)ᵀ and from t_c's rotation of c
    dq_dm = np.array([[ci, si], [-si, ci]])
    dtx_dth, dty_dth = -sn * c[0] - cs * c[1], cs * c[0] - sn * c[1]
    dqx_dth = -si * dx + ci * dy - (ci * dtx_dth + si * dty_dth)
    dqy_dth = -ci * dx - si * dy - (-si * dtx_dth + ci * dty_dth)
    dq_dx = np.column_stack([-dq_dm, [dqx_dth, dqy_dth]])
    dz_dq = np.array([[kappa, 0.0], [-qy / r2, qx / r2]])
    h_pose = dz_dq @ dq_dx
    h_kappa = np.array([qx, 0.0])
    h_m = dz_dq @ dq_dm
    return np.array([kappa * qx, math.atan2(qy, qx)]), h_pose, h_kappa, h_m


def _inverse_observe(pose, c, kappa, z):
    """Landmark position from a sighting, and its Jacobians w.r.t. pose, κ and z."""
    th = pose[2] + c[2]
    cs, sn = math.cos(pose[2]), math.sin(pose[2])
    tx = pose[0] + cs * c[0] - sn * c[1]
    ty = pose[1] + sn * c[0] + cs * c[1]
    depth, beta = z
    qx, qy = depth / kappa, depth / kappa * math.tan(beta)
    ci, si = math.cos(th), math.sin(th)
    m = np.array([tx + ci * qx - si * qy, ty + si * qx + ci * qy])
    rot = np.array([[ci, -si], [si, ci]])
    dq_dz = np.array([[1.0 / kappa, 0.0],
                      [math.tan(beta) / kappa, depth / kappa / math.cos(beta) ** 2]])  # fmt: skip
    dq_dk = np.array([-qx / kappa, -qy / kappa])
    dtx_dth, dty_dth = -sn * c[0] - cs * c[1], cs * c[0] - sn * c[1]
    dm_dth = np.array([dtx_dth - si * qx - ci * qy, dty_dth + ci * qx - si * qy])
    j_pose = np.column_stack([np.eye(2), dm_dth])
    return m, j_pose, rot @ dq_dk, rot @ dq_dz


def _prepare(data_dir, robot, p):
    """The MRCLAM recording on the filters' grid, as :func:`localize` prepares it."""
    from wheelbase.datasets import mrclam as reader
    from wheelbase.localization import mrclam as lm
    from wheelbase.odometry.dead_reckoning import dead_reckon

    files = reader.find_mrclam_files(data_dir, robot)
    data = reader.load_mrclam(files["odometry"], files["groundtruth"])
    data = lm._resample_odometry(data, files["groundtruth"], p["odometry_lag_s"],
                                 p["speed_lag_s"])  # fmt: skip
    landmarks = reader.load_landmarks(files["landmarks"])
    meas = reader.load_measurements(files["measurement"], files["barcodes"], landmarks)
    inside = (meas.t >= data.t[0]) & (meas.t <= data.t[-1])
    meas = reader.MrclamMeasurements(meas.t[inside], meas.landmark[inside], meas.z[inside],
                                 meas.robot_sightings)  # fmt: skip
    odom = dead_reckon(data.t, data.v, data.omega, data.true_pose[0])
    moved = relative_pose(lm._odometry_at(data, odom, meas.t - p["camera_lag_s"]),
                          lm._odometry_at(data, odom, meas.t))  # fmt: skip
    return data, landmarks, dataclasses.replace(meas, moved=moved), odom


def landmark_slam(
    data_dir: str | Path,
    robot: int = 1,
    method: str = "smoothing",
    parameters: dict[str, float] | None = None,
) -> LandmarkSlamResult:
    """EKF-SLAM (and smoothing) over one MRCLAM robot's recording (module docstring).

    Parameters
    ----------
    data_dir : str or Path
        Folder of one data set.
    robot : int
        Robot number, 1–5.
    method : {"ekf", "smoothing"}
        EKF-SLAM alone, or followed by the smoothing solution.
    parameters : dict or None
        Overrides of :data:`~wheelbase.localization.mrclam.MRCLAM_PARAMETERS` and
        :data:`LANDMARK_SLAM_PARAMETERS`.

    Returns
    -------
    LandmarkSlamResult
    """
    from wheelbase._validate import check_choice
    from wheelbase.localization import mrclam as lm
    from wheelbase.localization.kalman import chi2_gate

    check_choice("method", method, LANDMARK_SLAM_METHODS)
    p = dict(lm.MRCLAM_PARAMETERS) | LANDMARK_SLAM_PARAMETERS
    unknown_keys = sorted(set(parameters or {}) - set(p))
    if unknown_keys:
        raise ConfigError(f"unknown parameter {unknown_keys[0]!r}; allowed: {', '.join(p)}")
    p.update(parameters or {})
    start = time.perf_counter()
    data, landmarks, meas, odom = _prepare(data_dir, robot, p)
    motion = lm._motion(p)
    n_lm = landmarks.xy.shape[0]
    size = 4 + 2 * n_lm
    mean = np.zeros(size)
    mean[:3], mean[3] = data.true_pose[0], 1.0
    cov = np.zeros((size, size))
    # the map's frame is the start pose (the ground truth at the first sample, as localize
    # starts from): known exactly, so that the estimates are comparable with the survey (the
    # gauge, module docstring)
    cov[:3, :3] = np.diag([1e-12, 1e-12, 1e-12])
    cov[3, 3] = p["range_scale_std"] ** 2
    seen = np.zeros(n_lm, bool)
    earlier = lm.Sightings.empty(n_lm, p["correlation_time_s"])
    gate = chi2_gate(p["gate_probability"], 2)
    t, n = data.t, data.t.size
    controls = np.column_stack([data.v, data.omega])
    est = np.empty((n, 3))
    est[0] = mean[:3]
    used = gated = unknown = 0
    k, t_now = 0, t[0]
    # the smoothing problem's records: (time index, pose at it) per sighting group
    group_times: list[float] = []
    sightings: list[tuple[int, int, np.ndarray, np.ndarray]] = []  # (group, landmark, z, c)

    def advance(mean, cov, j):
        """Predict from t_now through t_{k+1} .. t_j; fill est."""
        dts = np.diff(np.concatenate([[t_now], t[k + 1 : j + 1]]))
        inc = controls[k:j] * dts[:, None]
        poses, gt, qt = _steps(motion, mean[:3], inc, dts)
        est[k + 1 : j + 1] = poses[1:]
        return _apply_motion(mean, cov, poses[-1], gt, qt)

    groups = np.flatnonzero(np.concatenate([[True], np.diff(meas.t) > 0]))
    for first, last in zip(groups, np.append(groups[1:], meas.t.size), strict=True):
        tm = meas.t[first]
        j = int(np.searchsorted(t, tm, side="right")) - 1
        if j > k:
            mean, cov = advance(mean, cov, j)
            k, t_now = j, t[j]
        if tm > t_now:
            inc = controls[k][None] * (tm - t_now)
            poses, gt, qt = _steps(motion, mean[:3], inc, np.array([tm - t_now]))
            mean, cov = _apply_motion(mean, cov, poses[-1], gt, qt)
            t_now = tm
        c = inverse_pose(meas.moved[first])  # the image pose relative to the stamp's
        group = len(group_times)
        group_times.append(tm)
        # the camera's errors correlate from one sighting of a landmark to the next: the
        # filter discounts them as localize does (a first sighting is never discounted)
        inflation = lm.correlated_inflation(earlier.see(tm, meas.landmark[first:last]),
                                            p["correlation"])  # fmt: skip
        for row in range(first, last):
            lid, z = int(meas.landmark[row]), meas.z[row]
            if lid < 0 or not np.all(np.isfinite(z)) or z[0] <= 0 or math.cos(z[1]) < 0.1:
                unknown += 1
                continue
            at = 4 + 2 * lid
            if not seen[lid]:
                mean, cov = _initialise(mean, cov, at, c, z, p)
                seen[lid] = True
                used += 1
                sightings.append((group, lid, z.copy(), c))
                continue
            mean, cov, ok = _update(mean, cov, at, c, z, p, gate, inflation[row - first])
            used += int(ok)
            gated += int(not ok)
            # the smoothing keeps the filter's outlier decisions (module docstring)
            if ok:
                sightings.append((group, lid, z.copy(), c))
    if k < n - 1:
        mean, cov = advance(mean, cov, n - 1)
    lm_xy = np.where(seen[:, None], mean[4:].reshape(-1, 2), np.nan)
    lm_cov = np.array([cov[4 + 2 * i : 6 + 2 * i, 4 + 2 * i : 6 + 2 * i] for i in range(n_lm)])
    lm_cov[~seen] = np.nan
    kappa = float(mean[3])
    if method == "smoothing":
        # the smoothing weighs the odometry by its measured heading errors (module docstring)
        smooth_motion = dataclasses.replace(motion, heading_per_rad=p["smoothing_heading_per_rad"])
        est, lm_xy, kappa = _smooth(data, odom, smooth_motion, est, lm_xy, kappa,
                                    np.array(group_times), sightings, seen, p)  # fmt: skip
    return LandmarkSlamResult(
        method=method,
        t=t - t[0],
        estimate=est,
        truth=data.true_pose,
        dead_reckoning=odom,
        subjects=landmarks.subjects,
        landmarks=lm_xy,
        landmark_cov=lm_cov,
        true_landmarks=landmarks.xy,
        range_scale=kappa,
        used=used,
        gated=gated,
        unknown=unknown,
        processing_time_s=time.perf_counter() - start,
        parameters=p,
    )


def _apply_motion(mean, cov, new_pose, gt, qt):
    mean = mean.copy()
    mean[:3] = new_pose
    cov = cov.copy()
    cov[:3, :] = gt @ cov[:3, :]
    cov[:, :3] = cov[:, :3] @ gt.T
    cov[:3, :3] += qt
    return mean, 0.5 * (cov + cov.T)


def _noise(p, z):
    sigma = p["range_std"] + p["range_std_per_m"] * z[0] / max(math.cos(z[1]), 0.1)
    return np.diag([sigma**2, p["bearing_std"] ** 2])


def _initialise(mean, cov, at, c, z, p):
    m, j_pose, j_k, j_z = _inverse_observe(mean[:3], c, mean[3], z)
    mean = mean.copy()
    mean[at : at + 2] = m
    jx = np.zeros((2, mean.size))
    jx[:, :3], jx[:, 3] = j_pose, j_k
    cov = cov.copy()
    cross = jx @ cov
    cov[at : at + 2, :] = cross
    cov[:, at : at + 2] = cross.T
    cov[at : at + 2, at : at + 2] = jx @ cov @ jx.T + j_z @ _noise(p, z) @ j_z.T
    return mean, 0.5 * (cov + cov.T)


def _update(mean, cov, at, c, z, p, gate, inflation=1.0):
    z_hat, h_pose, h_k, h_m = _observe(mean[:3], c, mean[3], mean[at : at + 2])
    h = np.zeros((2, mean.size))
    h[:, :3], h[:, 3], h[:, at : at + 2] = h_pose, h_k, h_m
    r = _noise(p, z) * inflation
    nu = np.array([z[0] - z_hat[0], wrap_angle(z[1] - z_hat[1])])
    s = h @ cov @ h.T + r
    d2 = float(nu @ np.linalg.solve(s, nu))
    if not d2 <= gate:
        return mean, cov, False
    dist = math.sqrt(d2)
    if dist > p["huber_k"]:  # Huber: inflate R so that the weight is k / d
        r = r * (dist / p["huber_k"])
        s = h @ cov @ h.T + r
    gain = np.linalg.solve(s, h @ cov).T
    mean = mean + gain @ nu
    mean[2] = wrap_angle(mean[2])
    ikh = np.eye(mean.size) - gain @ h
    cov = ikh @ cov @ ikh.T + gain @ r @ gain.T  # Joseph form
    return mean, 0.5 * (cov + cov.T), True


def _smooth(data, odom, motion, est, lm_xy, kappa, group_times, sightings, seen, p):
    """The smoothing solution (module docstring); returns poses on the grid, landmarks, κ.

    Gauss–Newton with Levenberg–Marquardt damping on the sparse normal equations: the poses
    at the sighting times (perturbed on the right, X·Exp(δ), as in
    :mod:`wheelbase.mapping.posegraph`, whose exact odometry-edge Jacobians are reused), the
    landmarks and κ; Huber weights (IRLS) on the sightings."""
    from scipy import sparse
    from scipy.sparse.linalg import spsolve

    from wheelbase.datasets.g2o import PoseGraph
    from wheelbase.localization import mrclam as lm
    from wheelbase.mapping.posegraph import _linearise, _retract

    n_g = group_times.size
    idx_lm = np.cumsum(seen) - 1
    n_seen = int(seen.sum())
    odo_at = lm._odometry_at(data, odom, group_times)
    controls = np.column_stack([data.v, data.omega])
    grid_index = np.searchsorted(data.t, group_times, side="right") - 1
    info = np.empty((n_g - 1, 3, 3))
    for g in range(n_g - 1):
        a, b = grid_index[g], grid_index[g + 1]
        times = np.concatenate([[group_times[g]], data.t[a + 1 : b + 1], [group_times[g + 1]]])
        dts = np.maximum(np.diff(times), 0.0)
        ctrl = controls[np.clip(np.arange(a, a + dts.size), 0, data.t.size - 1)]
        info[g] = _relative_information(motion, ctrl, dts)
    edges = np.column_stack([np.arange(n_g - 1), np.arange(1, n_g)])
    graph = PoseGraph(np.arange(n_g), odo_at, edges, relative_pose(odo_at[:-1], odo_at[1:]),
                      info)  # fmt: skip
    sg = np.array([q[0] for q in sightings])
    sl = idx_lm[np.array([q[1] for q in sightings])]
    sz = np.array([q[2] for q in sightings])
    sc = np.array([q[3] for q in sightings])
    r_inv = np.array([np.linalg.inv(_noise(p, z)) for z in sz])
    poses = _at_times(data, odom, est, group_times)
    marks = lm_xy[seen].copy()
    k_scale = kappa
    n_x = 3 * n_g + 2 * n_seen + 1
    # the gauge: the start pose, moved by the odometry to the first sighting, with the motion
    # model's covariance over that stretch, in the frame of the first sighting's pose where
    # the prior's residual lives (as the odometry edges' covariances)
    first = max(int(grid_index[0]), 0)
    dts0 = np.diff(np.concatenate([data.t[: first + 1], [group_times[0]]]))
    prior_pose = compose(data.true_pose[0], relative_pose(odom[0], odo_at[0]))
    prior_info = _relative_information(motion, controls[: dts0.size], dts0)
    k_info = 1.0 / p["range_scale_std"] ** 2

    def sightings_terms(poses, marks, k_scale):
        res = np.empty((sg.size, 2))
        jp = np.empty((sg.size, 2, 3))
        jk = np.empty((sg.size, 2))
        jm = np.empty((sg.size, 2, 2))
        for q in range(sg.size):
            pose = poses[sg[q]]
            z_hat, hp, hk, hm = _observe(pose, sc[q], k_scale, marks[sl[q]])
            res[q] = [sz[q, 0] - z_hat[0], wrap_angle(sz[q, 1] - z_hat[1])]
            c, s_ = math.cos(pose[2]), math.sin(pose[2])
            # world-frame Jacobian → right perturbation: δxy_world = R δxy_body
            jp[q] = hp @ np.array([[c, -s_, 0.0], [s_, c, 0.0], [0.0, 0.0, 1.0]])
            jk[q], jm[q] = hk, hm
        return res, jp, jk, jm

    def cost(poses, marks, k_scale):
        from wheelbase.mapping.posegraph import edge_chi2

        odo = float(edge_chi2(graph, poses).sum())
        res, *_ = sightings_terms(poses, marks, k_scale)
        d2 = np.einsum("qi,qij,qj->q", res, r_inv, res)
        d = np.sqrt(d2)
        hk = p["huber_k"]
        rob = np.where(d <= hk, d2, 2 * hk * d - hk * hk).sum()
        e0 = relative_pose(prior_pose, poses[0])
        return odo + rob + float(e0 @ prior_info @ e0) + k_info * (k_scale - 1.0) ** 2

    current = cost(poses, marks, k_scale)
    lam = 0.0
    for _ in range(30):
        _, blocks, gi, gj = _linearise(graph, poses, np.ones(graph.n_edges))
        rows, cols, vals = [], [], []
        grad = np.zeros(n_x)
        a = 3 * edges[:, 0][:, None] + np.arange(3)
        b = 3 * edges[:, 1][:, None] + np.arange(3)
        for blk, ra, ca in ((0, a, a), (1, a, b), (2, b, a), (3, b, b)):
            rows.append(np.repeat(ra, 3, axis=1).ravel())
            cols.append(np.tile(ca, (1, 3)).ravel())
            vals.append(blocks[:, blk].ravel())
        np.add.at(grad, a, gi)
        np.add.at(grad, b, gj)
        res, jp, jk, jm = sightings_terms(poses, marks, k_scale)
        d = np.sqrt(np.einsum("qi,qij,qj->q", res, r_inv, res))
        w = np.where(d <= p["huber_k"], 1.0, p["huber_k"] / np.maximum(d, 1e-12))
        jac = np.concatenate([jp, jm, jk[:, :, None]], 2)  # (Q, 2, 6): pose, landmark, κ
        idx = np.concatenate([3 * sg[:, None] + np.arange(3),
                              3 * n_g + 2 * sl[:, None] + np.arange(2),
                              np.full((sg.size, 1), n_x - 1)], 1)  # fmt: skip
        wr = r_inv * w[:, None, None]
        hq = np.swapaxes(jac, 1, 2) @ wr @ jac
        # the residual is z − h: the gradient of ½‖·‖² in the parameters is −Jᵀ W r
        gq = -np.einsum("qji,qjk,qk->qi", jac, wr, res)
        rows.append(np.repeat(idx, 6, axis=1).ravel())
        cols.append(np.tile(idx, (1, 6)).ravel())
        vals.append(hq.ravel())
        np.add.at(grad, idx, gq)
        # priors: the first pose (the gauge) and κ
        e0 = relative_pose(prior_pose, poses[0])
        rows.append(np.repeat(np.arange(3), 3))
        cols.append(np.tile(np.arange(3), 3))
        vals.append(prior_info.ravel())
        grad[:3] += prior_info @ e0
        rows.append([n_x - 1])
        cols.append([n_x - 1])
        vals.append([k_info])
        grad[-1] += k_info * (k_scale - 1.0)
        h = sparse.coo_matrix((np.concatenate(vals), (np.concatenate(rows),
                              np.concatenate(cols))), shape=(n_x, n_x)).tocsc()  # fmt: skip
        while True:
            damped = h + sparse.diags(lam * np.maximum(h.diagonal(), 1e-9)) if lam else h
            step = -spsolve(damped, grad)
            trial_p = _retract(poses, step[: 3 * n_g].reshape(-1, 3))
            trial_m = marks + step[3 * n_g : -1].reshape(-1, 2)
            trial_k = k_scale + step[-1]
            new = cost(trial_p, trial_m, trial_k) if np.all(np.isfinite(step)) else math.inf
            if new <= current:
                break
            lam = max(lam * 10.0, 1e-6)
            if lam > 1e6:
                break
        if not new <= current:
            break
        decrease = (current - new) / max(current, 1e-300)
        poses, marks, k_scale, current = trial_p, trial_m, trial_k, new
        lam /= 10.0
        if decrease < 1e-9:
            break
    out = np.full_like(lm_xy, np.nan)
    out[seen] = marks
    # every grid time: the pose of the last sighting before it, moved along the odometry
    last = np.clip(np.searchsorted(group_times, data.t, side="right") - 1, 0, n_g - 1)
    smoothed = compose(poses[last], relative_pose(odo_at[last], odom))
    return smoothed, out, float(k_scale)


def _relative_information(motion, controls, dts):
    """Information of the pose reached by a run of odometry steps, relative to the pose it
    started from, in the frame of the end pose (where a residual relative_pose(X̂_b, X_b) of
    an odometry edge or a prior lives).

    The motion model's covariance accumulated along the run is of the end pose in the start
    pose's frame; rotating it by the turn between the two expresses it in the end pose's. A
    floor of 1e-8 m² and 1e-10 rad² keeps a run of zero length invertible.

    Parameters
    ----------
    motion : VelocityMotion
        The motion model.
    controls : numpy.ndarray, shape (K, 2)
        (v [m/s], ω [rad/s]) of each step.
    dts : numpy.ndarray, shape (K,)
        Step lengths [s], >= 0.

    Returns
    -------
    numpy.ndarray, shape (3, 3)
        The information matrix [1/m², 1/(m·rad), 1/rad²].
    """
    _, _, qt = _steps(motion, np.zeros(3), controls * dts[:, None], dts)
    turn = float(np.sum(controls[:, 1] * dts))
    c, s = math.cos(turn), math.sin(turn)
    rot = np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])
    return np.linalg.inv(rot @ qt @ rot.T + np.diag([1e-8, 1e-8, 1e-10]))


def _at_times(data, odom, est, times):
    """Estimates at arbitrary times: the grid estimate before, moved along the odometry."""
    index = np.clip(np.searchsorted(data.t, times, side="right") - 1, 0, data.t.size - 1)
    from wheelbase.localization import mrclam as lm

    odo = lm._odometry_at(data, odom, times)
    return compose(est[index], relative_pose(odom[index], odo))
