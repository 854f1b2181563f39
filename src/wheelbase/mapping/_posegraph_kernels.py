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

__all__: list[str] = []

_SMALL = 1e-5  # as se2._SMALL: |φ| below which the series of J_r's third column are used


@numba.njit(cache=True, inline="always")
def _wrap(angle):  # pragma: no cover - compiled
    w = math.atan2(math.sin(angle), math.cos(angle))
    return math.pi if w <= -math.pi else w


@numba.njit(cache=True, inline="always")
def _a_b(phi):  # pragma: no cover - compiled
    """sin φ / φ and (1 − cos φ)/φ, smooth through 0 (as se2._a_b)."""
    if phi == 0.0:
        return 1.0, 0.0
    half = 0.5 * phi
    sh = math.sin(half) / half
    return math.sin(phi) / phi, half * sh * sh


@numba.njit(cache=True, inline="always")
def _residual(poses, i, j, z):  # pragma: no cover - compiled
    """r = Log(Z⁻¹ X_i⁻¹ X_j) and the pose X_j⁻¹ X_i."""
    xi, yi, ti = poses[i, 0], poses[i, 1], poses[i, 2]
    xj, yj, tj = poses[j, 0], poses[j, 1], poses[j, 2]
    ci, si = math.cos(ti), math.sin(ti)
    dx, dy = xj - xi, yj - yi
    tx, ty, tt = ci * dx + si * dy, -si * dx + ci * dy, _wrap(tj - ti)
    cz, sz = math.cos(z[2]), math.sin(z[2])
    ex, ey = tx - z[0], ty - z[1]
    mx, my, mt = cz * ex + sz * ey, -sz * ex + cz * ey, _wrap(tt - z[2])
    phi = _wrap(mt)
    a, b = _a_b(phi)
    det = a * a + b * b
    r0, r1 = (a * mx + b * my) / det, (-b * mx + a * my) / det
    cj, sj = math.cos(tj), math.sin(tj)
    dxi, dyi = xi - xj, yi - yj
    return r0, r1, phi, a, b, cj * dxi + sj * dyi, -sj * dxi + cj * dyi, _wrap(ti - tj)


@numba.njit(cache=True, inline="always")
def _add_at_b(out, a, b):  # pragma: no cover - compiled
    """out += aᵀ·b for 3×3 blocks."""
    for m in range(3):
        for n in range(3):
            out[m, n] += a[0, m] * b[0, n] + a[1, m] * b[1, n] + a[2, m] * b[2, n]


@numba.njit(cache=True)
def edge_chi2_kernel(poses, edges, measurements, information):  # pragma: no cover - compiled
    """rᵀΩr of every edge."""
    out = np.empty(edges.shape[0])
    for e in range(edges.shape[0]):
        r0, r1, r2, _, _, _, _, _ = _residual(poses, edges[e, 0], edges[e, 1], measurements[e])
        om = information[e]
        out[e] = (
            om[0, 0] * r0 * r0 + om[1, 1] * r1 * r1 + om[2, 2] * r2 * r2
            + 2.0 * (om[0, 1] * r0 * r1 + om[0, 2] * r0 * r2 + om[1, 2] * r1 * r2)
        )  # fmt: skip
    return out


@numba.njit(cache=True)
def assemble_kernel(poses, edges, measurements, information, weights, free_index, slot, upper,
                    diag, off, grad):  # pragma: no cover - compiled  # fmt: skip
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
    for e in range(edges.shape[0]):
        i, j = edges[e, 0], edges[e, 1]
        fi, fj = free_index[i], free_index[j]
        if fi < 0 and fj < 0:
            continue
        r[0], r[1], phi, a, b, dx, dy, dt = _residual(poses, i, j, measurements[e])
        # J_r(r)⁻¹ (se2.se2_right_jacobian_inv)
        if abs(phi) < _SMALL:
            p, q = phi / 6.0, 0.5 - phi * phi / 24.0
        else:
            p, q = (phi - math.sin(phi)) / (phi * phi), (1.0 - math.cos(phi)) / (phi * phi)
        u, v = r[0] * p - r[1] * q, r[0] * q + r[1] * p
        det = a * a + b * b
        ia, ib = a / det, b / det
        jj[0, 0], jj[0, 1], jj[0, 2] = ia, -ib, -(ia * u - ib * v)
        jj[1, 0], jj[1, 1], jj[1, 2] = ib, ia, -(ib * u + ia * v)
        jj[2, 0], jj[2, 1], jj[2, 2] = 0.0, 0.0, 1.0
        r[2] = phi
        # J_i = −J_r⁻¹ Ad(X_j⁻¹ X_i), Ad = [[c, −s, y], [s, c, −x], [0, 0, 1]]
        c, s = math.cos(dt), math.sin(dt)
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
def accumulate_linear(ji, jj, target, edges, held, free_index, slot, upper, diag, off,
                      rhs):  # pragma: no cover - compiled  # fmt: skip
    """Normal equations of the linear residuals r_e = J_i x_i + J_j x_j − c_e (ji, jj of shape
    (E, m, b), target c of shape (E, m)): diag, off, rhs zeroed then filled; a held vertex
    (``free_index`` −1) enters with its value ``held[v]`` on the right-hand side."""
    diag[:] = 0.0
    off[:] = 0.0
    rhs[:] = 0.0
    n_rows, b = ji.shape[1], ji.shape[2]
    t = np.empty(n_rows)
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
        for u in range(b):
            for m in range(n_rows):
                if fi >= 0:
                    rhs[fi, u] += ji[e, m, u] * t[m]
                if fj >= 0:
                    rhs[fj, u] += jj[e, m, u] * t[m]
            for w in range(b):
                sii, sij, sjj = 0.0, 0.0, 0.0
                for m in range(n_rows):
                    sii += ji[e, m, u] * ji[e, m, w]
                    sij += ji[e, m, u] * jj[e, m, w]
                    sjj += jj[e, m, u] * jj[e, m, w]
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
