"""Hybrid A*'s lattice: its motion primitives, and the samples of arcs, straight lines and
turns in place along a path (the primitives' and the curve shots' alike).

A primitive is a table of poses relative to the node it leaves, sampled every collision step,
with its direction, curvature, length, base cost and sweep (the farthest a covering circle of
the checked footprint moves along it, which lets the search skip collision samples that the
distance field vouches for). Used by :mod:`wheelbase.planning.hybrid_astar`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from wheelbase.errors import ConfigError
from wheelbase.limits import MAX_PRIMITIVE_SAMPLES
from wheelbase.planning.footprint import Footprint

__all__: list[str] = []

_ROTATE = 2  # segment type code for a turn in place (length = signed angle [rad])


@dataclass(frozen=True)
class _Primitives:
    offsets: np.ndarray  # (P, S, 3) poses relative to the node, padded
    nsamples: np.ndarray  # (P,)
    direction: np.ndarray  # (P,) +1/-1, 0 for turns in place
    kappa: np.ndarray  # (P,) steering curvature, ±inf for turns in place
    length: np.ndarray  # (P,) distance travelled [m]
    cost: np.ndarray  # (P,) base cost [m]
    sweep: np.ndarray  # (P,) farthest any covering-circle centre moves [m]


def _build_primitives(
    *,
    turning_radius: float,
    reverse: bool,
    curvatures: int,
    headings: int,
    length: float,
    step: float,
    non_straight_penalty: float,
    reverse_penalty: float,
    turn_in_place_cost: float,
    footprint: Footprint,
    checked: Footprint,
    swap_directions: bool = False,
) -> _Primitives:
    """The motion primitives of a lattice: arcs of ``curvatures`` curvatures in
    ``[−1/R, 1/R]`` (a straight line for ``turning_radius`` 0) of ``length`` [m], forward and
    (with ``reverse``) backward, sampled every ``step`` [m], plus turns in place of one, an
    eighth and a quarter of the heading bins for a robot that turns in place; costs by the
    penalties (``swap_directions``: the reverse penalty on forward motion, for the search from
    the goal). ``checked`` is the footprint the search checks (grown by its margin): its
    covering circles bound each primitive's sweep."""
    ds = length
    rows: list[tuple[np.ndarray, int, float, float, float]] = []
    dirs = (1, -1) if reverse else (1,)
    # Every primitive is sampled every collision_step and tried at every expansion: refuse
    # a table that would not fit (curvatures=3e7 hung, collision_step=1e-9 m alike).
    arcs = len(dirs) * (curvatures if turning_radius > 0 else 1)
    samples = arcs * max(1, math.ceil(min(ds / step, 1e15)))
    if samples > MAX_PRIMITIVE_SAMPLES:
        raise ConfigError(
            f"{arcs} motion primitives of {ds:.3g} m sampled every {step:.3g} m need "
            f"{samples:.3g} samples: more than {MAX_PRIMITIVE_SAMPLES:g}; use fewer "
            "curvatures or a larger collision_step"
        )
    if turning_radius > 0:
        kmax = 1.0 / turning_radius
        kappas = np.linspace(-kmax, kmax, curvatures)
    else:
        kappas = np.array([0.0])
    for d in dirs:
        for k in kappas:
            n = max(1, math.ceil(ds / step))
            s = d * ds * np.arange(1, n + 1) / n
            offs = _arc_offsets(float(k), s)
            cost = ds * (non_straight_penalty if k != 0 else 1.0)
            cost *= reverse_penalty if (d > 0 if swap_directions else d < 0) else 1.0
            rows.append((offs, d, float(k), ds, cost))
    if turning_radius == 0:
        bin_angle = 2.0 * math.pi / headings
        rho = footprint.max_radius
        for nb in sorted({1, max(1, headings // 8), max(1, headings // 4)}):
            for sign in (1.0, -1.0):
                angle = sign * nb * bin_angle
                n = max(1, math.ceil(abs(angle) * rho / step))
                offs = np.zeros((n, 3))
                offs[:, 2] = angle * np.arange(1, n + 1) / n
                rows.append((offs, 0, sign * math.inf, 0.0, turn_in_place_cost * nb * bin_angle))
    rho_c = float(np.max(np.hypot(*checked.circles.T)))
    sweep = [
        r[3] * (1.0 + (abs(r[2]) if np.isfinite(r[2]) else 0.0) * rho_c)
        + abs(r[0][-1, 2] if not np.isfinite(r[2]) else 0.0) * rho_c
        for r in rows
    ]
    nmax = max(r[0].shape[0] for r in rows)
    offsets = np.zeros((len(rows), nmax, 3))
    for i, r in enumerate(rows):
        offsets[i, : len(r[0])] = r[0]
    return _Primitives(
        offsets,
        np.array([len(r[0]) for r in rows], dtype=np.int64),
        np.array([r[1] for r in rows], dtype=np.int64),
        np.array([r[2] for r in rows]),
        np.array([r[3] for r in rows]),
        np.array([r[4] for r in rows]),
        np.array(sweep),
    )


def _arc_offsets(kappa: float, s: np.ndarray) -> np.ndarray:
    """Poses after signed distances ``s`` along an arc of curvature ``kappa`` from the origin."""
    if kappa == 0.0:
        return np.stack([s, np.zeros_like(s), np.zeros_like(s)], -1)
    th = kappa * s
    return np.stack([np.sin(th) / kappa, (1.0 - np.cos(th)) / kappa, th], -1)


def _compose(base: np.ndarray, offs: np.ndarray) -> np.ndarray:
    c, s = math.cos(base[2]), math.sin(base[2])
    out = np.empty_like(offs)
    out[:, 0] = base[0] + c * offs[:, 0] - s * offs[:, 1]
    out[:, 1] = base[1] + s * offs[:, 0] + c * offs[:, 1]
    out[:, 2] = base[2] + offs[:, 2]
    return out


def _sample_segment(
    pose: np.ndarray, kind: int, length: float, radius: float, step: float, rho: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    if kind == _ROTATE:
        n = max(1, math.ceil(abs(length) * rho / step))
        offs = np.zeros((n, 3))
        offs[:, 2] = length * np.arange(1, n + 1) / n
        kappa = math.copysign(math.inf, length)
        return _compose(pose, offs), np.zeros(n, np.int64), np.full(n, kappa), np.zeros(n)
    n = max(1, math.ceil(abs(length) / step))
    s = length * np.arange(1, n + 1) / n
    kappa = kind / radius if kind != 0 else 0.0
    seg = _compose(pose, _arc_offsets(kappa, s))
    d = 1 if length > 0 else -1
    return seg, np.full(n, d), np.full(n, kappa), np.full(n, abs(length) / n)
