"""The JAX backend of :func:`wheelbase.simulate` (optional extra ``wheelbase[jax]``).

The same step formulas as :func:`wheelbase.integrate.integrate_step`, written with
``jax.numpy`` and run over all steps by one ``jax.jit``-compiled ``lax.scan``; on a GPU this
keeps a large batch on the device for the whole run. The twists at the start, middle and end of
every step are computed by the model in NumPy first (models are NumPy code), so a run holds
three ``(steps, N, 3)`` arrays (one when the inputs are constant); only the poses that
``record_every`` keeps leave the compiled loop.
Float64 by default, so that results equal the NumPy backend to rounding; ``float32`` on request.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from wheelbase._jax import X64, import_jax

__all__ = ["roll_twists"]

_COMPILED: dict[tuple[str, bool, bool], Any] = {}


def _step_function(jnp: Any, method: str):
    def world(theta, twist):
        c, s = jnp.cos(theta), jnp.sin(theta)
        u, v, r = twist[..., 0], twist[..., 1], twist[..., 2]
        return jnp.stack([c * u - s * v, s * u + c * v, r], -1)

    def sinc(x):
        small = jnp.abs(x) < 1e-4
        safe = jnp.where(small, 1.0, x)
        return jnp.where(small, 1.0 - x * x / 6.0 + x**4 / 120.0, jnp.sin(safe) / safe)

    def step(pose, z0, zm, z1, h):
        theta = pose[..., 2]
        if method == "euler":
            new = pose + h * world(theta, z0)
        elif method == "midpoint":
            new = pose + h * world(theta + 0.5 * h * zm[..., 2], zm)
        elif method == "rk4":
            k1 = world(theta, z0)
            k2 = world(theta + 0.5 * h * k1[..., 2], zm)
            k3 = world(theta + 0.5 * h * k2[..., 2], zm)
            k4 = world(theta + h * k3[..., 2], z1)
            new = pose + h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
        elif method == "exact":
            phi = zm[..., 2] * h
            a = h * sinc(phi)
            b = h * jnp.sin(0.5 * phi) * sinc(0.5 * phi)
            body = jnp.stack([zm[..., 0] * a - zm[..., 1] * b, zm[..., 0] * b + zm[..., 1] * a])
            c, s = jnp.cos(theta), jnp.sin(theta)
            new = jnp.stack(
                [pose[..., 0] + c * body[0] - s * body[1],
                 pose[..., 1] + s * body[0] + c * body[1], theta + phi], -1
            )  # fmt: skip
        else:  # simpson
            r0, rm, r1 = z0[..., 2], zm[..., 2], z1[..., 2]
            theta_mid = theta + h / 24.0 * (5.0 * r0 + 8.0 * rm - r1)
            theta_end = theta + h / 6.0 * (r0 + 4.0 * rm + r1)
            rate = world(theta, z0) + 4.0 * world(theta_mid, zm) + world(theta_end, z1)
            new = pose + h / 6.0 * rate
            new = new.at[..., 2].set(theta_end)
        # θ − 2π·round(θ/2π) wraps any angle at a fraction of the cost of atan2(sin, cos), and
        # equals it to rounding; −π maps to π as everywhere in wheelbase.
        theta = new[..., 2]
        theta = theta - (2.0 * jnp.pi) * jnp.round(theta / (2.0 * jnp.pi))
        theta = jnp.where(theta <= -jnp.pi, jnp.pi, theta)
        return new.at[..., 2].set(theta)

    return step


def roll_twists(
    poses0: np.ndarray,
    z0: np.ndarray,
    zm: np.ndarray,
    z1: np.ndarray,
    steps: np.ndarray,
    method: str,
    record: np.ndarray | None = None,
    *,
    float64: bool = True,
) -> np.ndarray:
    """Integrate N robots over S steps on JAX; returns the recorded poses ``(R, N, 3)``.

    Parameters
    ----------
    poses0 : numpy.ndarray, shape (N, 3)
        Initial poses [m, m, rad] (heading already wrapped).
    z0, zm, z1 : numpy.ndarray, shape (S, N, 3) or (1, N, 3)
        Body twists at the start, middle and end of every step; a leading axis of 1 means
        constant twists, which the compiled loop then keeps out of the per-step data.
    steps : numpy.ndarray, shape (S,)
        Step lengths [s].
    method : str
        One of :data:`wheelbase.integrate.METHODS`.
    record : numpy.ndarray, optional
        Step indices to keep: 0, e, 2e, ... and S (what ``simulate`` asks for with
        ``record_every = e``); default every step.
    float64 : bool
        Compute in float64 (default) or float32.
    """
    jax, jnp = import_jax()
    n_steps = steps.shape[0]
    if record is None:
        record = np.arange(n_steps + 1)
    every = int(record[1] - record[0]) if record.size > 1 else max(n_steps, 1)
    # Only the kept poses leave the loop: an outer scan over records, an inner one over the
    # `every` steps between them. The steps are padded to a whole number of chunks with steps
    # of length 0, which leave a pose exactly as it is.
    chunks = record.size - 1
    padded = chunks * every
    hs = np.zeros(padded)
    hs[:n_steps] = steps
    constant = z0.shape[0] == 1
    if not constant:
        z0, zm, z1 = (np.concatenate([z, np.zeros((padded - n_steps, *z.shape[1:]))]) for z in
                      (z0, zm, z1))  # fmt: skip
    with X64(jax, float64):
        key = (method, float64, constant)
        if key not in _COMPILED:
            _COMPILED[key] = jax.jit(_run_function(jax, jnp, method, constant))
        dtype = jnp.float64 if float64 else jnp.float32
        shape = (chunks, every)
        args = [jnp.asarray(poses0, dtype=dtype), jnp.asarray(hs.reshape(shape), dtype=dtype)]
        args += [jnp.asarray(z if constant else z.reshape(*shape, *z.shape[1:]), dtype=dtype)
                 for z in (z0, zm, z1)]  # fmt: skip
        return np.asarray(_COMPILED[key](*args), dtype=np.float64)


def _run_function(jax: Any, jnp: Any, method: str, constant: bool):
    step = _step_function(jnp, method)

    def run(pose, hs, z0s, zms, z1s):
        def inner(carry, inputs):
            if constant:
                return step(carry, z0s[0], zms[0], z1s[0], inputs), None
            return step(carry, *inputs[1:], inputs[0]), None

        def outer(carry, inputs):
            new, _ = jax.lax.scan(inner, carry, inputs)
            return new, new

        scanned = hs if constant else (hs, z0s, zms, z1s)
        _, trace = jax.lax.scan(outer, pose, scanned)
        return jnp.concatenate([pose[None], trace], 0)

    return run
