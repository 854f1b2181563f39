"""Incremental wheel encoders: wheel rotation → integer tick counts → speed and distance.

Document 003 §III.

An incremental encoder with ``P`` pulses per revolution counts ``n = ⌊φ·P/(2π)⌋`` for a wheel
that has turned ``φ`` rad since the counter was zeroed. The microcontroller of document 003 reads
the counter once per sampling period ``T`` and turns the tick difference ``Δn`` into a speed and
a distance:

- eq. 6, ``RPM = Δn·60/P``, holds only for ``T = 1 s``; for any period it is
  ``RPM = Δn·60/(P·T)`` (:func:`ticks_to_rpm`);
- eq. 7, ``distance = 2π·r·RPM/60`` per second, is then ``D = 2π·r·Δn/P`` for the period
  (:func:`ticks_to_distance`). The document writes 3.14 for π; here π is exact.

Real counters are a fixed number of bits wide and wrap (a 16-bit counter goes 65535 → 0); the
reader unwraps the differences (:func:`unwrap_ticks`), which is exact as long as a wheel turns
fewer than ``2^(bits−1)`` ticks between two reads.

Random errors (:class:`Encoder` fields): each true tick can be missed or doubled with a given
probability (binomial draws), and zero-mean Gaussian noise (in ticks, rounded) can be added to
each tick difference. Errors are drawn from a seeded ``numpy.random.Generator``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from wheelbase._validate import as_float_array, finite, nonnegative, positive
from wheelbase.errors import ConfigError, InputError

__all__ = [
    "Encoder",
    "rad_per_s_to_rpm",
    "rpm_to_rad_per_s",
    "ticks_to_distance",
    "ticks_to_rpm",
    "unwrap_ticks",
]


def _pulses(value: object) -> int:
    """Validate a pulses-per-revolution count (an integer > 0)."""
    number = finite("pulses_per_revolution", value)  # type: ignore[arg-type]
    if number <= 0 or number != math.floor(number):
        raise ConfigError(f"pulses_per_revolution must be an integer > 0 (got {value!r})")
    return int(number)


def _period(value: object) -> float:
    return positive("period", value, "s")  # type: ignore[arg-type]


def ticks_to_rpm(ticks: ArrayLike, pulses_per_revolution: int, period: float) -> np.ndarray:
    """Wheel speed [RPM] from a tick difference over one sampling period (document 003 eq. 6).

    Parameters
    ----------
    ticks : array_like
        Tick differences Δn counted during the period (any shape).
    pulses_per_revolution : int
        Encoder resolution P [ticks/rev], > 0.
    period : float
        Sampling period T [s], > 0. Document 003 eq. 6 (``RPM = Δn·60/P``) is the case T = 1 s.

    Returns
    -------
    numpy.ndarray
        ``Δn·60/(P·T)`` [rev/min].

    Examples
    --------
    >>> float(ticks_to_rpm(20, 360, 0.1))
    33.333333333333336
    """
    ticks = as_float_array("ticks", ticks)
    return ticks * 60.0 / (_pulses(pulses_per_revolution) * _period(period))


def ticks_to_distance(
    ticks: ArrayLike, pulses_per_revolution: int, wheel_radius: float
) -> np.ndarray:
    """Distance rolled by a wheel [m] for a tick difference (document 003 eq. 7).

    Parameters
    ----------
    ticks : array_like
        Tick differences Δn (any shape).
    pulses_per_revolution : int
        Encoder resolution P [ticks/rev], > 0.
    wheel_radius : float
        Wheel radius r [m], > 0.

    Returns
    -------
    numpy.ndarray
        ``2π·r·Δn/P`` [m]: eq. 7 (2π·r·RPM/60 per second) with RPM from eq. 6 over any period.
    """
    ticks = as_float_array("ticks", ticks)
    radius = positive("wheel_radius", wheel_radius, "m")
    return 2.0 * math.pi * radius * ticks / _pulses(pulses_per_revolution)


def rpm_to_rad_per_s(rpm: ArrayLike) -> np.ndarray:
    """Convert wheel speeds from revolutions per minute to rad/s (× 2π/60)."""
    return as_float_array("rpm", rpm) * (2.0 * math.pi / 60.0)


def rad_per_s_to_rpm(omega: ArrayLike) -> np.ndarray:
    """Convert wheel speeds from rad/s to revolutions per minute (× 60/2π)."""
    return as_float_array("omega", omega) * (60.0 / (2.0 * math.pi))


def unwrap_ticks(raw: ArrayLike, counter_bits: int | None) -> np.ndarray:
    """Tick differences between successive raw counter readings, undoing the counter wrap.

    Parameters
    ----------
    raw : array_like of int, shape (T, ...)
        Raw counter readings over time (first axis), e.g. ``(T, 2)`` for (left, right).
    counter_bits : int or None
        Counter width in bits (2..62); ``None`` for a counter that never wraps.

    Returns
    -------
    numpy.ndarray of int64, shape (T − 1, ...)
        Δn_k = raw[k+1] − raw[k] mapped to [−2^(bits−1), 2^(bits−1)): exact while a wheel
        turns fewer than 2^(bits−1) ticks between two readings.

    Examples
    --------
    >>> unwrap_ticks([65530, 4, 65534], 16).tolist()
    [10, -6]
    """
    raw = np.asarray(raw)
    integral = np.issubdtype(raw.dtype, np.integer) or (
        np.issubdtype(raw.dtype, np.floating) and np.all(np.isfinite(raw)) and np.all(raw % 1 == 0)
    )
    if raw.ndim == 0 or not integral:
        raise InputError(f"raw must be integer counter readings of shape (T, ...) (got {raw!r})")
    raw = raw.astype(np.int64)
    diff = np.diff(raw, axis=0)
    if counter_bits is None:
        return diff
    bits = _bits(counter_bits)
    modulus = 1 << bits
    half = modulus >> 1
    return (diff + half) % modulus - half


def _bits(value: object) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or not 2 <= value <= 62:
        raise ConfigError(f"counter_bits must be an integer in 2..62 or None (got {value!r})")
    return int(value)


@dataclass(frozen=True)
class Encoder:
    """An incremental wheel encoder with optional counter wrap and random tick errors.

    Parameters
    ----------
    pulses_per_revolution : int
        Resolution P [ticks per wheel revolution], an integer > 0 (document 003's magnetic
        disc encoder; count it at the wheel, i.e. motor pulses × gear ratio).
    counter_bits : int or None
        Width of the hardware counter in bits (e.g. 16); readings wrap modulo 2^bits. ``None``
        (default): a counter that never wraps.
    miss_probability : float
        Probability in [0, 1) that a true tick is not counted.
    extra_probability : float
        Probability in [0, 1) that a true tick is counted twice (contact bounce).
    noise_std : float
        Standard deviation [ticks] of Gaussian noise added (rounded) to each tick difference,
        >= 0.
    seed : int or None
        Seed of the generator used when none is passed to :meth:`measure`/:meth:`tick_deltas`.

    Examples
    --------
    >>> encoder = Encoder(1024, counter_bits=16)
    >>> angles = 2 * np.pi * np.array([0.0, 30.0, 60.0, 90.0])  # 0, 30, 60, 90 revolutions
    >>> encoder.measure(angles).tolist()  # 92160 ticks wrap to 92160 - 65536
    [0, 30720, 61440, 26624]
    >>> unwrap_ticks(encoder.measure(angles), 16).tolist()
    [30720, 30720, 30720]
    """

    pulses_per_revolution: int
    counter_bits: int | None = None
    miss_probability: float = 0.0
    extra_probability: float = 0.0
    noise_std: float = 0.0
    seed: int | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "pulses_per_revolution", _pulses(self.pulses_per_revolution))
        if self.counter_bits is not None:
            object.__setattr__(self, "counter_bits", _bits(self.counter_bits))
        for name in ("miss_probability", "extra_probability"):
            value = nonnegative(name, getattr(self, name))
            if value >= 1.0:
                raise ConfigError(f"{name} must be in [0, 1) (got {value:g})")
            object.__setattr__(self, name, value)
        object.__setattr__(self, "noise_std", nonnegative("noise_std", self.noise_std, "ticks"))

    @property
    def is_ideal(self) -> bool:
        """Whether the encoder adds no random error (only quantisation)."""
        return self.miss_probability == 0 and self.extra_probability == 0 and self.noise_std == 0

    @property
    def radians_per_tick(self) -> float:
        """Wheel rotation of one tick, 2π/P [rad]."""
        return 2.0 * math.pi / self.pulses_per_revolution

    def count(self, angle: ArrayLike) -> np.ndarray:
        """Ideal absolute tick count ⌊φ·P/(2π)⌋ (int64) of a wheel turned by ``angle`` [rad]."""
        angle = as_float_array("angle", angle)
        return np.floor(angle / self.radians_per_tick + 1e-9).astype(np.int64)

    def rng(self, rng: np.random.Generator | None = None) -> np.random.Generator:
        """The generator to draw errors from: ``rng`` if given, else a new one from ``seed``."""
        return rng if rng is not None else np.random.default_rng(self.seed)

    def tick_deltas(
        self,
        angle_before: ArrayLike,
        angle_after: ArrayLike,
        rng: np.random.Generator | None = None,
    ) -> np.ndarray:
        """Tick differences counted while the wheels turn from one angle to another.

        Parameters
        ----------
        angle_before, angle_after : array_like
            Cumulative wheel angles [rad] at the two reads (same shape, e.g. ``(2,)`` for the
            (left, right) wheels or ``(T, 2)`` for T successive periods).
        rng : numpy.random.Generator, optional
            Source of the random errors (default: a generator seeded with ``seed``; pass one
            generator to successive calls to get independent errors).

        Returns
        -------
        numpy.ndarray of int64
            The true tick difference ⌊φ₁P/2π⌋ − ⌊φ₀P/2π⌋ with missed ticks subtracted, extra
            ticks added (both in the direction of rotation) and the rounded Gaussian noise.
        """
        true = self.count(angle_after) - self.count(angle_before)
        if self.is_ideal:
            return true
        generator = self.rng(rng)
        magnitude = np.abs(true)
        sign = np.sign(true)
        counted = true.copy()
        if self.miss_probability > 0:
            counted -= sign * generator.binomial(magnitude, self.miss_probability)
        if self.extra_probability > 0:
            counted += sign * generator.binomial(magnitude, self.extra_probability)
        if self.noise_std > 0:
            noise = generator.normal(0.0, self.noise_std, size=np.shape(true))
            counted += np.round(noise).astype(np.int64)
        return counted

    def measure(self, angles: ArrayLike, rng: np.random.Generator | None = None) -> np.ndarray:
        """Raw counter readings for a time series of cumulative wheel angles.

        Parameters
        ----------
        angles : array_like, shape (T, ...)
            Cumulative wheel angles [rad] at the T reads (first axis is time).
        rng : numpy.random.Generator, optional
            Source of the random errors (default: a generator seeded with ``seed``).

        Returns
        -------
        numpy.ndarray of int64, shape (T, ...)
            Counter readings: the ideal count at the first read, then the measured tick
            differences accumulated, wrapped modulo 2^counter_bits when the counter has a width.
        """
        angles = as_float_array("angles", angles, min_ndim=1)
        start = self.count(angles[0])
        deltas = self.tick_deltas(angles[:-1], angles[1:], rng)
        counts = np.concatenate([start[None], start + np.cumsum(deltas, axis=0)], axis=0)
        return self.wrap(counts)

    def wrap(self, counts: ArrayLike) -> np.ndarray:
        """Counts as the hardware counter holds them: modulo 2^counter_bits (unchanged if None)."""
        counts = np.asarray(counts, dtype=np.int64)
        if self.counter_bits is None:
            return counts
        return counts % (1 << self.counter_bits)

    def rpm(self, ticks: ArrayLike, period: float) -> np.ndarray:
        """Wheel speed [RPM] from tick differences over ``period`` seconds (eq. 6 generalised).

        Parameters
        ----------
        ticks : array_like
            Tick differences.
        period : float
            Sampling period [s], > 0.
        """
        return ticks_to_rpm(ticks, self.pulses_per_revolution, period)
