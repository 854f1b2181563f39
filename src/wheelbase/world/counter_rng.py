"""Counter-based random numbers: a uniform draw is a hash of (seed, stream, step, agent, k).

A world's step draws its random numbers (new goals) from SplitMix64 (G. Steele, D. Lea and
C. Flood, "Fast splittable pseudorandom number generators", OOPSLA 2014) applied to the
counters, not from a generator that carries state, so ``World.step`` is a pure function of its
arguments: the same state stepped twice draws the same numbers, and world ``b`` of a batch
draws what it draws alone.
"""

from __future__ import annotations

import numba
import numpy as np

__all__ = ["STREAM_DIRECTION", "STREAM_GOAL", "STREAM_ORCA", "STREAM_SPAWN", "counter_uniform"]

STREAM_GOAL = 1
"""Stream of the goal draws (during steps and at the start)."""
STREAM_SPAWN = 2
"""Stream of the start positions and the lattice order (:meth:`World.start`)."""
STREAM_DIRECTION = 3
"""Stream of the first headings of ``straight`` agents and first waypoints."""
STREAM_ORCA = 4
"""Stream of ORCA's perturbation of the preferred velocities."""

_GOLDEN = np.uint64(0x9E3779B97F4A7C15)
_M1 = np.uint64(0xBF58476D1CE4E5B9)
_M2 = np.uint64(0x94D049BB133111EB)


@numba.njit(cache=True, inline="always")
def _mix(z):
    """The SplitMix64 finaliser: a bijection of uint64 with good avalanche."""
    z = (z ^ (z >> np.uint64(30))) * _M1
    z = (z ^ (z >> np.uint64(27))) * _M2
    return z ^ (z >> np.uint64(31))


@numba.njit(cache=True)
def counter_uniform(seed, stream, step, agent, k):
    """A uniform number in [0, 1) determined by the five integer counters.

    Parameters
    ----------
    seed, stream, step, agent, k : int
        The world's seed, the purpose, the step counter, the agent and the draw within the
        step.

    Returns
    -------
    float
        ``(h >> 11) · 2⁻⁵³`` of the hash h: 53 random bits.
    """
    z = _mix(np.uint64(seed) + _GOLDEN * np.uint64(stream + 1))
    z = _mix(z + _GOLDEN * np.uint64(step + 1))
    z = _mix(z + _GOLDEN * np.uint64(agent + 1))
    z = _mix(z + _GOLDEN * np.uint64(k + 1))
    return float(z >> np.uint64(11)) * (1.0 / 9007199254740992.0)
