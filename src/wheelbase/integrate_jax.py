"""The JAX backend of :func:`wheelbase.simulate` (optional extra ``wheelbase[jax]``).

The same step formulas as :func:`wheelbase.integrate.integrate_step`, written with
``jax.numpy`` and run over all steps by one ``jax.jit``-compiled ``lax.scan``; on a GPU this
keeps a large batch on the device for the whole run. The twists at the start, middle and end of
every step are computed by the model in NumPy first (models are NumPy code), so a run holds
three ``(steps, N, 3)`` arrays; use ``record_every`` to keep the recorded poses small.
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
        wrapped = jnp.arctan2(jnp.sin(new[..., 2]), jnp.cos(new[..., 2]))
        wrapped = jnp.where(wrapped <= -jnp.pi, jnp.pi, wrapped)
        return new.at[..., 2].set(wrapped)

    return step


def roll_twists(
    poses0: np.ndarray,
    z0: np.ndarray,
    zm: np.ndarray,
    z1: np.ndarray,
    steps: np.ndarray,
    method: str,
    *,
    float64: bool = True,
) -> np.ndarray:
    """Integrate N robots over S steps on JAX; returns the poses ``(S + 1, N, 3)``.

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
    float64 : bool
        Compute in float64 (default) or float32.
    """
    jax, jnp = import_jax()
    with X64(jax, float64):
        constant = z0.shape[0] == 1
        key = (method, float64, constant)
        if key not in _COMPILED:
            step = _step_function(jnp, method)

            def run(pose, z0s, zms, z1s, hs):
                def body(carry, inputs):
                    if constant:
                        new = step(carry, z0s[0], zms[0], z1s[0], inputs)
                    else:
                        new = step(carry, *inputs)
                    return new, new

                scanned = hs if constant else (z0s, zms, z1s, hs)
                _, trace = jax.lax.scan(body, pose, scanned)
                return jnp.concatenate([pose[None], trace], 0)

            _COMPILED[key] = jax.jit(run)
        dtype = jnp.float64 if float64 else jnp.float32
        args = [jnp.asarray(a, dtype=dtype) for a in (poses0, z0, zm, z1, steps)]
        return np.asarray(_COMPILED[key](*args), dtype=np.float64)
