"""The compiled twin of :func:`wheelbase.geometry.wrap_angle`, for Numba kernels.

:func:`wrap_angle_scalar` wraps one angle to (−π, π], the interval of
:func:`~wheelbase.geometry.wrap_angle` (−π itself becomes +π), by arithmetic: an angle already
inside is returned as it is, any other is moved by whole turns (no trigonometric call, a few
nanoseconds inside the Hybrid A* search and the batch integrators). The two agree to the
rounding of the angle itself (|difference| ≤ 4e-16·|angle| + 1e-15 rad, tested). Kept apart from
:mod:`wheelbase.geometry` so that importing it does not load Numba.
"""

from __future__ import annotations

import math

import numba

__all__ = ["wrap_angle_scalar"]

_TWO_PI = 2.0 * math.pi


@numba.njit(cache=True, inline="always")
def wrap_angle_scalar(angle: float) -> float:
    """One angle [rad] wrapped to (−π, π] (compiled; callable from Python too).

    Parameters
    ----------
    angle : float
        The angle [rad]; NaN stays NaN.

    Returns
    -------
    float
        The angle moved by whole turns into (−π, π].

    Examples
    --------
    >>> wrap_angle_scalar(-math.pi) == math.pi
    True
    """
    if -math.pi < angle <= math.pi:
        return angle
    wrapped = angle - _TWO_PI * math.ceil((angle - math.pi) / _TWO_PI)
    # the quotient's rounding may land a whole turn off at the interval's ends
    if wrapped <= -math.pi:
        wrapped += _TWO_PI
    elif wrapped > math.pi:
        wrapped -= _TWO_PI
    return wrapped
