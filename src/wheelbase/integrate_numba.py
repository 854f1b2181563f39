"""The compiled kernels of :func:`wheelbase.integrate.simulate` (backend ``numba``).

Kept apart from :mod:`wheelbase.integrate` so that importing the integrators (and
``wheelbase --help``) does not load Numba; ``simulate`` imports this module on first use.
"""

from __future__ import annotations

import math

import numba

from wheelbase.geometry_numba import wrap_angle_scalar

__all__ = ["roll_constant", "step_batch", "step_batch_serial"]


@numba.njit(cache=True, inline="always")
def _sinc(x: float) -> float:
    # sin(x)/x, with its Taylor series near 0 where the quotient loses precision.
    if abs(x) < 1e-4:
        x2 = x * x
        return 1.0 - x2 / 6.0 + x2 * x2 / 120.0
    return math.sin(x) / x


@numba.njit(cache=True)
def _step_scalar(x, y, th, u0, v0, r0, um, vm, rm, u1, v1, r1, h, method):
    """One step for one robot; the same arithmetic as :func:`integrate_step`."""
    if method == 0:  # euler
        c, s = math.cos(th), math.sin(th)
        return x + h * (c * u0 - s * v0), y + h * (s * u0 + c * v0), th + h * r0
    if method == 1:  # midpoint
        tm = th + 0.5 * h * rm
        c, s = math.cos(tm), math.sin(tm)
        return x + h * (c * um - s * vm), y + h * (s * um + c * vm), th + h * rm
    if method == 2:  # rk4
        c, s = math.cos(th), math.sin(th)
        k1x, k1y = c * u0 - s * v0, s * u0 + c * v0
        t2 = th + 0.5 * h * r0
        c, s = math.cos(t2), math.sin(t2)
        k2x, k2y = c * um - s * vm, s * um + c * vm
        t3 = th + 0.5 * h * rm
        c, s = math.cos(t3), math.sin(t3)
        k3x, k3y = c * um - s * vm, s * um + c * vm
        t4 = th + h * rm
        c, s = math.cos(t4), math.sin(t4)
        k4x, k4y = c * u1 - s * v1, s * u1 + c * v1
        return (
            x + h / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x),
            y + h / 6.0 * (k1y + 2.0 * k2y + 2.0 * k3y + k4y),
            th + h / 6.0 * (r0 + 4.0 * rm + r1),
        )
    if method == 3:  # exact arc of the mid-step twist
        phi = rm * h
        a = h * _sinc(phi)
        b = h * math.sin(0.5 * phi) * _sinc(0.5 * phi)
        dxb, dyb = um * a - vm * b, um * b + vm * a
        c, s = math.cos(th), math.sin(th)
        return x + c * dxb - s * dyb, y + s * dxb + c * dyb, th + phi
    # simpson
    tm = th + h / 24.0 * (5.0 * r0 + 8.0 * rm - r1)
    t1 = th + h / 6.0 * (r0 + 4.0 * rm + r1)
    c0, s0 = math.cos(th), math.sin(th)
    cm, sm = math.cos(tm), math.sin(tm)
    c1, s1 = math.cos(t1), math.sin(t1)
    fx = (c0 * u0 - s0 * v0) + 4.0 * (cm * um - sm * vm) + (c1 * u1 - s1 * v1)
    fy = (s0 * u0 + c0 * v0) + 4.0 * (sm * um + cm * vm) + (s1 * u1 + c1 * v1)
    return x + h / 6.0 * fx, y + h / 6.0 * fy, t1


@numba.njit(cache=True, parallel=True)
def roll_constant(pose0, twist, times, method, record_index, out):
    """Integrate robots with constant twists over the whole grid; each robot is independent.

    With the twist held constant, every method moves the robot by a body-frame displacement
    that does not depend on the heading: one step is η += h·R(θ)·d, θ += h·ρ, where d and ρ
    come from one step of :func:`_step_scalar` from the origin (R(θ + α) = R(θ)·R(α)). Each
    step then costs one cos/sin pair whatever the method, instead of up to four; the result
    equals the step-by-step update to rounding. A step whose length differs from the
    nominal one (the shortened last step) goes through :func:`_step_scalar` itself.
    """
    n_robots = pose0.shape[0]
    n_steps = times.shape[0] - 1
    h_nominal = times[1] - times[0]
    for i in numba.prange(n_robots):
        x, y, th = pose0[i, 0], pose0[i, 1], pose0[i, 2]
        u, v, r = twist[i, 0], twist[i, 1], twist[i, 2]
        # Body-frame displacement per second of one nominal step, and the heading rate.
        dx, dy, _ = _step_scalar(0.0, 0.0, 0.0, u, v, r, u, v, r, u, v, r, h_nominal, method)
        dx, dy = dx / h_nominal, dy / h_nominal
        # The heading update, with the same expression as _step_scalar.
        simpson_weights = method == 2 or method == 4  # rk4, simpson
        weighted_rate = r + 4.0 * r + r
        slot = 0
        if record_index[0] == 0:
            out[0, i, 0], out[0, i, 1], out[0, i, 2] = x, y, wrap_angle_scalar(th)
            slot = 1
        for k in range(n_steps):
            h = times[k + 1] - times[k]
            if abs(h - h_nominal) <= 1e-9 * h_nominal:
                c, s = math.cos(th), math.sin(th)
                x += h * (c * dx - s * dy)
                y += h * (s * dx + c * dy)
                th += h / 6.0 * weighted_rate if simpson_weights else h * r
            else:
                x, y, th = _step_scalar(x, y, th, u, v, r, u, v, r, u, v, r, h, method)
            if th > math.pi or th <= -math.pi:  # keep θ small, as the NumPy backend does
                th = wrap_angle_scalar(th)
            if slot < record_index.shape[0] and record_index[slot] == k + 1:
                out[slot, i, 0], out[slot, i, 1], out[slot, i, 2] = x, y, wrap_angle_scalar(th)
                slot += 1


@numba.njit(cache=True, parallel=True)
def step_batch(pose, z0, zm, z1, h, method):
    """Advance every robot of ``pose`` (N, 3) by one step, in place."""
    for i in numba.prange(pose.shape[0]):
        x, y, th = _step_scalar(
            pose[i, 0], pose[i, 1], pose[i, 2],
            z0[i, 0], z0[i, 1], z0[i, 2],
            zm[i, 0], zm[i, 1], zm[i, 2],
            z1[i, 0], z1[i, 1], z1[i, 2],
            h, method,
        )  # fmt: skip
        # an angle inside (−π, π] is returned as it is: skip the call there
        if th > math.pi or th <= -math.pi:
            th = wrap_angle_scalar(th)
        pose[i, 0], pose[i, 1], pose[i, 2] = x, y, th


# A few robots do not pay for the threads of a parallel loop: a call of the parallel kernel
# costs ~0.2 ms however small the batch, which dominated single-robot runs with callable inputs.
step_batch_serial = numba.njit(cache=True)(step_batch.py_func)
