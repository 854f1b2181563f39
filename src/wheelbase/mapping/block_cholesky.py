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
    # relax=1, panel_size=1: no supernodes for a factor that only the ordering is wanted of
    lu = splu(laplacian.tocsc(), permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0, relax=1,
              panel_size=1, options={"SymmetricMode": True})  # fmt: skip
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
    # each row's pattern in a topological order (Davis's cs_ereach: every path up the tree is
    # pushed whole in front of the paths found before it, so that a column comes before the
    # columns it updates); no sort, whose generic Numba code took seconds to compile
    row_cols = np.empty(row_ptr[n], np.int64)
    path = np.empty(n, np.int64)
    col_count = np.zeros(n, np.int64)
    mark[:] = -1
    for k in range(n):
        mark[k] = k
        top = row_ptr[k + 1]
        for p in range(a_ptr[k], a_ptr[k + 1]):
            i = a_rows[p]
            length = 0
            while mark[i] != k:
                mark[i] = k
                path[length] = i
                length += 1
                col_count[i] += 1
                i = parent[i]
            while length > 0:
                length -= 1
                top -= 1
                row_cols[top] = path[length]
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


_KERNELS: dict[int, tuple] = {}


def _kernels(b: int) -> tuple:
    """The numeric kernels (factor, substitute) for b×b blocks, b a compile-time constant
    (Numba unrolls the block loops); compiled once per b and cached on disk."""
    if b not in _KERNELS:
        _KERNELS[b] = _make_kernels(b)
    return _KERNELS[b]


def _make_kernels(B: int) -> tuple:  # B: the block size, a constant of the kernels
    @numba.njit(cache=True)
    def factor(a_ptr, a_rows, a_diag, a_off, damping, row_ptr, row_cols, row_slot, col_ptr,
               col_rows, l_diag, l_off, inv, x):  # pragma: no cover - compiled  # fmt: skip
        """Up-looking block Cholesky of A + diag(damping) into (l_diag, l_off); False on a
        non-positive pivot (at most 1e-13 of the diagonal before elimination); inv (n, B)
        receives the pivots' reciprocals. x (n, B, B) is a zeroed workspace, left zeroed."""
        n = a_diag.shape[0]
        y = np.empty((B, B))
        d = np.empty((B, B))
        ref = np.empty(B)
        for k in range(n):
            for p in range(a_ptr[k], a_ptr[k + 1]):  # scatter column k of A (rows < k)
                q = a_rows[p]
                for r in range(B):
                    for c in range(B):
                        x[q, r, c] += a_off[p, r, c]
            for r in range(B):
                for c in range(B):
                    d[r, c] = a_diag[k, r, c]
                d[r, r] += damping[k, r]
                ref[r] = abs(d[r, r])
            for t in range(row_ptr[k], row_ptr[k + 1]):
                i = row_cols[t]
                # y = L_ii⁻¹ x_i (forward substitution, column by column); y = L[k, i]ᵀ
                for c in range(B):
                    for r in range(B):
                        s = x[i, r, c]
                        for m in range(r):
                            s -= l_diag[i, r, m] * y[m, c]
                        y[r, c] = s * inv[i, r]
                for r in range(B):
                    for c in range(B):
                        x[i, r, c] = 0.0
                for p in range(col_ptr[i], row_slot[t]):  # rows q of column i, i < q < k
                    q = col_rows[p]
                    for r in range(B):
                        for c in range(B):
                            s = 0.0
                            for m in range(B):
                                s += l_off[p, r, m] * y[m, c]
                            x[q, r, c] -= s
                slot = row_slot[t]
                for r in range(B):
                    for c in range(B):
                        l_off[slot, r, c] = y[c, r]
                        s = 0.0
                        for m in range(B):
                            s += y[m, r] * y[m, c]
                        d[r, c] -= s
            # the pivot block: dense Cholesky d = L_kk L_kkᵀ
            ok = True
            for j in range(B):
                s = d[j, j]
                for m in range(j):
                    s -= l_diag[k, j, m] * l_diag[k, j, m]
                if not (s > _PIVOT_RTOL * ref[j] and s > 0.0):
                    ok = False
                    break
                l_diag[k, j, j] = np.sqrt(s)
                inv[k, j] = 1.0 / l_diag[k, j, j]
                for r in range(j + 1, B):
                    s = d[r, j]
                    for m in range(j):
                        s -= l_diag[k, r, m] * l_diag[k, j, m]
                    l_diag[k, r, j] = s * inv[k, j]
                for r in range(j):
                    l_diag[k, r, j] = 0.0
            if not ok:
                for p in range(a_ptr[k], a_ptr[k + 1]):  # leave the workspace zeroed
                    x[a_rows[p]] = 0.0
                for t in range(row_ptr[k], row_ptr[k + 1]):
                    x[row_cols[t]] = 0.0
                return False
        return True

    @numba.njit(cache=True)
    def substitute(l_diag, l_off, inv, col_ptr, col_rows, rhs):  # pragma: no cover - compiled
        """Solve L Lᵀ z = rhs in place (rhs of shape (n, B))."""
        n = l_diag.shape[0]
        for i in range(n):  # L y = rhs, column-oriented
            for r in range(B):
                s = rhs[i, r]
                for m in range(r):
                    s -= l_diag[i, r, m] * rhs[i, m]
                rhs[i, r] = s * inv[i, r]
            for p in range(col_ptr[i], col_ptr[i + 1]):
                q = col_rows[p]
                for r in range(B):
                    s = 0.0
                    for m in range(B):
                        s += l_off[p, r, m] * rhs[i, m]
                    rhs[q, r] -= s
        for i in range(n - 1, -1, -1):  # Lᵀ z = y
            for p in range(col_ptr[i], col_ptr[i + 1]):
                q = col_rows[p]
                for r in range(B):
                    s = 0.0
                    for m in range(B):
                        s += l_off[p, m, r] * rhs[q, m]
                    rhs[i, r] -= s
            for r in range(B - 1, -1, -1):
                s = rhs[i, r]
                for m in range(r + 1, B):
                    s -= l_diag[i, m, r] * rhs[i, m]
                rhs[i, r] = s * inv[i, r]

    return factor, substitute


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
            self._inv = np.zeros((self.n_nodes, b))  # reciprocals of L's diagonal
            self._x = np.zeros((self.n_nodes, b, b))

    def factor(self, diag: np.ndarray, off: np.ndarray, damping: np.ndarray | None = None) -> bool:
        """Factor A + diag(damping) numerically; False if it is not positive definite.

        Parameters
        ----------
        diag : numpy.ndarray, shape (n_nodes, b, b)
            Diagonal blocks, vertex order.
        off : numpy.ndarray, shape (n_off, b, b)
            Off-diagonal blocks at ``pair_slot``, each the block above the diagonal in the
            factor's order (see ``pair_upper``).
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
        self._factored = _kernels(b)[0](
            self._a_ptr, self._a_rows, diag[order], np.ascontiguousarray(off, np.float64),
            np.ascontiguousarray(damping, np.float64)[order], self._row_ptr, self._row_cols,
            self._row_slot, self._col_ptr, self._col_rows, self._l_diag, self._l_off, self._inv,
            self._x,
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
        _kernels(self._block)[1](
            self._l_diag, self._l_off, self._inv, self._col_ptr, self._col_rows, z
        )
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
