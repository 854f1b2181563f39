"""The sparse block Cholesky factorisation against dense linear algebra."""

import numpy as np
import pytest

from wheelbase.errors import ConfigError
from wheelbase.mapping.block_cholesky import BlockCholesky


def _random_system(rng, n, b, extra):
    """A chain of n vertices plus random pairs (repeats, both orders, self pairs), and a
    positive definite matrix on that pattern: Σ JᵀJ over pairs plus a ridge."""
    chain = np.column_stack([np.arange(n - 1), np.arange(1, n)])
    pairs = np.vstack([chain, rng.integers(0, n, (extra, 2))])
    chol = BlockCholesky(n, pairs)
    diag = np.zeros((n, b, b))
    off = np.zeros((chol.n_off, b, b))
    for v in range(n):
        a = rng.normal(size=(b, b))
        diag[v] = a.T @ a + 0.1 * np.eye(b)
    for e, (i, j) in enumerate(pairs):
        ji, jj = rng.normal(size=(b, b)), rng.normal(size=(b, b))
        if i == j:
            diag[i] += (ji + jj).T @ (ji + jj)
            continue
        diag[i] += ji.T @ ji
        diag[j] += jj.T @ jj
        off[chol.pair_slot[e]] += ji.T @ jj if chol.pair_upper[e] else jj.T @ ji
    return chol, diag, off


@pytest.mark.parametrize("b", [1, 2, 3])
def test_solves_equal_dense_solves(b):
    rng = np.random.default_rng(b)
    for n in (1, 2, 7, 40):
        chol, diag, off = _random_system(rng, n, b, extra=2 * n)
        dense = chol.to_dense(diag, off)
        np.testing.assert_array_equal(dense, dense.T)
        rhs = rng.normal(size=(n, b))
        assert chol.factor(diag, off)
        expected = np.linalg.solve(dense, rhs.ravel()).reshape(n, b)
        np.testing.assert_allclose(chol.solve(rhs), expected, rtol=1e-9, atol=1e-10)
        damping = rng.uniform(0.0, 2.0, (n, b))
        assert chol.factor(diag, off, damping)
        expected = np.linalg.solve(dense + np.diag(damping.ravel()), rhs.ravel()).reshape(n, b)
        np.testing.assert_allclose(chol.solve(rhs), expected, rtol=1e-9, atol=1e-10)


def test_fill_is_no_more_than_the_natural_orders():
    # a grid graph: minimum degree beats the row-by-row order's band
    side = 15
    idx = np.arange(side * side).reshape(side, side)
    pairs = np.vstack([np.column_stack([idx[:, :-1].ravel(), idx[:, 1:].ravel()]),
                       np.column_stack([idx[:-1].ravel(), idx[1:].ravel()])])  # fmt: skip
    chol = BlockCholesky(side * side, pairs)
    diag = np.broadcast_to(5.0 * np.eye(1), (side * side, 1, 1)).copy()
    off = -np.ones((chol.n_off, 1, 1))
    assert chol.factor(diag, off)
    natural = np.linalg.cholesky(chol.to_dense(diag, off))
    assert chol.fill_blocks <= np.count_nonzero(np.abs(np.tril(natural, -1)) > 1e-14)


def test_singular_and_indefinite_matrices_are_refused():
    # vertex 2 has no edge and a zero block: singular
    chol = BlockCholesky(3, np.array([[0, 1]]))
    diag = np.zeros((3, 3, 3))
    diag[0] = diag[1] = 2.0 * np.eye(3)
    off = np.zeros((1, 3, 3))
    assert not chol.factor(diag, off)
    with pytest.raises(ConfigError, match="factor"):
        chol.solve(np.ones((3, 3)))
    # a Laplacian (connected, nothing held): singular to rounding, refused as well
    chol = BlockCholesky(4, np.array([[0, 1], [1, 2], [2, 3], [3, 0]]))
    diag = np.broadcast_to(2.0 * np.eye(2), (4, 2, 2)).copy()
    off = np.broadcast_to(-np.eye(2), (chol.n_off, 2, 2)).copy()
    assert not chol.factor(diag, off)
    # and the same matrix with a ridge is fine; a failure leaves the workspace clean
    assert chol.factor(diag, off, np.full((4, 2), 1e-3))
    assert not chol.factor(-diag, off)
    assert chol.factor(diag, off, np.full((4, 2), 1e-3))
    dense = chol.to_dense(diag, off) + 1e-3 * np.eye(8)
    rhs = np.arange(8.0).reshape(4, 2)
    np.testing.assert_allclose(chol.solve(rhs).ravel(), np.linalg.solve(dense, rhs.ravel()))


def test_inputs_are_checked():
    with pytest.raises(ConfigError, match="pairs"):
        BlockCholesky(2, np.array([[0, 2]]))
    chol = BlockCholesky(2, np.array([[0, 1]]))
    with pytest.raises(ConfigError, match="diag"):
        chol.factor(np.zeros((3, 2, 2)), np.zeros((1, 2, 2)))
