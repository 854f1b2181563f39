"""Particle-set tools: low-variance resampling, the KLD-sampling bound, clusters of particles.

Low-variance resampling (Thrun, Burgard and Fox, Table 4.4)
    One random offset r ∈ [0, 1/n) and the n points r + k/n on the cumulative weights pick the
    new particles: O(n), and a set of equal weights comes back unchanged.
KLD sampling
    (Fox, "Adapting the sample size in particle filters through KLD-sampling", IJRR 2003;
    the book's Table 8.4.) With k histogram bins occupied by the particles, n = (k −
    1)/(2ε)·(1 − 2/(9(k − 1)) + √(2/(9(k − 1)))·z_{1−δ})³ particles keep the KL divergence
    between the particle set and the true posterior below ε with probability 1 − δ. Fox
    draws particles one by one until n exceeds the bound for the bins they fill; here the
    bound is met for the *expected* number of bins that n draws from the weighted set fill,
    k(n) = Σ_b 1 − (1 − w_b)^n (w_b the weight in bin b), which fixes n before one
    low-variance pass draws them. (Nav2 passes its ``pf_z`` = 0.99 as z itself; here z =
    Φ⁻¹(1 − δ), 2.33 for δ = 0.01.)
Clusters
    The occupied bins (x, y, θ), connected through faces, edges and corners and across the ±π
    cut, form clusters, as the k-d tree of Nav2's AMCL does; each has its weight, weighted mean
    (circular in θ) and covariance.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import ndimage, special

from wheelbase.geometry import wrap_angle

__all__ = ["Cluster", "clusters", "kld_particles", "low_variance_resample"]


def low_variance_resample(weights: np.ndarray, n: int, rng: np.random.Generator) -> np.ndarray:
    """Indices of ``n`` particles drawn by low-variance (systematic) resampling.

    Parameters
    ----------
    weights : numpy.ndarray, shape (P,)
        Normalised weights (sum 1).
    n : int
        Number of particles to draw, >= 1.
    rng : numpy.random.Generator
        Source of the one random offset.

    Returns
    -------
    numpy.ndarray of int, shape (n,)

    Examples
    --------
    >>> low_variance_resample(np.full(4, 0.25), 4, np.random.default_rng(0)).tolist()
    [0, 1, 2, 3]
    """
    cumulative = np.cumsum(weights)
    cumulative[-1] = 1.0  # rounding must not leave the last points unpicked
    points = (rng.random() + np.arange(n)) / n
    return np.minimum(np.searchsorted(cumulative, points, side="right"), weights.size - 1)


def _bin_keys(particles: np.ndarray, bin_size: tuple[float, float, float]) -> np.ndarray:
    cells = np.floor(particles[:, :2] / np.asarray(bin_size[:2])).astype(np.int64)
    n_theta = max(1, round(2.0 * math.pi / bin_size[2]))
    theta = np.floor((particles[:, 2] + math.pi) / (2.0 * math.pi) * n_theta).astype(np.int64)
    return np.column_stack([cells, np.mod(theta, n_theta)])


def _kld_bound(k: np.ndarray | float, epsilon: float, z: float) -> np.ndarray:
    k = np.asarray(k, dtype=np.float64)
    km1 = np.maximum(k - 1.0, 1e-12)
    b = 2.0 / (9.0 * km1)
    return np.where(k > 1.0, km1 / (2.0 * epsilon) * (1.0 - b + np.sqrt(b) * z) ** 3, 0.0)


def kld_particles(
    particles: np.ndarray,
    weights: np.ndarray,
    bin_size: tuple[float, float, float],
    epsilon: float,
    delta: float,
    min_particles: int,
    max_particles: int,
    random_fraction: float = 0.0,
    random_bins: float = 0.0,
) -> int:
    """Number of particles the KLD bound asks for (module docstring).

    Parameters
    ----------
    particles : numpy.ndarray, shape (P, 3)
        The weighted particle set.
    weights : numpy.ndarray, shape (P,)
        Normalised weights.
    bin_size : tuple of float
        Histogram bins (x [m], y [m], θ [rad]).
    epsilon : float
        Bound on the KL divergence, > 0.
    delta : float
        Probability of exceeding it, in (0, 1).
    min_particles, max_particles : int
        Limits of the answer.
    random_fraction : float
        Fraction of the drawn particles that will be replaced by random poses (augmented MCL),
        in [0, 1]: as in Fox's sampling, the bins they fill count, so injection grows the set.
    random_bins : float
        Bins the random poses are spread over (uniformly), > 0 when ``random_fraction`` is.

    Returns
    -------
    int
    """
    keys = _bin_keys(particles, bin_size)
    keys -= keys.min(axis=0)
    span = keys.max(axis=0) + 1
    flat = (keys[:, 0] * span[1] + keys[:, 1]) * span[2] + keys[:, 2]  # one integer per bin
    _, inverse = np.unique(flat, return_inverse=True)
    bin_weight = np.bincount(inverse, weights=weights)
    bin_weight = bin_weight[bin_weight > 0.0]
    z = float(special.ndtri(1.0 - delta))
    log_miss = np.log1p(-np.minimum(bin_weight * (1.0 - random_fraction), 1.0 - 1e-16))
    n = min_particles
    for _ in range(100):  # the sequence increases to the fixed point; a few steps suffice
        expected_bins = np.sum(-np.expm1(n * log_miss))
        if random_fraction > 0.0:  # random draws fill the bins of the free space
            expected_bins += random_bins * -math.expm1(-n * random_fraction / random_bins)
        wanted = math.ceil(float(_kld_bound(expected_bins, epsilon, z)))
        wanted = min(max(wanted, min_particles), max_particles)
        if wanted <= n:
            break
        n = wanted
    return n


@dataclass(frozen=True)
class Cluster:
    """A connected group of occupied bins of a particle set.

    Attributes
    ----------
    weight : float
        Total weight of its particles.
    mean : numpy.ndarray, shape (3,)
        Weighted mean pose (θ as the weighted circular mean).
    cov : numpy.ndarray, shape (3, 3)
        Weighted covariance (θ deviations wrapped about the mean).
    count : int
        Number of particles.
    """

    weight: float
    mean: np.ndarray
    cov: np.ndarray
    count: int


def _weighted_pose(particles: np.ndarray, weights: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    w = weights / weights.sum()
    theta = math.atan2(float(w @ np.sin(particles[:, 2])), float(w @ np.cos(particles[:, 2])))
    mean = np.array([w @ particles[:, 0], w @ particles[:, 1], theta])
    dev = particles - mean
    dev[:, 2] = wrap_angle(dev[:, 2])
    return mean, (dev * w[:, None]).T @ dev


def clusters(
    particles: np.ndarray, weights: np.ndarray, bin_size: tuple[float, float, float]
) -> list[Cluster]:
    """The clusters of a weighted particle set, heaviest first (module docstring).

    Parameters
    ----------
    particles : numpy.ndarray, shape (P, 3)
        Particle poses.
    weights : numpy.ndarray, shape (P,)
        Weights (normalised or not).
    bin_size : tuple of float
        Histogram bins (x [m], y [m], θ [rad]).

    Returns
    -------
    list of Cluster
    """
    keys = _bin_keys(particles, bin_size)
    lo = keys[:, :2].min(0)
    n_theta = max(1, round(2.0 * math.pi / bin_size[2]))
    shape = (*(keys[:, :2].max(0) - lo + 1), n_theta)
    occupied = np.zeros(shape, bool)
    index = (keys[:, 0] - lo[0], keys[:, 1] - lo[1], keys[:, 2])
    occupied[index] = True
    labels, count = ndimage.label(occupied, structure=np.ones((3, 3, 3), bool))
    if n_theta > 2 and count > 1:  # join labels that touch across the ±π cut
        parent = np.arange(count + 1)

        def root(a: int) -> int:
            while parent[a] != a:
                parent[a] = parent[parent[a]]
                a = parent[a]
            return a

        first, last = labels[..., 0], labels[..., -1]
        padded = np.pad(last, 1)
        for dx in (-1, 0, 1):
            for dy in (-1, 0, 1):
                near = padded[1 + dx : 1 + dx + shape[0], 1 + dy : 1 + dy + shape[1]]
                for a, b in zip(first[(first > 0) & (near > 0)], near[(first > 0) & (near > 0)],
                                strict=True):  # fmt: skip
                    parent[root(int(a))] = root(int(b))
        labels = np.array([root(a) for a in range(count + 1)])[labels]
    particle_label = labels[index]
    out = []
    for label in np.unique(particle_label):
        members = particle_label == label
        w = weights[members]
        if w.sum() <= 0.0:
            continue
        mean, cov = _weighted_pose(particles[members], w)
        out.append(Cluster(float(w.sum()), mean, cov, int(members.sum())))
    total = sum(c.weight for c in out)
    out = [Cluster(c.weight / total, c.mean, c.cov, c.count) for c in out]
    return sorted(out, key=lambda c: -c.weight)
