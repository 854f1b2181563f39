"""A differential drive on terrain: wheel slip, traction limits, load transfer, slopes and soil.

:class:`TerrainDynamics` extends document 000's Lagrange–Euler model
(:class:`wheelbase.dynamics.DiffDriveDynamics`) with the ground. Two contact models:

**Rigid contact** (``slip=False``): the wheels roll without slipping, v = 0, the reduced
dynamics of :mod:`wheelbase.dynamics` in (u, r). The ground adds forces that the wheels do not
produce: rolling resistance c_rr·N_k of every contact (drive wheels and casters), or on soil
the compaction resistance R_c(N_k) (Bekker), both smoothed as tanh(v_k / 1 mm/s) like the
existing model's; and gravity m·g_t at the CG on a slope. They enter as the equivalent change of
wheel torques, so with none of them (c_rr = 0, flat) the step *is* the existing one: the same
trajectories to the last bit.

**Slip** (``slip=True``): each drive wheel turns at its own rate ω_k, J_w·ω̇_k = τ_k − a·F_x,k
− M_rr,k, and the body has the three degrees of freedom (u, v, r) of document 000's
unconstrained model, pushed by the contact forces. The wheel's slip velocity against the ground
is (a·ω − v_x, −v_y) at its contact, whose velocity is (v_x, v_y) = (u ∓ d·r, v); divided by
V = √(v_x² + v_ε²) it is the slip vector (κ, tan α) — the longitudinal slip ratio κ of Pacejka
(κ = (aω − v_x)/|v_x| away from standstill) and the lateral slip — of magnitude σ. The force
has the direction of the slip velocity (it opposes the sliding: combined slip by the similarity
method) and the magnitude

- on hard ground N·μ(σ), μ the surface's magic-formula curve
  (:class:`~wheelbase.terrain.friction.FrictionCurve`), plus the rolling-resistance moment
  M_rr = c_rr·N·a·tanh(a·ω / 1 mm/s) on the wheel;
- on soil the Janosi–Hanamoto thrust at the slip i = σ/(1 + σ) (Wong's i = 1 − v/(aω) when
  driving straight) over the contact length of the Bekker sinkage, plus the compaction
  resistance R_c on the body (:mod:`wheelbase.terrain.soil`).

Casters roll freely in any direction (no side force) against their rolling or compaction
resistance. Normal loads come from :mod:`wheelbase.terrain.contact` with the load transfer of
the tangential ground force one substep before (a lag of microseconds), the CG height, and
m·g·cos α on a slope. Each contact looks up the surface under itself (a wheel on ice beside one
on concrete is a split-μ start); the slope is the one under the centroid.

Integration: RK4 in substeps short enough for the stiffest contact, h·λ ≤ ``step_factor``
with λ the contact's force slope (N·B·C·D/V per unit slip speed) over the inertia it moves
(a²/J_w + 1/m + d²/I_B); resistances count likewise. One substep when nothing is stiff.

Energy. Besides the state the kernel integrates, with the same RK4 stages, the work of the wheel
torques W = ∫Σ τ_k·ω_k dt, what slip dissipates ∫Σ F_k·(slip velocity) dt, rolling resistance
∫(Σ M_rr·ω + Σ casters) dt, soil compaction ∫Σ R_c·v dt, damping, and the work of gravity; with
the kinetic energy T = ½VᵀMV + ½J_w(ω_L² + ω_R²),
W = ΔT − W_gravity + slip + rolling + soil + damping holds to the integration error
(``tests/test_terrain_dynamics.py`` checks 1e-6 relative on every surface).

State of a robot: (x, y, ψ, u, v, r) as the existing plants, and an auxiliary row
(:data:`AUX_NAMES`): wheel rates, wheel angles, the energy integrals, the lagged ground force.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numba
import numpy as np
from numpy.typing import ArrayLike

from wheelbase._validate import as_float_array, integer, positive
from wheelbase.dynamics import GRAVITY, DiffDriveDynamics, _accel
from wheelbase.errors import ConfigError
from wheelbase.geometry_numba import wrap_angle_scalar
from wheelbase.terrain.contact import RM100_CONTACTS, WheelContacts
from wheelbase.terrain.map import TerrainMap

__all__ = [
    "AUX_NAMES",
    "MAX_SUBSTEPS",
    "MIN_SLIP_SPEED",
    "SIGNAL_NAMES",
    "TerrainDynamics",
    "terrain_step",
]

AUX_NAMES: tuple[str, ...] = (
    "omega_left",
    "omega_right",
    "angle_left",
    "angle_right",
    "work_wheels",
    "dissipated_slip",
    "dissipated_rolling",
    "dissipated_soil",
    "dissipated_damping",
    "work_gravity",
    "ground_force_x",
    "ground_force_y",
    "started",
)
"""Columns of a robot's auxiliary row: wheel rates [rad/s], wheel angles [rad], energies [J]
(work of the wheel torques; dissipated by slip, rolling resistance, soil, damping; work done
by gravity), the net tangential ground force of the last evaluation [N] (load transfer), and
whether the wheel rates were set from the first twist."""
_AUX = len(AUX_NAMES)

SIGNAL_NAMES: tuple[str, ...] = (
    "slip_left",
    "slip_right",
    "traction_left",
    "traction_right",
    "load_left",
    "load_right",
    "sinkage_left",
    "sinkage_right",
    "surface_left",
    "surface_right",
    "substeps",
)
"""Signals of a robot after each step: longitudinal slip ratio κ of each drive wheel,
longitudinal ground force on it [N], its normal load [N], sinkage [m], the index of the
surface under it, and the substeps the step took."""
_SIG = len(SIGNAL_NAMES)

MIN_SLIP_SPEED = 1e-4
"""Smallest v_ε [m/s]: the slip's stiffness at standstill grows as 1/v_ε."""

MAX_SUBSTEPS = 4000
"""Most substeps of one step (a step that would need more integrates with fewer and may go
unstable: that robot then ends ``diverged``)."""

_RR_SPEED = 1e-3  # m/s: smoothing of the resistances, as DiffDriveDynamics' rolling resistance
# parameter vector: DiffDriveDynamics' ten first (the compiled _accel reads them), then these
_JW, _WIDTH, _CASTER_R, _CASTER_B, _HEIGHT, _VEPS, _G, _SLIP, _FACTOR = range(10, 19)
_PARAMS = 19


# --------------------------------------------------------------------------- contact forces
@numba.njit(cache=True)
def _shear_fraction(x):
    if x < 1e-4:
        return x / 2.0 - x * x / 6.0 + x * x * x / 24.0
    return 1.0 - (-math.expm1(-x)) / x


@numba.njit(cache=True)
def _soil_contact(row, load, radius, width):
    """(sinkage z₀ [m], contact length l [m], shear strength A·c + N·tan φ [N], R_c [N])."""
    if load <= 0.0:
        return 0.0, 0.0, 0.0, 0.0
    n, kc, kphi, coh, tanphi = row[5], row[6], row[7], row[8], row[9]
    base = 3.0 * load / ((3.0 - n) * (kc + width * kphi) * math.sqrt(2.0 * radius))
    z0 = base ** (2.0 / (2.0 * n + 1.0))
    ratio = min(z0 / radius, 1.0)
    length = radius * math.acos(1.0 - ratio)
    strength = width * length * coh + load * tanphi
    resist = width * (kc / width + kphi) * z0 ** (n + 1.0) / (n + 1.0)
    return z0, length, strength, resist


@numba.njit(cache=True)
def _surface_at(x, y, cells, geo):
    col = math.floor((x - geo[0]) / geo[2])
    row = math.floor((y - geo[1]) / geo[2])
    if row < 0 or row >= cells.shape[0] or col < 0 or col >= cells.shape[1]:
        return 0, -1, -1
    return cells[row, col], row, col


@numba.njit(cache=True)
def _rhs(y, tl, tr, p, layout, loads, table, cells, slope, geo, out, info):
    """Rate ``out`` (16,) of the augmented state ``y`` (16,); ``info`` (8,): ground force
    (T_x, T_y), per wheel slip κ, traction F_x and sinkage, for the signals."""
    m, xb, yb, ib, a, d, bu, br = p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7]
    jw, vel_eps, g, slip = p[_JW], p[_VEPS], p[_G], p[_SLIP] > 0.5
    px, py, psi, u, v, r = y[0], y[1], y[2], y[3], y[4], y[5]
    c, s = math.cos(psi), math.sin(psi)
    if not slip:
        v = 0.0
    # gravity at the CG, from the slope under the centroid (body frame)
    _code, grow, gcol = _surface_at(px, py, cells, geo)
    gsx, gsy = 0.0, 0.0
    if grow >= 0:
        gsx, gsy = slope[grow, gcol, 0], slope[grow, gcol, 1]
    fgx = -m * g * (c * gsx + s * gsy)
    fgy = -m * g * (-s * gsx + c * gsy)
    fx, fy, mz = fgx, fgy, xb * fgy - yb * fgx  # external forces at B (gravity first)
    gx, gy = 0.0, 0.0  # the ground's tangential force (load transfer)
    p_in = d_slip = d_roll = d_soil = 0.0
    torque = (tl, tr)
    for k in range(2):
        wy = layout[k, 1]  # +d left, −d right
        vx = u - wy * r
        wx_, wy_ = px + c * layout[k, 0] - s * wy, py + s * layout[k, 0] + c * wy
        code, _r, _c = _surface_at(wx_, wy_, cells, geo)
        row = table[code]
        load = loads[k]
        soil = row[0] > 0.5
        z0 = length = strength = resist = 0.0
        if soil:
            z0, length, strength, resist = _soil_contact(row, load, a, p[_WIDTH])
        drag = resist * math.tanh(vx / _RR_SPEED) if soil else 0.0
        if slip:
            omega = y[6 + k]
            big_v = math.sqrt(vx * vx + vel_eps * vel_eps)
            svx, svy = a * omega - vx, -v
            kappa, tan_a = svx / big_v, svy / big_v
            sigma = math.sqrt(kappa * kappa + tan_a * tan_a)
            if soil:
                if sigma > 1e-12:
                    i_s = sigma / (1.0 + sigma)
                    f = strength * _shear_fraction(i_s * length / row[10]) / sigma
                else:
                    f = strength * length / (2.0 * row[10])
                m_rr = 0.0
            else:
                bb, cc, dd = row[1], row[2], row[3]
                if sigma > 1e-12:
                    f = load * dd * math.sin(cc * math.atan(bb * sigma)) / sigma
                else:
                    f = load * bb * cc * dd
                m_rr = row[4] * load * a * math.tanh(a * omega / _RR_SPEED)
            wfx, wfy = f * kappa, f * tan_a
            out[6 + k] = (torque[k] - a * wfx - m_rr) / jw
            out[8 + k] = omega
            p_in += torque[k] * omega
            d_slip += wfx * svx + wfy * svy
            d_roll += m_rr * omega
            d_soil += drag * vx
            fx += wfx - drag
            fy += wfy
            mz += -wy * (wfx - drag)
            gx += wfx - drag
            gy += wfy
            info[2 + k] = kappa
            info[4 + k] = wfx
        else:
            resist_k = drag if soil else row[4] * load * math.tanh(vx / _RR_SPEED)
            out[6 + k] = 0.0
            out[8 + k] = vx / a
            p_in += torque[k] * vx / a
            if soil:
                d_soil += resist_k * vx
            else:
                d_roll += resist_k * vx
            fx -= resist_k
            mz -= -wy * resist_k
            gx += torque[k] / a - resist_k
            info[2 + k] = 0.0
            info[4 + k] = torque[k] / a - resist_k
        info[6 + k] = z0
    for k in range(2, layout.shape[0]):
        cx_, cy_ = layout[k, 0], layout[k, 1]
        vcx, vcy = u - cy_ * r, v + cx_ * r
        code, _r, _c = _surface_at(px + c * cx_ - s * cy_, py + s * cx_ + c * cy_, cells, geo)
        row = table[code]
        if row[0] > 0.5:
            resist = _soil_contact(row, loads[k], p[_CASTER_R], p[_CASTER_B])[3]
        else:
            resist = row[4] * loads[k]
        speed = math.sqrt(vcx * vcx + vcy * vcy)
        if speed > 1e-15:
            factor = resist * math.tanh(speed / _RR_SPEED) / speed
        else:
            factor = resist / _RR_SPEED
        fcx, fcy = -factor * vcx, -factor * vcy
        fx += fcx
        fy += fcy
        mz += cx_ * fcy - cy_ * fcx
        gx += fcx
        gy += fcy
        if row[0] > 0.5:
            d_soil += factor * speed * speed
        else:
            d_roll += factor * speed * speed
    p_grav = fgx * (u - yb * r) + fgy * (v + xb * r)
    if slip:
        fx -= bu * u
        fy -= bu * v
        mz -= br * r
        b1 = fx + m * r * (v + xb * r)
        b2 = fy - m * r * (u - yb * r)
        b3 = mz - m * r * (xb * u + yb * v)
        schur = ib - m * (xb * xb + yb * yb)
        dr = (b3 + yb * b1 - xb * b2) / schur
        du = (b1 + m * yb * dr) / m
        dv = (b2 - m * xb * dr) / m
        d_damp = bu * (u * u + v * v) + br * r * r
    else:
        # the external forces as the change of wheel torques that gives them (F_x, M_z)
        dl = a * (0.5 * fx - 0.5 * mz / d)
        dright = a * (0.5 * fx + 0.5 * mz / d)
        du, dv, dr, lateral = _accel(u, 0.0, r, tl + dl, tr + dright, p)
        gy = lateral - fgy
        d_damp = bu * u * u + br * r * r
    out[0] = c * u - s * v
    out[1] = s * u + c * v
    out[2] = r
    out[3], out[4], out[5] = du, dv, dr
    out[10] = p_in
    out[11] = d_slip
    out[12] = d_roll
    out[13] = d_soil
    out[14] = d_damp
    out[15] = p_grav
    info[0], info[1] = gx, gy


@numba.njit(cache=True)
def _stiffness(y, p, layout, loads, table, cells, geo):
    """An upper bound of the rates λ [1/s] of the contact dynamics at ``y``: the force slopes
    of all contacts on the body (summed) plus the stiffest wheel's spin (module docstring)."""
    m, ib, a = p[0], p[3], p[4]
    jw, vel_eps, slip = p[_JW], p[_VEPS], p[_SLIP] > 0.5
    px, py, psi, u, r = y[0], y[1], y[2], y[3], y[5]
    c, s = math.cos(psi), math.sin(psi)
    on_body = 0.0
    on_wheel = 0.0
    for k in range(layout.shape[0]):
        kx, ky = layout[k, 0], layout[k, 1]
        code, _r, _c = _surface_at(px + c * kx - s * ky, py + s * kx + c * ky, cells, geo)
        row = table[code]
        load = loads[k]
        soil = row[0] > 0.5
        if k < 2:
            radius, width = a, p[_WIDTH]
        else:
            radius, width = p[_CASTER_R], p[_CASTER_B]
        _z0, length, strength, resist = 0.0, 0.0, 0.0, row[4] * load
        if soil:
            _z0, length, strength, resist = _soil_contact(row, load, radius, width)
        mobility = 1.0 / m + (kx * kx + ky * ky) / ib  # of the body at this contact
        if k >= 2 or not slip or soil:
            on_body += resist / _RR_SPEED * mobility  # the smoothed resistances
        if k < 2 and slip:
            vx = u - ky * r
            big_v = math.sqrt(vx * vx + vel_eps * vel_eps)
            if soil:
                grip = strength * length / (2.0 * row[10])
                spin = 0.0
            else:
                grip = load * row[1] * row[2] * row[3]
                spin = row[4] * load * a * a / (_RR_SPEED * jw)
            on_body += grip / big_v * mobility
            on_wheel = max(on_wheel, grip / big_v * a * a / jw + spin)
    return on_body + on_wheel


@numba.njit(cache=True)
def _update_loads(y, aux, p, layout, ainv, slope, cells, geo, loads):
    m, xb, yb = p[0], p[1], p[2]
    _code, grow, gcol = _surface_at(y[0], y[1], cells, geo)
    rise2 = 0.0
    if grow >= 0:
        rise2 = slope[grow, gcol, 0] ** 2 + slope[grow, gcol, 1] ** 2
    weight = m * p[_G] * math.sqrt(max(1.0 - rise2, 0.0))
    b0, b1, b2 = weight, weight * xb - p[_HEIGHT] * aux[10], weight * yb - p[_HEIGHT] * aux[11]
    l0 = ainv[0, 0] * b0 + ainv[0, 1] * b1 + ainv[0, 2] * b2
    l1 = ainv[1, 0] * b0 + ainv[1, 1] * b1 + ainv[1, 2] * b2
    l2 = ainv[2, 0] * b0 + ainv[2, 1] * b1 + ainv[2, 2] * b2
    for k in range(layout.shape[0]):
        value = layout[k, 2] * (l0 + l1 * layout[k, 0] + l2 * layout[k, 1])
        loads[k] = value if value > 0.0 else 0.0


@numba.njit(cache=True)
def _advance(s6, aux, tl, tr, dt, p, layout, ainv, table, cells, slope, geo, sig):
    """Advance one robot by ``dt`` (state ``s6`` (6,) and ``aux`` in place); signals ``sig``."""
    n_aug = 16
    y = np.empty(n_aug)
    for j in range(6):
        y[j] = s6[j]
    slip = p[_SLIP] > 0.5
    a, d = p[4], p[5]
    if aux[12] < 0.5:  # first step: the wheels roll with the body's twist
        aux[0] = (s6[3] - d * s6[5]) / a
        aux[1] = (s6[3] + d * s6[5]) / a
        aux[12] = 1.0
    if not slip:
        y[4] = 0.0
    y[6], y[7] = aux[0], aux[1]
    for j in range(8):
        y[8 + j] = aux[2 + j]
    loads = np.empty(layout.shape[0])
    k1, k2, k3, k4, tmp = (np.empty(n_aug), np.empty(n_aug), np.empty(n_aug),
                           np.empty(n_aug), np.empty(n_aug))  # fmt: skip
    info = np.zeros(8)
    scratch = np.zeros(8)
    remaining = dt
    substeps = 0
    while remaining > 1e-15 * dt and substeps < MAX_SUBSTEPS:
        _update_loads(y, aux, p, layout, ainv, slope, cells, geo, loads)
        lam = _stiffness(y, p, layout, loads, table, cells, geo)
        h = remaining
        if lam * h > p[_FACTOR]:
            left = MAX_SUBSTEPS - substeps
            h = max(p[_FACTOR] / lam, remaining / left)
            h = min(h, remaining)
        _rhs(y, tl, tr, p, layout, loads, table, cells, slope, geo, k1, info)
        aux[10], aux[11] = info[0], info[1]
        for j in range(n_aug):
            tmp[j] = y[j] + 0.5 * h * k1[j]
        _rhs(tmp, tl, tr, p, layout, loads, table, cells, slope, geo, k2, scratch)
        for j in range(n_aug):
            tmp[j] = y[j] + 0.5 * h * k2[j]
        _rhs(tmp, tl, tr, p, layout, loads, table, cells, slope, geo, k3, scratch)
        for j in range(n_aug):
            tmp[j] = y[j] + h * k3[j]
        _rhs(tmp, tl, tr, p, layout, loads, table, cells, slope, geo, k4, scratch)
        for j in range(n_aug):
            y[j] += h / 6.0 * (k1[j] + 2.0 * k2[j] + 2.0 * k3[j] + k4[j])
        remaining -= h
        substeps += 1
    y[2] = wrap_angle_scalar(y[2])
    for j in range(6):
        s6[j] = y[j]
    if slip:
        aux[0], aux[1] = y[6], y[7]
    else:
        aux[0] = (y[3] - d * y[5]) / a
        aux[1] = (y[3] + d * y[5]) / a
    for j in range(8):
        aux[2 + j] = y[8 + j]
    # the signals at the new state
    _update_loads(y, aux, p, layout, ainv, slope, cells, geo, loads)
    _rhs(y, tl, tr, p, layout, loads, table, cells, slope, geo, k1, info)
    aux[10], aux[11] = info[0], info[1]
    for k in range(2):
        sig[k] = info[2 + k]
        sig[2 + k] = info[4 + k]
        sig[4 + k] = loads[k]
        sig[6 + k] = info[6 + k]
        c, s = math.cos(y[2]), math.sin(y[2])
        wy = layout[k, 1]
        sig[8 + k] = _surface_at(y[0] - s * wy, y[1] + c * wy, cells, geo)[0]
    sig[10] = substeps


@numba.njit(cache=True)
def terrain_step(states, aux, torques, dt, p, layout, ainv, table, cells, slope, geo, signals):
    """Advance every robot (rows of ``states`` (N, 6), ``aux`` (N, 13)) by ``dt`` in place.

    Parameters
    ----------
    states : numpy.ndarray, shape (N, 6)
        (x, y, ψ, u, v, r).
    aux : numpy.ndarray, shape (N, 13)
        Auxiliary rows (:data:`AUX_NAMES`).
    torques : numpy.ndarray, shape (N, 2)
        Wheel torques (left, right) [N·m], held over the step.
    dt : float
        Step [s].
    p, layout, ainv, table, cells, slope, geo : numpy.ndarray
        The compiled model (:meth:`TerrainDynamics.kernel_args`).
    signals : numpy.ndarray, shape (N, 11)
        Filled with :data:`SIGNAL_NAMES` at the new state.
    """
    for i in range(states.shape[0]):
        _advance(states[i], aux[i], torques[i, 0], torques[i, 1], dt, p, layout, ainv, table,
                 cells, slope, geo, signals[i])  # fmt: skip


# --------------------------------------------------------------------------- the model
@dataclass(frozen=True)
class TerrainDynamics:
    """A differential drive on terrain (module docstring): rigid contact or wheel slip.

    Parameters
    ----------
    dynamics : DiffDriveDynamics
        The rigid body and wheels of document 000 (e.g. :data:`wheelbase.dynamics.RM100`, or a
        body with its payload); must be ``constrained`` (the slip model frees v itself).
    terrain : TerrainMap
        The ground.
    contacts : WheelContacts
        Drive-wheel width and spin inertia, casters, load sharing, CG height.
    slip : bool
        Wheel slip (True) or rigid rolling contact (False).
    slip_speed : float
        v_ε [m/s], in [:data:`MIN_SLIP_SPEED`, 10]: the speed below which the slip ratio's
        denominator stops shrinking (a smaller one is more exact at standstill and stiffer to
        integrate).
    step_factor : float
        Largest h·λ of a substep (RK4 is stable to 2.78 on a real eigenvalue), in (0, 2.5].
    gravity : float
        g [m/s²], > 0.

    Examples
    --------
    >>> from wheelbase.dynamics import RM100
    >>> from wheelbase.terrain.surfaces import SURFACES
    >>> model = TerrainDynamics(RM100, TerrainMap.uniform(SURFACES["ice"]))
    >>> model.state_names[:2]
    ('omega_left', 'omega_right')
    """

    dynamics: DiffDriveDynamics
    terrain: TerrainMap
    contacts: WheelContacts = RM100_CONTACTS
    slip: bool = True
    slip_speed: float = 0.05
    step_factor: float = 1.0
    gravity: float = GRAVITY
    _args: tuple = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        if not isinstance(self.dynamics, DiffDriveDynamics):
            raise ConfigError(
                f"dynamics must be a DiffDriveDynamics (got {type(self.dynamics).__name__})"
            )
        if not self.dynamics.constrained:
            raise ConfigError("give the constrained (no lateral slip) model: slip frees v itself")
        if self.dynamics.rolling_resistance != 0.0:
            raise ConfigError(
                "the terrain's surfaces give the rolling resistance: use a DiffDriveDynamics "
                "with rolling_resistance 0"
            )
        if not isinstance(self.terrain, TerrainMap):
            raise ConfigError(f"terrain must be a TerrainMap (got {type(self.terrain).__name__})")
        if not isinstance(self.contacts, WheelContacts):
            raise ConfigError(
                f"contacts must be WheelContacts (got {type(self.contacts).__name__})"
            )
        object.__setattr__(self, "slip", bool(self.slip))
        slip_speed = positive("slip_speed", self.slip_speed, "m/s")
        if not MIN_SLIP_SPEED <= slip_speed <= 10.0:
            raise ConfigError(
                f"slip_speed must be in [{MIN_SLIP_SPEED:g}, 10] m/s (got {slip_speed:g}): "
                "below, the slip at standstill is too stiff to integrate"
            )
        object.__setattr__(self, "slip_speed", slip_speed)
        factor = positive("step_factor", self.step_factor)
        if factor > 2.5:
            raise ConfigError(f"step_factor must be in (0, 2.5] (got {factor:g})")
        object.__setattr__(self, "step_factor", factor)
        object.__setattr__(self, "gravity", positive("gravity", self.gravity, "m/s²"))
        p = np.zeros(_PARAMS)
        p[:10] = self.dynamics.params
        c = self.contacts
        p[_JW], p[_WIDTH] = c.wheel_inertia, c.wheel_width
        p[_CASTER_R], p[_CASTER_B], p[_HEIGHT] = c.caster_radius, c.caster_width, c.cg_height
        p[_VEPS], p[_G], p[_SLIP], p[_FACTOR] = self.slip_speed, self.gravity, self.slip, factor
        terrain = self.terrain
        geo = np.array([terrain.origin[0], terrain.origin[1], terrain.resolution])
        args = (
            p,
            np.ascontiguousarray(c.layout(self.dynamics.half_track)),
            np.ascontiguousarray(c.load_matrix(self.dynamics.half_track)),
            np.ascontiguousarray(terrain.table),
            terrain.cells,
            terrain.slope,
            geo,
        )
        object.__setattr__(self, "_args", args)

    @property
    def state_names(self) -> tuple[str, ...]:
        """Names of the auxiliary row (:data:`AUX_NAMES`)."""
        return AUX_NAMES

    def kernel_args(self) -> tuple:
        """(p, layout, ainv, table, cells, slope, geo) for :func:`terrain_step`."""
        return self._args

    def with_dynamics(self, dynamics: DiffDriveDynamics) -> TerrainDynamics:
        """The same ground and contacts under another body (a payload picked up).

        Parameters
        ----------
        dynamics : DiffDriveDynamics
            The new rigid-body model.
        """
        return TerrainDynamics(
            dynamics, self.terrain, self.contacts, self.slip, self.slip_speed,
            self.step_factor, self.gravity,
        )  # fmt: skip

    def start(self, n: int) -> np.ndarray:
        """Auxiliary rows ``(n, 13)`` of robots at rest (wheel rates set at the first step).

        Parameters
        ----------
        n : int
            Number of robots.
        """
        return np.zeros((integer("n", n, minimum=1), _AUX))

    def step(
        self, state: ArrayLike, aux: np.ndarray, torques: ArrayLike, dt: float
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Advance states ``(N, 6)`` by ``dt`` under wheel torques held over the step.

        Parameters
        ----------
        state : array_like, shape (N, 6)
            (x [m], y [m], ψ [rad], u [m/s], v [m/s], r [rad/s]).
        aux : numpy.ndarray, shape (N, 13)
            Auxiliary rows (:meth:`start`), not changed.
        torques : array_like, shape (N, 2)
            Wheel torques (left, right) [N·m].
        dt : float
            Step [s], > 0.

        Returns
        -------
        state, aux, signals : numpy.ndarray
            The new states and auxiliary rows and the signals ``(N, 11)`` of
            :data:`SIGNAL_NAMES`.
        """
        s = np.array(as_float_array("state", state, 6, min_ndim=2, max_ndim=2))
        tau = np.array(as_float_array("torques", torques, 2, min_ndim=2, max_ndim=2))
        if tau.shape[0] != s.shape[0] or aux.shape != (s.shape[0], _AUX):
            raise ConfigError(f"state {s.shape}, aux {aux.shape} and torques {tau.shape} disagree")
        new_aux = np.array(aux, dtype=np.float64)
        signals = np.zeros((s.shape[0], _SIG))
        terrain_step(s, new_aux, tau, positive("dt", dt, "s"), *self._args, signals)
        return s, new_aux, signals

    def kinetic_energy(self, state: ArrayLike, aux: np.ndarray) -> np.ndarray:
        """T = ½VᵀMV + ½J_w(ω_L² + ω_R²) [J] (the wheels' spin only with slip).

        Parameters
        ----------
        state : array_like, shape (..., 6)
            States.
        aux : numpy.ndarray, shape (..., 13)
            Their auxiliary rows.
        """
        s = as_float_array("state", state, 6)
        body = self.dynamics.body.kinetic_energy(s[..., 3:])
        if not self.slip:
            return body
        spin = 0.5 * self.contacts.wheel_inertia * (aux[..., 0] ** 2 + aux[..., 1] ** 2)
        return body + spin

    def energy_balance(
        self, state0: ArrayLike, aux0: np.ndarray, state: ArrayLike, aux: np.ndarray
    ) -> dict[str, np.ndarray]:
        """The terms of W = ΔT − W_gravity + dissipation between two states [J].

        Parameters
        ----------
        state0, aux0 : array_like
            The earlier states and auxiliary rows.
        state, aux : array_like
            The later ones.

        Returns
        -------
        dict
            ``work`` (of the wheel torques), ``kinetic`` (ΔT), ``gravity`` (work done against
            gravity), ``slip``, ``rolling``, ``soil``, ``damping`` and ``residual``
            (work − everything else).
        """
        diff = np.asarray(aux) - np.asarray(aux0)
        kinetic = self.kinetic_energy(state, aux) - self.kinetic_energy(state0, aux0)
        terms = {
            "work": diff[..., 4],
            "kinetic": kinetic,
            "gravity": -diff[..., 9],
            "slip": diff[..., 5],
            "rolling": diff[..., 6],
            "soil": diff[..., 7],
            "damping": diff[..., 8],
        }
        spent = sum(terms[k] for k in ("kinetic", "gravity", "slip", "rolling", "soil", "damping"))
        terms["residual"] = terms["work"] - spent
        return terms
