"""Numba kernels of :mod:`wheelbase.mapping.posegraph`: one loop over the edges that computes
each SE(2) residual, its Jacobians and the blocks of the normal equations and adds them into
the :class:`~wheelbase.mapping.block_cholesky.BlockCholesky` storage, without the (E, 3, 3)
temporaries of the NumPy version (``posegraph._linearise``, which a test holds them to).

The formulas are those of :mod:`wheelbase.mapping.se2` (Log, J_r⁻¹, Ad), term for term.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from wheelbase.geometry_numba import wrap_angle_scalar

__all__: list[str] = []

_SMALL = 1e-5  # as se2._SMALL: |φ| below which the series of J_r's third column are used


@numba.njit(cache=True, inline="always")
def _half_angle(phi):  # pragma: no cover - compiled
    """sin φ and 1 − cos φ from one sine and one cosine of φ/2 (no cancellation near 0)."""
    sh, ch = math.sin(0.5 * phi), math.cos(0.5 * phi)
    return 2.0 * sh * ch, 2.0 * sh * sh


@numba.njit(cache=True)
def cos_sin(poses):  # pragma: no cover - compiled
    """cos θ and sin θ of every pose, (V, 2): each vertex's once, not each edge's."""
    out = np.empty((poses.shape[0], 2))
    for v in range(poses.shape[0]):
        out[v, 0], out[v, 1] = math.cos(poses[v, 2]), math.sin(poses[v, 2])
    return out


@numba.njit(cache=True, inline="always")
def _residual(poses, cs, i, j, z, zcs):  # pragma: no cover - compiled
    """r = Log(Z⁻¹ X_i⁻¹ X_j) = (ρ₁, ρ₂, φ), sin φ, 1 − cos φ and the pose X_j⁻¹ X_i as
    (x, y, cos θ, sin θ); cs holds cos, sin of the poses' angles, zcs those of Z's."""
    ci, si, cj, sj = cs[i, 0], cs[i, 1], cs[j, 0], cs[j, 1]
    dx, dy = poses[j, 0] - poses[i, 0], poses[j, 1] - poses[i, 1]
    tx, ty = ci * dx + si * dy, -si * dx + ci * dy
    cz, sz = zcs[0], zcs[1]
    ex, ey = tx - z[0], ty - z[1]
    mx, my = cz * ex + sz * ey, -sz * ex + cz * ey
    phi = wrap_angle_scalar(poses[j, 2] - poses[i, 2] - z[2])
    sin_phi, one_minus_cos = _half_angle(phi)
    if phi == 0.0:
        a, b = 1.0, 0.0
    else:  # a = sin φ / φ, b = (1 − cos φ)/φ: V(φ) of se2
        a, b = sin_phi / phi, one_minus_cos / phi
    det = a * a + b * b
    r0, r1 = (a * mx + b * my) / det, (-b * mx + a * my) / det
    # X_j⁻¹ X_i: translation R_jᵀ (t_i − t_j), angle θ_i − θ_j by its cosine and sine
    ax, ay = cj * -dx + sj * -dy, -sj * -dx + cj * -dy
    return r0, r1, phi, a, b, sin_phi, one_minus_cos, ax, ay, ci * cj + si * sj, si * cj - ci * sj


@numba.njit(cache=True, inline="always")
def _add_at_b(out, a, b):  # pragma: no cover - compiled
    """out += aᵀ·b for 3×3 blocks."""
    for m in range(3):
        for n in range(3):
            out[m, n] += a[0, m] * b[0, n] + a[1, m] * b[1, n] + a[2, m] * b[2, n]


@numba.njit(cache=True)
def edge_chi2_kernel(poses, edges, measurements, zcs, information):  # pragma: no cover - compiled
    """rᵀΩr of every edge (zcs: cos, sin of the measured angles, (E, 2))."""
    out = np.empty(edges.shape[0])
    cs = cos_sin(poses)
    for e in range(edges.shape[0]):
        r0, r1, r2, _, _, _, _, _, _, _, _ = _residual(
            poses, cs, edges[e, 0], edges[e, 1], measurements[e], zcs[e]
        )
        om = information[e]
        out[e] = (
            om[0, 0] * r0 * r0 + om[1, 1] * r1 * r1 + om[2, 2] * r2 * r2
            + 2.0 * (om[0, 1] * r0 * r1 + om[0, 2] * r0 * r2 + om[1, 2] * r1 * r2)
        )  # fmt: skip
    return out


@numba.njit(cache=True)
def assemble_kernel(poses, edges, measurements, zcs, information, weights, free_index, slot,
                    upper, diag, off, grad):  # pragma: no cover - compiled  # fmt: skip
    """Add each edge's JᵀWΩJ blocks and JᵀWΩr into diag (n_free, 3, 3), off (n_off, 3, 3)
    and grad (n_free, 3), zeroed first; vertices with ``free_index`` −1 are held."""
    diag[:] = 0.0
    off[:] = 0.0
    grad[:] = 0.0
    ji = np.empty((3, 3))
    jj = np.zeros((3, 3))
    om = np.empty((3, 3))
    oi = np.empty((3, 3))
    oj = np.empty((3, 3))
    r = np.empty(3)
    wr = np.empty(3)
    cs = cos_sin(poses)
    for e in range(edges.shape[0]):
        i, j = edges[e, 0], edges[e, 1]
        fi, fj = free_index[i], free_index[j]
        if fi < 0 and fj < 0:
            continue
        r[0], r[1], phi, a, b, sin_phi, one_minus_cos, dx, dy, c, s = _residual(
            poses, cs, i, j, measurements[e], zcs[e]
        )
        # J_r(r)⁻¹ (se2.se2_right_jacobian_inv)
        if abs(phi) < _SMALL:
            p, q = phi / 6.0, 0.5 - phi * phi / 24.0
        else:
            p, q = (phi - sin_phi) / (phi * phi), one_minus_cos / (phi * phi)
        u, v = r[0] * p - r[1] * q, r[0] * q + r[1] * p
        det = a * a + b * b
        ia, ib = a / det, b / det
        jj[0, 0], jj[0, 1], jj[0, 2] = ia, -ib, -(ia * u - ib * v)
        jj[1, 0], jj[1, 1], jj[1, 2] = ib, ia, -(ib * u + ia * v)
        jj[2, 0], jj[2, 1], jj[2, 2] = 0.0, 0.0, 1.0
        r[2] = phi
        # J_i = −J_r⁻¹ Ad(X_j⁻¹ X_i), Ad = [[c, −s, y], [s, c, −x], [0, 0, 1]]
        for m in range(3):
            ji[m, 0] = -(jj[m, 0] * c + jj[m, 1] * s)
            ji[m, 1] = -(-jj[m, 0] * s + jj[m, 1] * c)
            ji[m, 2] = -(jj[m, 0] * dy - jj[m, 1] * dx + jj[m, 2])
        w = weights[e]
        for m in range(3):
            for n in range(3):
                om[m, n] = information[e, m, n] * w
        for m in range(3):
            wr[m] = om[m, 0] * r[0] + om[m, 1] * r[1] + om[m, 2] * r[2]
            for n in range(3):
                oi[m, n] = om[m, 0] * ji[0, n] + om[m, 1] * ji[1, n] + om[m, 2] * ji[2, n]
                oj[m, n] = om[m, 0] * jj[0, n] + om[m, 1] * jj[1, n] + om[m, 2] * jj[2, n]
        if fi >= 0:
            for m in range(3):
                grad[fi, m] += ji[0, m] * wr[0] + ji[1, m] * wr[1] + ji[2, m] * wr[2]
            _add_at_b(diag[fi], ji, oi)
        if fj >= 0:
            for m in range(3):
                grad[fj, m] += jj[0, m] * wr[0] + jj[1, m] * wr[1] + jj[2, m] * wr[2]
            _add_at_b(diag[fj], jj, oj)
        if fi >= 0 and fj >= 0:
            if fi == fj:  # an edge from a vertex to itself: all four blocks on the diagonal
                for m in range(3):
                    for n in range(3):
                        h = ji[0, m] * oj[0, n] + ji[1, m] * oj[1, n] + ji[2, m] * oj[2, n]
                        diag[fi, m, n] += h
                        diag[fi, n, m] += h
            elif upper[e]:  # the (i, j) block J_iᵀΩJ_j
                _add_at_b(off[slot[e]], ji, oj)
            else:  # the (j, i) block J_jᵀΩJ_i
                _add_at_b(off[slot[e]], jj, oi)


@numba.njit(cache=True)
def accumulate_linear(ji, jj, weight, target, edges, held, free_index, slot, upper, diag, off,
                      rhs):  # pragma: no cover - compiled  # fmt: skip
    """Normal equations of the linear residuals r_e = J_i x_i + J_j x_j − c_e weighted by W_e
    (ji, jj of shape (E, m, b), weight (E, m, m), target c (E, m)): diag, off, rhs zeroed then
    filled with Σ JᵀWJ and Σ JᵀW c; a held vertex (``free_index`` −1) enters with its value
    ``held[v]`` on the right-hand side."""
    diag[:] = 0.0
    off[:] = 0.0
    rhs[:] = 0.0
    n_rows, b = ji.shape[1], ji.shape[2]
    t = np.empty(n_rows)
    wi = np.empty((n_rows, b))  # W J_i
    wj = np.empty((n_rows, b))  # W J_j
    for e in range(edges.shape[0]):
        i, j = edges[e, 0], edges[e, 1]
        fi, fj = free_index[i], free_index[j]
        if fi < 0 and fj < 0:
            continue
        for m in range(n_rows):
            t[m] = target[e, m]
            if fi < 0:
                for n in range(b):
                    t[m] -= ji[e, m, n] * held[i, n]
            if fj < 0:
                for n in range(b):
                    t[m] -= jj[e, m, n] * held[j, n]
        for m in range(n_rows):
            for u in range(b):
                si, sj = 0.0, 0.0
                for n in range(n_rows):
                    si += weight[e, m, n] * ji[e, n, u]
                    sj += weight[e, m, n] * jj[e, n, u]
                wi[m, u], wj[m, u] = si, sj
        for u in range(b):
            for m in range(n_rows):
                if fi >= 0:
                    rhs[fi, u] += wi[m, u] * t[m]
                if fj >= 0:
                    rhs[fj, u] += wj[m, u] * t[m]
            for w in range(b):
                sii, sij, sjj = 0.0, 0.0, 0.0
                for m in range(n_rows):
                    sii += ji[e, m, u] * wi[m, w]
                    sij += ji[e, m, u] * wj[m, w]
                    sjj += jj[e, m, u] * wj[m, w]
                if fi >= 0:
                    diag[fi, u, w] += sii
                if fj >= 0:
                    diag[fj, u, w] += sjj
                if fi >= 0 and fj >= 0:
                    if fi == fj:
                        diag[fi, u, w] += sij
                        diag[fi, w, u] += sij
                    elif upper[e]:
                        off[slot[e], u, w] += sij
                    else:
                        off[slot[e], w, u] += sij


@numba.njit(cache=True)
def retract_kernel(poses, free, step):  # pragma: no cover - compiled
    """A copy of poses with X_v·Exp(δ) for each free vertex v (step in free's order)."""
    out = poses.copy()
    for k in range(free.size):
        v = free[k]
        r0, r1, phi = step[k, 0], step[k, 1], step[k, 2]
        sin_phi, one_minus_cos = _half_angle(phi)
        if phi == 0.0:
            a, b = 1.0, 0.0
        else:
            a, b = sin_phi / phi, one_minus_cos / phi
        ex, ey = a * r0 - b * r1, b * r0 + a * r1
        c, s = math.cos(poses[v, 2]), math.sin(poses[v, 2])
        out[v, 0] = poses[v, 0] + c * ex - s * ey
        out[v, 1] = poses[v, 1] + s * ex + c * ey
        out[v, 2] = wrap_angle_scalar(poses[v, 2] + wrap_angle_scalar(phi))
    return out
