"""The JAX backend of :class:`wheelbase.control.MPPI` (private; extra ``wheelbase[jax]``).

``jax.jit`` + ``lax.scan`` over the horizon; float32 by default, float64 with
``jax_float64=True``. On a GPU the sampled commands stay on the device and the weighted mean is
taken there (:func:`weighted_mean`). It does not score perception (costmap, tracks): the
controller refuses a view on this backend.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from wheelbase._jax import X64, import_jax
from wheelbase.control.mppi_bounds import KIND_FRONT, KIND_HOLONOMIC, KIND_REAR, KIND_VELOCITY

__all__ = ["KEPT_DEVICE_SAMPLES", "host_samples", "jax_costs", "jax_function", "weighted_mean"]

_JAX_CACHE: dict = {}

KEPT_DEVICE_SAMPLES = 256
"""With the jax backend, :attr:`MPPIPlan.samples` holds the first this many samples (enough for a
fan of rollouts); the others never leave the device."""


def jax_costs(mppi: Any, pose, mean, lo, hi, scale, window, info, last, w, noise, mp):
    """Costs and sampled commands from the JAX backend; with ``noise=None`` the noise is drawn
    on the device from a key folded from (seed, call).

    Parameters
    ----------
    mppi : MPPI
        The controller (its map on the device is cached on it).
    pose, mean, lo, hi, scale, window, info, last, w, noise, mp : numpy.ndarray
        As for :func:`wheelbase.control.mppi_numpy.numpy_costs` (no perception here).

    Returns
    -------
    costs : numpy.ndarray, shape (K,)
    controls : numpy.ndarray or jax.Array, shape (K, T, m)
        On the device where that is a GPU.
    """
    jax, jnp = import_jax()
    if noise is None and jax.default_backend() == "cpu":
        # NumPy draws normals about twice as fast as XLA's threefry on a CPU; on a GPU the
        # draw stays on the device (no (K, T, m) transfer at every call).
        noise = mppi._rng.standard_normal((mppi.samples, mppi.horizon_steps, mppi.nu))
        noise *= mppi.noise_std
    draw = noise is None
    function = jax_function(
        mppi.horizon_steps, int(mppi.critics.path_stride), mppi._kind, mppi.jax_float64,
        mppi.samples if draw else None,
    )  # fmt: skip
    dtype = np.float64 if mppi.jax_float64 else np.float32
    with X64(jax, mppi.jax_float64):
        if mppi._jax_map is None or mppi._jax_map[0] != dtype:
            # The map goes to the device once, not at every call (its origin relative to
            # the robot, four numbers, at every call).
            arrays = (mppi._field.distance_field, mppi._field.circles)
            mppi._jax_map = (dtype, *(jnp.asarray(a, dtype=dtype) for a in arrays))
        _, df, circles = mppi._jax_map
        if draw:
            noise = jax.random.fold_in(jax.random.PRNGKey(mppi.seed), mppi._calls)
        else:
            noise = np.asarray(noise, dtype)
        extra = np.array([0.0, mppi.dt, mppi._wheel_base, *mppi.noise_std])
        small = (np.asarray(v, dtype) for v in (pose, mean, lo, hi, scale, window, info, last))
        costs, controls = function(*small, noise, np.asarray(w, dtype), df,
                                   np.asarray(mp, dtype), circles,
                                   np.asarray(extra, dtype))  # fmt: skip
        if jax.default_backend() == "cpu":  # host and device are one: NumPy is quicker
            return np.asarray(costs, np.float64), np.asarray(controls, np.float64)
        # On a GPU the sampled commands stay there: (K, T, m) is 0.9 GB at a million
        # samples in float64; the weighted mean is taken there (see weighted_mean).
        return np.asarray(costs, np.float64), controls


def weighted_mean(weights: np.ndarray, controls: Any, float64: bool) -> np.ndarray:
    """Σ_i w_i V_i, shape (T, m): on the host for NumPy arrays, on the device for JAX arrays
    (only K weights go there and T·m numbers come back).

    Parameters
    ----------
    weights : numpy.ndarray, shape (K,)
        Softmin weights.
    controls : numpy.ndarray or jax.Array, shape (K, T, m)
        Sampled sequences.
    float64 : bool
        Reduce in float64 on the device.

    Returns
    -------
    numpy.ndarray
    """
    if isinstance(controls, np.ndarray):
        return np.tensordot(weights, controls, axes=1)
    jax, jnp = import_jax()
    with X64(jax, float64):
        device_weights = jnp.asarray(weights, dtype=controls.dtype)
        return np.asarray(jnp.tensordot(device_weights, controls, axes=1), np.float64)


def host_samples(controls: Any, float64: bool) -> np.ndarray:
    """The first :data:`KEPT_DEVICE_SAMPLES` sampled sequences on the host (all of a NumPy
    array).

    Parameters
    ----------
    controls : numpy.ndarray or jax.Array, shape (K, T, m)
        Sampled sequences.
    float64 : bool
        Copy them in float64.

    Returns
    -------
    numpy.ndarray
    """
    if isinstance(controls, np.ndarray):
        return controls
    jax, _jnp = import_jax()
    with X64(jax, float64):
        return np.asarray(controls[:KEPT_DEVICE_SAMPLES], np.float64)


def jax_function(steps: int, stride: int, kind: int, float64: bool, samples: int | None):
    """The jit-compiled JAX iteration: a ``lax.scan`` rolls the samples out, then the critics
    score all steps at once (on a CPU this beat a per-step fusion of rollout and critics:
    5.8 against 7.5 ms at 2,000 × 56).

    Parameters
    ----------
    steps : int
        Horizon steps T.
    stride : int
        The path critics' stride.
    kind : int
        The command kind (:mod:`wheelbase.control.mppi_bounds`).
    float64 : bool
        Compute in float64.
    samples : int or None
        Draw that many noise sequences inside from a PRNG key; ``None``: take the noise as an
        argument.

    Returns
    -------
    callable
        The jitted function (cached per arguments).
    """
    key = (steps, stride, kind, float64, samples)
    if key in _JAX_CACHE:
        return _JAX_CACHE[key]
    jax, jnp = import_jax()
    lax = jax.lax

    def wrap(a):
        return jnp.arctan2(jnp.sin(a), jnp.cos(a))

    checked = np.arange(stride - 1, steps, stride)

    def run(pose, mean, lo, hi, scale, window, info, last, noise, w, df, mp, circles, extra):
        dt, wheel_base, sigma = extra[1], extra[2], extra[3:]
        if samples is not None:  # `noise` is the PRNG key
            noise = jax.random.normal(noise, (samples, steps, sigma.shape[0]), pose.dtype) * sigma
        controls = jnp.clip(mean[None] + noise, lo, hi)
        if kind == KIND_HOLONOMIC:  # (v_x, v_y) in the disk of radius hi[0], as MPPI._clip
            speed = jnp.hypot(controls[..., 0], controls[..., 1])
            shrink = jnp.where(speed > hi[0], hi[0] / jnp.where(speed > 0.0, speed, 1.0), 1.0)
            planar = controls[..., :2] * shrink[..., None]
            controls = jnp.concatenate([planar, controls[..., 2:]], -1)
        n = noise.shape[0]
        goal_mode = info[0] > 0.5
        rows, cols = df.shape
        x0, y0, res, has_map = mp[0], mp[1], mp[2], mp[3] > 0.5

        def step(carry, u):
            x, y, th = carry
            v, second = u[:, 0], u[:, 1]
            lateral = 0.0
            if kind == KIND_VELOCITY:
                speed, rate = v, second
            elif kind == KIND_REAR:
                speed, rate = v, v * jnp.tan(second) / wheel_base
            elif kind == KIND_FRONT:
                speed, rate = v * jnp.cos(second), v * jnp.sin(second) / wheel_base
            else:
                speed, lateral, rate = v, second, u[:, 2]
            x = x + dt * (jnp.cos(th) * speed - jnp.sin(th) * lateral)
            y = y + dt * (jnp.sin(th) * speed + jnp.cos(th) * lateral)
            th = wrap(th + dt * rate)
            return (x, y, th), (x, y, th)

        zeros = jnp.zeros(n, dtype=pose.dtype)
        carry = (zeros + pose[0], zeros + pose[1], zeros + pose[2])
        (x, y, th), (xs, ys, ths) = lax.scan(step, carry, jnp.swapaxes(controls, 0, 1))
        cost = zeros
        if checked.size:
            px, py, pth = xs[checked], ys[checked], ths[checked]  # (C, N)
            d2 = (px[..., None] - window[:, 0]) ** 2 + (py[..., None] - window[:, 1]) ** 2
            nearest = jnp.argmin(d2, axis=-1)
            dmin = jnp.min(d2, axis=-1)
            err = wrap(pth - window[nearest, 2])
            cost = cost + (w[0] * jnp.sum(jnp.sqrt(dmin), 0) + w[1] * jnp.sum(err * err, 0)) / (
                checked.size
            )
        goal = w[3] * jnp.sum(jnp.hypot(xs - info[1], ys - info[2]), 0) / steps
        cost = cost + jnp.where(goal_mode, goal, 0.0)
        c, s = jnp.cos(ths), jnp.sin(ths)
        collided = jnp.zeros(n, dtype=bool)
        clearance = jnp.full(xs.shape, jnp.inf, dtype=xs.dtype)
        for k in range(circles.shape[0]):
            cx = xs + c * circles[k, 0] - s * circles[k, 1]
            cy = ys + s * circles[k, 0] + c * circles[k, 1]
            col = jnp.floor((cx - x0) / res).astype(jnp.int32)
            row = jnp.floor((cy - y0) / res).astype(jnp.int32)
            inside = (row >= 0) & (row < rows) & (col >= 0) & (col < cols)
            field = df[jnp.clip(row, 0, rows - 1), jnp.clip(col, 0, cols - 1)]
            clear = field - circles[k, 2] - math.sqrt(2.0) * res - info[6]
            collided = collided | (has_map & jnp.any(~inside | (clear <= 0.0), axis=0))
            clearance = jnp.minimum(clearance, jnp.where(inside, clear, 0.0))
        gap = jnp.where(clearance > 0.0, jnp.maximum(w[10] - clearance, 0.0), 0.0)
        cost = cost + jnp.where(has_map, w[5] * jnp.sum(gap * gap, 0) / steps, 0.0)
        v = controls[..., 0]
        cost = cost + w[6] * jnp.sum(jnp.maximum(-info[4] * v, 0.0), 1) * dt
        cost = cost + w[7] * jnp.sum((controls / scale) ** 2, axis=(1, 2)) / steps
        previous = jnp.concatenate(
            [jnp.broadcast_to(last, (n, 1, last.shape[0])), controls[:, :-1]], 1
        )
        cost = cost + w[8] * jnp.sum(((controls - previous) / scale) ** 2, axis=(1, 2)) / steps
        if kind in (KIND_VELOCITY, KIND_HOLONOMIC):
            cost = cost + w[9] * jnp.sum(jnp.abs(controls[..., -1]), 1) / (steps * scale[-1])
        d2_end = (x[:, None] - window[:, 0]) ** 2 + (y[:, None] - window[:, 1]) ** 2
        follow = w[2] * (window[-1, 3] - window[jnp.argmin(d2_end, axis=-1), 3])
        heading = w[4] * jnp.abs(wrap(th - info[3]))
        cost = cost + jnp.where(goal_mode, heading, follow)
        cost = cost + jnp.where(collided, w[11], 0.0)
        return cost, controls

    function = jax.jit(run)
    _JAX_CACHE[key] = function
    return function
