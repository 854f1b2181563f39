"""Counter-based random streams: a robot's random numbers as a function of what it is and when.

Every random number of the closed loop (encoder noise, wheel slip, lidar and landmark noise,
a particle filter's draws) comes from a generator made for the occasion from three integers:
the robot's seed, the stream (which source of randomness) and a counter (the step, or a block
of steps). Nothing random is carried from step to step, so :meth:`Engine.step
<wheelbase.sim.Engine.step>` is a function of the state it is given: stepping one saved state
twice gives the same result (branching, replay, learning rollouts), and robot ``i`` of a batch
draws what the single run with seed ``i`` draws.

The three integers seed a :class:`numpy.random.SeedSequence` as its entropy and spawn key
(the key is mixed in after the seed, so (seed, stream, counter) triples never collide, as
plain lists of words can: ``[s, 1]`` and ``[s, 1, 0]`` seed the same generator). A generator
serves the draws of NumPy (normals, binomials, choices) outside the kernels; the world's agents,
which draw inside Numba kernels, hash their counters to uniforms instead
(:mod:`wheelbase.world.counter_rng`), on the same principle.
"""

from __future__ import annotations

import numpy as np

__all__ = ["counter_stream"]


def counter_stream(seed: int, stream: int, counter: int) -> np.random.Generator:
    """The generator of robot ``seed``'s source ``stream`` at ``counter`` (module docstring).

    Parameters
    ----------
    seed : int
        The robot's seed, >= 0.
    stream : int
        Which source of randomness (a constant of the module that draws), >= 0.
    counter : int
        The step (or block of steps) the numbers are for, >= 0.

    Returns
    -------
    numpy.random.Generator

    Examples
    --------
    >>> a = counter_stream(7, 1, 42).normal()
    >>> a == counter_stream(7, 1, 42).normal() != counter_stream(7, 1, 43).normal()
    True
    """
    sequence = np.random.SeedSequence(int(seed), spawn_key=(int(stream), int(counter)))
    return np.random.default_rng(sequence)
