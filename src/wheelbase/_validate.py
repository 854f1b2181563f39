"""Input validation shared by every public function (private module).

Each helper raises a :class:`~wheelbase.errors.WheelbaseError` subclass whose message names the
parameter, the unit, what is allowed and what was given.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from wheelbase.errors import ConfigError, DataError, InputError

__all__ = [
    "as_float_array",
    "as_rng",
    "check_choice",
    "count_text",
    "finite",
    "flag",
    "integer",
    "nonnegative",
    "parse_angle",
    "positive",
    "read_text",
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


def integer(
    name: str,
    value: object,
    minimum: int | None = None,
    maximum: int | None = None,
    unit: str = "",
) -> int:
    """Return ``value`` as an int, or raise ConfigError unless it is a whole number in bounds.

    An integral float (``72.0``, as YAML may give it) is accepted; booleans, strings, NaN, inf
    and fractions are not. ``int(inf)`` would raise ``OverflowError`` and ``int("x")``
    ``ValueError``: this says instead what the parameter is and what it allows.
    """
    allowed = "an integer"
    if minimum is not None and maximum is not None:
        allowed += f" in [{minimum}, {maximum}]"
    elif minimum is not None:
        allowed += f" >= {minimum}"
    elif maximum is not None:
        allowed += f" <= {maximum}"
    whole = isinstance(value, (int, np.integer)) and not isinstance(value, (bool, np.bool_))
    integral = isinstance(value, (float, np.floating)) and math.isfinite(value)
    number = int(value) if whole or (integral and value == int(value)) else None
    if (
        number is None
        or (minimum is not None and number < minimum)
        or (maximum is not None and number > maximum)
    ):
        raise ConfigError(f"{name} must be {allowed}{_unit(unit)} (got {value!r})")
    return number


def flag(name: str, value: object) -> bool:
    """Return ``value`` if it is a boolean, else raise ConfigError (``bool("no")`` is True)."""
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    raise ConfigError(f"{name} must be true or false (got {value!r})")


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


def as_rng(rng: np.random.Generator | int | None) -> np.random.Generator:
    """A NumPy generator from a generator (returned as is), a seed, or None (fresh entropy).

    Parameters
    ----------
    rng : numpy.random.Generator, int or None
        The source of randomness or its seed.

    Returns
    -------
    numpy.random.Generator
    """
    if isinstance(rng, np.random.Generator):
        return rng
    if rng is not None and (isinstance(rng, bool) or not isinstance(rng, int | np.integer)):
        raise ConfigError(f"rng must be a numpy Generator, an integer seed or None (got {rng!r})")
    return np.random.default_rng(rng)


def read_text(
    path: Path, what: str, error: type[Exception] = DataError, label: str | None = None
) -> str:
    """The UTF-8 text of a file, or ``error`` naming it: unreadable, or not UTF-8.

    Parameters
    ----------
    path : pathlib.Path
        The file.
    what : str
        What the file is (``"Moving AI map"``), for the message.
    error : type
        The WheelbaseError subclass to raise.
    label : str, optional
        How to name the file in the message (default: its path).
    """
    try:
        return Path(path).read_text(encoding="utf-8")
    except UnicodeDecodeError as exc:
        byte = exc.object[exc.start]
        raise error(
            f"{label or path}: not UTF-8 text (byte {byte:#04x} at offset {exc.start}); "
            f"save the {what} as UTF-8"
        ) from None
    except OSError as exc:
        raise error(f"cannot read {what} {label or path}: {exc}") from None


def parse_angle(text: str | float, name: str = "angle", default_unit: str = "rad") -> float:
    """Parse an angle typed by a user (CLI flag, file) into radians.

    ``"90deg"``, ``"90°"``, ``"1.57rad"``, or a bare number in ``default_unit`` (``"rad"`` or
    ``"deg"``).

    Parameters
    ----------
    text : str or float
        The angle as typed.
    name : str
        What the angle is, for the error message.
    default_unit : {"rad", "deg"}
        Unit of a bare number.

    Raises
    ------
    ConfigError
        If the text is not a finite number with an optional ``deg``/``°``/``rad`` suffix.

    Examples
    --------
    >>> round(parse_angle("90deg"), 6), parse_angle("1.5rad"), parse_angle("-0.5")
    (1.570796, 1.5, -0.5)
    """
    raw = str(text).strip().lower()
    scale = math.pi / 180 if default_unit == "deg" else 1.0
    for suffix, factor in (("deg", math.pi / 180), ("°", math.pi / 180), ("rad", 1.0)):
        if raw.endswith(suffix):
            raw, scale = raw[: -len(suffix)].strip(), factor
            break
    try:
        value = float(raw)
    except ValueError:
        example = "90deg, 1.57rad or 90" if default_unit == "deg" else "90deg, 1.57rad or 1.57"
        raise ConfigError(f"{name} must be an angle such as {example} (got {text!r})") from None
    return finite(name, value, default_unit) * scale


def _unit(unit: str) -> str:
    return f" {unit}" if unit else ""


def count_text(number: float) -> str:
    """A count for a message, to 3 digits; an int too large for a float stays readable
    (``f"{10**400:.3g}"`` raises OverflowError).

    Parameters
    ----------
    number : int or float
        The count (a float estimate, possibly inf, is written as such).

    Returns
    -------
    str
    """
    if isinstance(number, float) or abs(number) < 10**300:
        return f"{number:.3g}"
    digits = str(abs(number))
    head = f"{digits[0]}.{digits[1:3]}".rstrip("0").rstrip(".")
    return ("-" if number < 0 else "") + head + f"e+{len(digits) - 1}"
