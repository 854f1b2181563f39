"""Input validation shared by every public function (private module).

Each helper raises a :class:`~wheelbase.errors.WheelbaseError` subclass whose message names the
parameter, the unit, what is allowed and what was given.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from wheelbase.errors import ConfigError, InputError

__all__ = [
    "as_float_array",
    "check_choice",
    "finite",
    "nonnegative",
    "positive",
]


def finite(name: str, value: float, unit: str = "", error: type[Exception] = ConfigError) -> float:
    """Return ``value`` as a float, or raise if it is not a finite real number."""
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise error(f"{name} must be a real number{_unit(unit)} (got {value!r})") from None
    if not math.isfinite(number):
        raise error(f"{name} must be finite{_unit(unit)} (got {number})")
    return number


def positive(name: str, value: float, unit: str = "") -> float:
    """Return ``value`` as a float, or raise ConfigError unless it is finite and > 0."""
    number = finite(name, value, unit)
    if number <= 0.0:
        raise ConfigError(f"{name} must be > 0{_unit(unit)} (got {number:g})")
    return number


def nonnegative(name: str, value: float, unit: str = "") -> float:
    """Return ``value`` as a float, or raise ConfigError unless it is finite and >= 0."""
    number = finite(name, value, unit)
    if number < 0.0:
        raise ConfigError(f"{name} must be >= 0{_unit(unit)} (got {number:g})")
    return number


def check_choice(name: str, value: str, allowed: Sequence[str]) -> str:
    """Return ``value`` if it is one of ``allowed``, else raise ConfigError listing them."""
    if value not in allowed:
        raise ConfigError(f"unknown {name} {value!r}; allowed: {', '.join(map(repr, allowed))}")
    return value


def as_float_array(
    name: str,
    value: object,
    last_dim: int | None = None,
    *,
    min_ndim: int = 0,
    max_ndim: int | None = None,
) -> np.ndarray:
    """Convert ``value`` to a finite float64 array, checking the size of its last axis.

    Raises
    ------
    InputError
        If the value is not numeric, not finite, or has the wrong shape.
    """
    try:
        array = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise InputError(f"{name} must be numeric (got {type(value).__name__})") from None
    if array.ndim < min_ndim or (max_ndim is not None and array.ndim > max_ndim):
        allowed = f"{min_ndim}..{max_ndim}" if max_ndim is not None else f">= {min_ndim}"
        raise InputError(f"{name} must have {allowed} dimensions (got shape {array.shape})")
    if last_dim is not None and (array.ndim == 0 or array.shape[-1] != last_dim):
        raise InputError(f"{name} must have shape (..., {last_dim}) (got shape {array.shape})")
    if not np.all(np.isfinite(array)):
        raise InputError(f"{name} must be finite (got NaN or inf)")
    return array


def _unit(unit: str) -> str:
    return f" {unit}" if unit else ""
