"""Sparse block Cholesky factorisation for the normal equations of graphs (pose graphs, SLAM).

The normal matrix H of a least-squares problem on a graph has one dense b×b block per vertex
(the diagonal) and one per pair of vertices an edge joins; everything else is zero. Its Cholesky
factor H = L·Lᵀ is computed here on that block structure:

* the **symbolic** part, done once per graph: a fill-reducing order of the vertices (SuperLU's
  multiple minimum degree on the vertex graph's Laplacian, 3²-times smaller than H), the
  elimination tree (Liu's algorithm with path compression) and the pattern of every row of L
  (the "row subtrees" of the tree: Davis, *Direct Methods for Sparse Linear Systems*, SIAM
  2006, §4.1-4.3);
* the **numeric** part, each time the values change: the up-looking factorisation (Davis §4.7),
  row k of L by one sparse triangular solve over the precomputed pattern, every scalar of the
  textbook algorithm a b×b block, every division a small dense Cholesky; then the forward and
  backward substitutions. Both are Numba kernels (``cache=True``) without a call into BLAS.

A non-positive pivot (a block of H left singular by its edges, relative to 1e-13 of its own
diagonal) makes :meth:`BlockCholesky.factor` return ``False`` rather than a factor of a
matrix that is not positive definite.
"""

from __future__ import annotations

import numba
import numpy as np
from scipy import sparse
from scipy.sparse.linalg import splu

from wheelbase.errors import ConfigError

__all__ = ["BlockCholesky"]

_PIVOT_RTOL = 1e-13  # a pivot below this fraction of its block's diagonal counts as zero


def _minimum_degree_order(n: int, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """new position of each vertex: SuperLU's minimum degree on the vertex graph's Laplacian
    plus identity (positive definite, so that SuperLU's symmetric mode factors it as it is)."""
    if n <= 1:
        return np.arange(n)
    laplacian = sparse.coo_matrix(
        (np.full(2 * a.size, -1.0), (np.concatenate([a, b]), np.concatenate([b, a]))),
        shape=(n, n),
    ).tocsc()
    laplacian = laplacian + sparse.diags(1.0 - np.asarray(laplacian.sum(0)).ravel())
    lu = splu(laplacian.tocsc(), permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
              options={"SymmetricMode": True})  # fmt: skip
    return np.asarray(lu.perm_c, dtype=np.int64)


@numba.njit(cache=True)
def _symbolic(n, a_ptr, a_rows):  # pragma: no cover - compiled
    """Elimination tree and row patterns of L from the strict upper pattern of A (CSC)."""
    parent = np.full(n, -1, np.int64)
    ancestor = np.full(n, -1, np.int64)
    for k in range(n):
        for p in range(a_ptr[k], a_ptr[k + 1]):
            i = a_rows[p]
            while i != -1 and i < k:
                nxt = ancestor[i]
                ancestor[i] = k
                if nxt == -1:
                    parent[i] = k
                i = nxt
    mark = np.full(n, -1, np.int64)
    row_ptr = np.zeros(n + 1, np.int64)
    for k in range(n):  # sizes of the row patterns (the row subtrees)
        mark[k] = k
        count = 0
        for p in range(a_ptr[k], a_ptr[k + 1]):
            i = a_rows[p]
            while mark[i] != k:
                mark[i] = k
                count += 1
                i = parent[i]
        row_ptr[k + 1] = row_ptr[k] + count
    row_cols = np.empty(row_ptr[n], np.int64)
    col_count = np.zeros(n, np.int64)
    mark[:] = -1
    for k in range(n):
        mark[k] = k
        top = row_ptr[k]
        for p in range(a_ptr[k], a_ptr[k + 1]):
            i = a_rows[p]
            while mark[i] != k:
                mark[i] = k
                row_cols[top] = i
                top += 1
                col_count[i] += 1
                i = parent[i]
        row_cols[row_ptr[k] : row_ptr[k + 1]] = np.sort(row_cols[row_ptr[k] : row_ptr[k + 1]])
    col_ptr = np.zeros(n + 1, np.int64)
    for i in range(n):
        col_ptr[i + 1] = col_ptr[i] + col_count[i]
    col_rows = np.empty(col_ptr[n], np.int64)
    row_slot = np.empty(row_ptr[n], np.int64)  # where L[k, i] of row k's pattern is stored
    fill = col_ptr[:-1].copy()
    for k in range(n):  # rows in increasing order: each column's rows come out sorted
        for t in range(row_ptr[k], row_ptr[k + 1]):
            i = row_cols[t]
            row_slot[t] = fill[i]
            col_rows[fill[i]] = k
            fill[i] += 1
    return parent, row_ptr, row_cols, row_slot, col_ptr, col_rows


@numba.njit(cache=True)
def _dense_cholesky(d, out, ref):  # pragma: no cover - compiled
    """out = the lower Cholesky factor of the b×b block d; False if d is not positive definite
    (a pivot at most 1e-13 of ``ref``, the diagonal of the block before elimination)."""
    b = d.shape[0]
    for j in range(b):
        s = d[j, j]
        for m in range(j):
            s -= out[j, m] * out[j, m]
        if not s > _PIVOT_RTOL * ref[j] or not s > 0.0:
            return False
        out[j, j] = np.sqrt(s)
        for i in range(j + 1, b):
            t = d[i, j]
            for m in range(j):
                t -= out[i, m] * out[j, m]
            out[i, j] = t / out[j, j]
        for i in range(j):
            out[i, j] = 0.0
    return True


@numba.njit(cache=True)
def _factor(a_ptr, a_rows, a_diag, a_off, damping, row_ptr, row_cols, row_slot, col_ptr,
            col_rows, l_diag, l_off, x, d):  # pragma: no cover - compiled  # fmt: skip
    """Up-looking block Cholesky of A + diag(damping) into (l_diag, l_off); False on a
    non-positive pivot. x (n, b, b) is a zeroed workspace and left zeroed; d is (b, b)."""
    n, b = a_diag.shape[0], a_diag.shape[1]
    y = np.empty((b, b))
    ref = np.empty(b)
    for k in range(n):
        for p in range(a_ptr[k], a_ptr[k + 1]):  # scatter column k of A (rows < k)
            x[a_rows[p]] += a_off[p]
        d[:, :] = a_diag[k]
        for u in range(b):
            d[u, u] += damping[k, u]
            ref[u] = abs(d[u, u])
        for t in range(row_ptr[k], row_ptr[k + 1]):
            i = row_cols[t]
            li = l_diag[i]
            xi = x[i]
            # y = L_ii⁻¹ x_i (forward substitution, column by column); y = L[k, i]ᵀ
            for c in range(b):
                for r in range(b):
                    s = xi[r, c]
                    for m in range(r):
                        s -= li[r, m] * y[m, c]
                    y[r, c] = s / li[r, r]
            xi[:, :] = 0.0
            for p in range(col_ptr[i], row_slot[t]):  # rows r of column i with i < r < k
                xr = x[col_rows[p]]
                lp = l_off[p]
                for r in range(b):
                    for c in range(b):
                        s = 0.0
                        for m in range(b):
                            s += lp[r, m] * y[m, c]
                        xr[r, c] -= s
            lk = l_off[row_slot[t]]
            for r in range(b):
                for c in range(b):
                    lk[r, c] = y[c, r]
                    s = 0.0
                    for m in range(b):
                        s += y[m, r] * y[m, c]
                    d[r, c] -= s
        if not _dense_cholesky(d, l_diag[k], ref):
            for p in range(a_ptr[k], a_ptr[k + 1]):  # leave the workspace zeroed
                x[a_rows[p]] = 0.0
            for t in range(row_ptr[k], row_ptr[k + 1]):
                x[row_cols[t]] = 0.0
            return False
    return True


@numba.njit(cache=True)
def _substitute(l_diag, l_off, col_ptr, col_rows, rhs):  # pragma: no cover - compiled
    """Solve L Lᵀ z = rhs in place (rhs of shape (n, b))."""
    n, b = l_diag.shape[0], l_diag.shape[1]
    for i in range(n):  # L y = rhs, column-oriented
        li = l_diag[i]
        for r in range(b):
            s = rhs[i, r]
            for m in range(r):
                s -= li[r, m] * rhs[i, m]
            rhs[i, r] = s / li[r, r]
        for p in range(col_ptr[i], col_ptr[i + 1]):
            row = col_rows[p]
            for r in range(b):
                s = 0.0
                for m in range(b):
                    s += l_off[p, r, m] * rhs[i, m]
                rhs[row, r] -= s
    for i in range(n - 1, -1, -1):  # Lᵀ z = y
        for p in range(col_ptr[i], col_ptr[i + 1]):
            row = col_rows[p]
            for r in range(b):
                s = 0.0
                for m in range(b):
                    s += l_off[p, m, r] * rhs[row, m]
                rhs[i, r] -= s
        li = l_diag[i]
        for r in range(b - 1, -1, -1):
            s = rhs[i, r]
            for m in range(r + 1, b):
                s -= li[m, r] * rhs[i, m]
            rhs[i, r] = s / li[r, r]


class BlockCholesky:
    """The symbolic Cholesky factorisation of a graph's block normal matrix, reused for
    every numeric factorisation of matrices with that pattern.

    Parameters
    ----------
    n_nodes : int
        Number of unknown blocks (vertices), >= 0.
    pairs : numpy.ndarray, shape (P, 2)
        Vertex pairs with a nonzero off-diagonal block (an edge each; repeats, either order
        and pairs ``(i, i)`` allowed).

    Attributes
    ----------
    position : numpy.ndarray, shape (n_nodes,)
        The row-block of each vertex in the factor (its place in the fill-reducing order).
    pair_slot : numpy.ndarray, shape (P,)
        Index into the off-diagonal block array of each pair's block, -1 for ``(i, i)``.
    pair_upper : numpy.ndarray, shape (P,)
        True where the stored block is the (first, second) one of the pair, False where it is
        (second, first): blocks are stored above the diagonal, in the factor's order.
    n_off : int
        Number of distinct off-diagonal blocks.
    fill_blocks : int
        Off-diagonal blocks of L.

    Examples
    --------
    >>> import numpy as np
    >>> chol = BlockCholesky(3, np.array([[0, 1], [1, 2]]))
    >>> diag = np.broadcast_to(4.0 * np.eye(2), (3, 2, 2)).copy()
    >>> off = np.broadcast_to(-np.eye(2), (chol.n_off, 2, 2)).copy()
    >>> chol.factor(diag, off)
    True
    >>> dense = chol.to_dense(diag, off)
    >>> bool(np.allclose(dense @ chol.solve(np.ones((3, 2))).ravel(), 1.0))
    True
    """

    def __init__(self, n_nodes: int, pairs: np.ndarray) -> None:
        n = int(n_nodes)
        pairs = np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
        if n < 0 or (pairs.size and (pairs.min() < 0 or pairs.max() >= n)):
            raise ConfigError(f"pairs must index 0..{n - 1} (n_nodes = {n})")
        self.n_nodes = n
        off = pairs[:, 0] != pairs[:, 1]
        self.position = _minimum_degree_order(n, pairs[off, 0], pairs[off, 1])
        self._order = np.argsort(self.position)  # the vertex at each position
        pa, pb = self.position[pairs[:, 0]], self.position[pairs[:, 1]]
        low, high = np.minimum(pa, pb), np.maximum(pa, pb)
        # the strict upper pattern of A in CSC: column high, row low, unique
        key = high[off] * max(n, 1) + low[off]
        unique, inverse = np.unique(key, return_inverse=True)
        self.n_off = int(unique.size)
        self._a_rows = (unique % max(n, 1)).astype(np.int64)
        self._a_ptr = np.searchsorted(unique // max(n, 1), np.arange(n + 1)).astype(np.int64)
        self.pair_slot = np.full(pairs.shape[0], -1, np.int64)
        self.pair_slot[off] = inverse.ravel()
        self.pair_upper = pa <= pb
        (_, self._row_ptr, self._row_cols, self._row_slot, self._col_ptr,
         self._col_rows) = _symbolic(n, self._a_ptr, self._a_rows)  # fmt: skip
        self.fill_blocks = int(self._col_ptr[-1])
        self._block = 0
        self._factored = False

    def _workspace(self, b: int) -> None:
        if self._block != b:
            self._block = b
            self._l_diag = np.zeros((self.n_nodes, b, b))
            self._l_off = np.zeros((self.fill_blocks, b, b))
            self._x = np.zeros((self.n_nodes, b, b))
            self._d = np.zeros((b, b))

    def factor(self, diag: np.ndarray, off: np.ndarray, damping: np.ndarray | None = None) -> bool:
        """Factor A + diag(damping) numerically; False if it is not positive definite.

        Parameters
        ----------
        diag : numpy.ndarray, shape (n_nodes, b, b)
            Diagonal blocks, vertex order.
        off : numpy.ndarray, shape (n_off, b, b)
            Off-diagonal blocks at :attr:`pair_slot`, each the block above the diagonal in the
            factor's order (see :attr:`pair_upper`).
        damping : numpy.ndarray or None, shape (n_nodes, b)
            Added to the diagonals of the diagonal blocks (Levenberg–Marquardt), default none.

        Returns
        -------
        bool
        """
        diag = np.ascontiguousarray(diag, dtype=np.float64)
        b = diag.shape[-1]
        if diag.shape != (self.n_nodes, b, b) or off.shape != (self.n_off, b, b):
            raise ConfigError(
                f"factor needs diag ({self.n_nodes}, b, b) and off ({self.n_off}, b, b) "
                f"(got {diag.shape} and {off.shape})"
            )
        self._workspace(b)
        order = self._order
        damping = np.zeros((self.n_nodes, b)) if damping is None else damping
        self._factored = _factor(
            self._a_ptr, self._a_rows, diag[order], np.ascontiguousarray(off, np.float64),
            np.ascontiguousarray(damping, np.float64)[order], self._row_ptr, self._row_cols,
            self._row_slot, self._col_ptr, self._col_rows, self._l_diag, self._l_off,
            self._x, self._d,
        )  # fmt: skip
        return bool(self._factored)

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        """A⁻¹·rhs with the last successful :meth:`factor`.

        Parameters
        ----------
        rhs : numpy.ndarray, shape (n_nodes, b)
            Right-hand side, vertex order.

        Returns
        -------
        numpy.ndarray, shape (n_nodes, b)
        """
        if not self._factored:
            raise ConfigError("solve needs a successful factor() first")
        z = np.array(rhs, dtype=np.float64)[self._order]
        _substitute(self._l_diag, self._l_off, self._col_ptr, self._col_rows, z)
        return z[self.position]

    def to_dense(self, diag: np.ndarray, off: np.ndarray) -> np.ndarray:
        """The matrix A of these blocks as a dense (n·b, n·b) array in vertex order (tests).

        Parameters
        ----------
        diag : numpy.ndarray, shape (n_nodes, b, b)
            Diagonal blocks.
        off : numpy.ndarray, shape (n_off, b, b)
            Off-diagonal blocks (as :meth:`factor`).

        Returns
        -------
        numpy.ndarray
        """
        b = diag.shape[-1]
        order = self._order
        out = np.zeros((self.n_nodes * b, self.n_nodes * b))
        for v in range(self.n_nodes):
            out[v * b : (v + 1) * b, v * b : (v + 1) * b] = diag[v]
        for k in range(self.n_nodes):
            for p in range(self._a_ptr[k], self._a_ptr[k + 1]):
                r, c = order[self._a_rows[p]], order[k]
                out[r * b : (r + 1) * b, c * b : (c + 1) * b] = off[p]
                out[c * b : (c + 1) * b, r * b : (r + 1) * b] = off[p].T
        return out
