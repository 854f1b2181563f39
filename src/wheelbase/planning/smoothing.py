"""Path smoothing that keeps the curvature limit, the clearance and the cusps.

Hybrid A* paths are chains of short arcs whose steering curvature jumps between −1/R, 0 and
+1/R (the zig-zag visible in document 002's Hybrid A* slides before smoothing). Instead of
moving points and hoping the result stays drivable (Dolgov et al. 2010 add a curvature term to
a gradient descent for that), this smoother works on the **curvature profile** κ(s) of each
segment between cusps (and between turns in place):

1. low-pass κ(s) with a moving average of width ``window`` metres — an average of values in
   [−1/R, 1/R] stays in it, so the curvature limit holds by construction;
2. integrate the poses again from the segment's first pose (exact arcs per sample interval);
3. restore the segment's end pose exactly by Gauss–Newton on a small correction
   δκ(s) = (1 − |κ(s)|R) Σ aⱼ sin(jπ s/L) (minimum-norm steps; zero where the curvature is at
   its limit), then re-check |κ| ≤ 1/R; the end must match to 1e-9 of the segment's length
   (at least 1e-9 m), computed in the segment's own frame, so a path 4.5e9 m from the origin
   is smoothed as it would be at the origin;
4. accept the segment only if the footprint, grown by the planner's continuous-motion margin
   plus the clearance the original segment had (up to ``safe_distance``), is collision-free;
   otherwise try half the window, and finally keep the original segment.

Start, goal and every cusp pose are therefore unchanged, and smoothing never makes a path
infeasible. For turning in place (R = 0) straight segments have no curvature to smooth and
turns in place are kept as they are.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
from scipy.ndimage import uniform_filter1d

from wheelbase._validate import nonnegative, positive
from wheelbase.geometry import wrap_angle
from wheelbase.planning.footprint import Footprint
from wheelbase.planning.occupancy import OccupancyGrid
from wheelbase.planning.path import PlannedPath

__all__ = ["smooth_path"]


def smooth_path(
    path: PlannedPath,
    grid: OccupancyGrid,
    footprint: Footprint,
    turning_radius: float,
    *,
    window: float = 2.0,
    safe_distance: float = 0.3,
    collision_margin: float | None = None,
    basis: int = 6,
) -> PlannedPath:
    """Smooth a planned path segment by segment, keeping cusps, clearance and curvature.

    Parameters
    ----------
    path : PlannedPath
        A successful path (e.g. from :meth:`HybridAStar.plan`).
    grid : OccupancyGrid
        The map it was planned on.
    footprint : Footprint
        Robot outline (body frame of the reference point).
    turning_radius : float
        Minimum turning radius R [m]; 0 (turning in place) means no curvature limit.
    window : float
        Width [m] of the moving average applied to the curvature profile.
    safe_distance : float
        Clearance [m] kept wherever the original path had at least that much.
    collision_margin : float or None
        Footprint growth [m] covering the motion between samples; default half the largest
        sample spacing times (1 + ρ_max/R), as in the planner.
    basis : int
        Number of sine terms of the end-pose correction (>= 3).

    Returns
    -------
    PlannedPath
        Same start, goal, cusps and statistics; poses, curvatures and arc length updated.

    Examples
    --------
    >>> from wheelbase.planning import HybridAStar, OccupancyGrid
    >>> grid = OccupancyGrid.from_array(np.zeros((80, 120), bool), 0.1)
    >>> planner = HybridAStar(grid, (0.8, 0.5), 1.0, rear_axle_to_center=0.2)
    >>> raw = planner.plan((1.5, 1.5, 0.0), (10.0, 6.0, 0.0))
    >>> smooth = smooth_path(raw, grid, planner.footprint, 1.0)
    >>> bool(np.allclose(smooth.poses[-1], raw.poses[-1]))
    True
    """
    if not path.success or len(path) < 5:
        return path
    radius = nonnegative("turning_radius", turning_radius, "m")
    window = positive("window", window, "m")
    safe_distance = nonnegative("safe_distance", safe_distance, "m")
    if int(basis) != basis or basis < 3:
        from wheelbase.errors import ConfigError

        raise ConfigError(f"basis must be an integer >= 3 (got {basis!r})")
    kmax = 1.0 / radius if radius > 0 else math.inf
    ds_all = np.diff(path.arc_length)
    if collision_margin is None:
        spacing = float(ds_all.max()) if len(ds_all) else 0.0
        bend = footprint.max_radius / radius if radius > 0 else 1.0
        collision_margin = 0.5 * spacing * (1.0 + bend)
    collision_margin = nonnegative("collision_margin", collision_margin, "m")

    poses = path.poses.copy()
    curv = path.curvatures.copy()
    rotating = np.isinf(curv)
    breaks = {0, len(path) - 1}
    breaks.update(int(i) for i in path.cusp_indices)
    for i in np.nonzero(rotating)[0]:
        breaks.update((int(i) - 1, int(i)))
    bounds = sorted(b for b in breaks if 0 <= b < len(path))
    for a, b in itertools.pairwise(bounds):
        if b - a < 6 or rotating[a + 1 : b + 1].any():
            continue
        seg = slice(a, b + 1)
        direction = int(path.directions[a + 1])
        ds = ds_all[a:b]
        kappa = curv[a + 1 : b + 1]  # curvature of each interval
        required = _clearance_kept(grid, footprint, poses[seg], collision_margin, safe_distance)
        checked = footprint.inflated(collision_margin + required)
        for w in (window, window / 2):
            n = max(1, round(w / float(np.mean(ds))))
            smooth_k = uniform_filter1d(kappa, size=n, mode="nearest")
            result = _close_end(poses[a], poses[b], ds, smooth_k, direction, basis, kmax)
            if result is None:
                continue
            new_poses, new_k = result
            if np.any(np.abs(new_k) > kmax * (1.0 + 1e-6)):
                continue
            if grid.in_collision(checked, new_poses).any():
                continue
            poses[seg] = new_poses
            curv[a + 1 : b + 1] = new_k
            curv[a] = new_k[0] if a == 0 else curv[a]
            break
    return PlannedPath(
        poses, path.directions.copy(), curv, path.arc_length.copy(), True, path.stats
    )


def _clearance_kept(grid, footprint, poses, margin, safe) -> float:
    """Largest of (safe, safe/2, safe/4, 0) that the original segment satisfies."""
    for c in (safe, safe / 2, safe / 4):
        if c > 0 and not grid.in_collision(footprint.inflated(margin + c), poses).any():
            return c
    return 0.0


def _integrate(start: np.ndarray, ds: np.ndarray, kappa: np.ndarray, direction: int) -> np.ndarray:
    """Poses after intervals of length ``ds`` with steering curvature ``kappa`` (exact arcs)."""
    step = direction * ds  # signed distance along the body x axis
    dth = kappa * step
    th = start[2] + np.concatenate([[0.0], np.cumsum(dth)])
    # exact arc: chord of length step·sinc(dθ/2) along the mid heading
    chord = step * np.sinc(dth / (2 * np.pi))
    mid = th[:-1] + dth / 2
    x = start[0] + np.concatenate([[0.0], np.cumsum(chord * np.cos(mid))])
    y = start[1] + np.concatenate([[0.0], np.cumsum(chord * np.sin(mid))])
    return np.column_stack([x, y, th])


def _close_end(start, end, ds, kappa, direction, basis, kmax):
    """Correct κ so that integration from ``start`` ends exactly at ``end`` (Gauss–Newton).

    Works in the frame of ``start``'s position: far from the origin, absolute coordinates keep
    only micrometres, which the end match needs to the nanometre."""
    origin, goal = start[:2].copy(), end
    start = np.array([0.0, 0.0, start[2]])
    end = np.array([end[0] - origin[0], end[1] - origin[1], end[2]])
    s = np.concatenate([[0.0], np.cumsum(ds)])
    mid_s = (s[:-1] + s[1:]) / 2
    length = s[-1]
    phi = np.stack([np.sin(j * np.pi * mid_s / length) for j in range(1, basis + 1)], 1)
    if np.isfinite(kmax):
        # correct only where the curvature has room, in proportion to that room
        phi *= np.clip(1.0 - np.abs(kappa) / kmax, 0.0, None)[:, None]
    coef = np.zeros(basis)
    scale = max(length, 1e-9)
    tolerance = 1e-9 * max(length, 1.0)  # [m]: relative to the segment, at least 1e-9 m

    step_s = direction * ds  # signed distance of each interval along the body x axis

    def residual_and_jacobian(c):
        """The end-pose error and its exact derivative with respect to ``c``.

        Interval i moves the pose by the chord ``v_i = c_i·(cos m_i, sin m_i)``, with the
        chord length ``c_i = t_i·sinc(a_i)``, ``a_i = κ_i·t_i/2`` and the mid heading
        ``m_i = θ_i + a_i``. Raising κ_i by dκ turns every later chord by ``t_i·dκ`` and
        the chord ``i`` itself by ``t_i·dκ/2`` (J: a quarter turn), and changes its length:
        ``∂p/∂κ_i = t_i·J·(Σ_{k>i} v_k + v_i/2) + ∂c_i/∂κ_i·(cos m_i, sin m_i)`` and
        ``∂θ/∂κ_i = t_i``. (Finite differences needed one integration per basis term.)"""
        k = kappa + phi @ c
        half = k * step_s / 2.0
        theta = start[2] + np.concatenate([[0.0], np.cumsum(2.0 * half)])
        mid = theta[:-1] + half
        chord = step_s * np.sinc(half / np.pi)
        cos_m, sin_m = np.cos(mid), np.sin(mid)
        vx, vy = chord * cos_m, chord * sin_m
        after_x = np.cumsum(vx[::-1])[::-1] - vx / 2.0  # Σ_{k>i} v_k + v_i/2
        after_y = np.cumsum(vy[::-1])[::-1] - vy / 2.0
        # d(sin a / a)/da = (a cos a − sin a)/a², → −a/3 near 0; da/dκ = t/2
        small = np.abs(half) < 1e-4
        safe = np.where(small, 1.0, half)
        dsinc = np.where(small, -half / 3.0, (half * np.cos(half) - np.sin(half)) / safe**2)
        dchord = step_s * dsinc * step_s / 2.0
        d_x = -step_s * after_y + dchord * cos_m
        d_y = step_s * after_x + dchord * sin_m
        r = np.array(
            [
                vx.sum() - end[0],
                vy.sum() - end[1],
                scale * float(wrap_angle(theta[-1] - end[2])),
            ]
        )
        jac = np.stack([d_x @ phi, d_y @ phi, scale * (step_s @ phi)])
        return r, jac

    r, jac = residual_and_jacobian(coef)
    for _ in range(12):
        if np.max(np.abs(r)) < 1e-2 * tolerance:
            break
        step, *_ = np.linalg.lstsq(jac, -r, rcond=None)
        coef = coef + step
        r, jac = residual_and_jacobian(coef)
    if np.max(np.abs(r)) > tolerance:
        return None
    new_k = kappa + phi @ coef
    poses = _integrate(start, ds, new_k, direction)
    poses[:, 2] = wrap_angle(poses[:, 2])
    poses[:, :2] += origin
    poses[-1] = goal
    return poses, new_k
