"""UMBmark: measuring and correcting systematic odometry errors (Borenstein & Feng 1996).

J. Borenstein and L. Feng, "Measurement and correction of systematic odometry errors in mobile
robots", IEEE Trans. Robotics and Automation 12(6), 1996. The robot drives a square of side L
(4 m) using only its odometry, ``runs`` times clockwise (cw) and counter-clockwise (ccw); after
each run the return position error ε = (true − odometry) of the final position is measured.
The centres of gravity (x_cg, y_cg) of the cw and ccw errors and

    E_max,syst = max(√(x_cg,cw² + y_cg,cw²), √(x_cg,ccw² + y_cg,ccw²))

measure the systematic error. Two error types explain them: type A, every nominal 90° turn is
off by α (a wrong track), and type B, each straight leg curves by β (unequal wheel diameters).

Conventions here: the robot starts at the origin facing +x; a ccw run turns left (the square
lies in y > 0), a cw run turns right. α > 0 means each turn falls *short* of 90°, β > 0 that
the legs curve to the left. Linearising the four legs in α and β (derived again for these
conventions; the printed forms agree):

    ε_cw  = −2L(β + α)·(1, 1),      ε_ccw = 2L(β − α)·(1, −1)

so that (Borenstein & Feng eqs. 11.a/b, from the x errors)

    α = (x_cg,cw + x_cg,ccw)/(−4L),    β = (x_cg,cw − x_cg,ccw)/(−4L).

The y errors carry the same information with the signs arranged differently
(α = (y_cg,cw − y_cg,ccw)/(−4L), β = (y_cg,cw + y_cg,ccw)/(−4L)); :func:`umbmark_correction`
averages both estimates, which halves the noise. The corrections (eqs. 12–17):

    R = (L/2)/sin(β/2),   E_d = D_R/D_L = (R + b/2)/(R − b/2),   E_b = (π/2)/(π/2 − α),

the track becomes b' = E_b·b and the wheel distances are scaled by c_L = 2/(E_d + 1) and
c_R = 2/(1/E_d + 1) (the mean diameter is kept).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from wheelbase._validate import check_choice, integer, positive
from wheelbase.errors import ConfigError
from wheelbase.models.diffdrive import DiffDrive
from wheelbase.odometry.dead_reckoning import WheelOdometry, integrate_increments
from wheelbase.odometry.error_model import OdometryErrors

__all__ = [
    "UMBmarkCalibration",
    "UMBmarkCorrection",
    "UMBmarkResult",
    "calibrate_umbmark",
    "umbmark_correction",
    "umbmark_test",
]


@dataclass(frozen=True)
class UMBmarkResult:
    """Return position errors of a bidirectional square test.

    Attributes
    ----------
    errors_cw, errors_ccw : numpy.ndarray, shape (runs, 2)
        Return position errors ε = true − odometry (x, y) [m] of each run.
    paths_cw, paths_ccw : numpy.ndarray, shape (runs, 9, 3)
        True poses at the start and after each leg and turn of each run.
    side : float
        Side L of the square [m].
    """

    errors_cw: np.ndarray
    errors_ccw: np.ndarray
    paths_cw: np.ndarray
    paths_ccw: np.ndarray
    side: float

    @property
    def cg_cw(self) -> np.ndarray:
        """Centre of gravity (x, y) [m] of the cw errors."""
        return self.errors_cw.mean(axis=0)

    @property
    def cg_ccw(self) -> np.ndarray:
        """Centre of gravity (x, y) [m] of the ccw errors."""
        return self.errors_ccw.mean(axis=0)

    @property
    def e_max_syst(self) -> float:
        """E_max,syst [m]: the larger distance of the two centres of gravity from the origin."""
        return float(max(np.hypot(*self.cg_cw), np.hypot(*self.cg_ccw)))


@dataclass(frozen=True)
class UMBmarkCorrection:
    """Correction factors estimated from a square test.

    Attributes
    ----------
    alpha : float
        Type-A error: how far each 90° turn falls short [rad].
    beta : float
        Type-B error: heading change over one leg, positive to the left [rad].
    diameter_ratio : float
        Estimated E_d = D_R/D_L of the robot relative to its odometry model [–].
    track_ratio : float
        Estimated E_b = b_actual/b_model [–].
    half_track : float
        Corrected half track [m] (b'/2).
    scale_left, scale_right : float
        Corrected wheel-distance factors [–] (the old ones × c_L, c_R).
    """

    alpha: float
    beta: float
    diameter_ratio: float
    track_ratio: float
    half_track: float
    scale_left: float
    scale_right: float

    @property
    def track(self) -> float:
        """Corrected track b' [m]."""
        return 2.0 * self.half_track

    def apply(self, odometry: WheelOdometry) -> WheelOdometry:
        """``odometry`` with the corrected track and wheel factors."""
        return replace(
            odometry,
            half_track=self.half_track,
            scale_left=self.scale_left,
            scale_right=self.scale_right,
        )


def umbmark_test(
    robot: DiffDrive,
    errors: OdometryErrors,
    odometry: WheelOdometry,
    side: float = 4.0,
    runs: int = 5,
    seed: int | None = 0,
) -> UMBmarkResult:
    """Simulate the bidirectional square test of a robot that drives by its odometry.

    Parameters
    ----------
    robot : DiffDrive
        The nominal geometry (wheel radius, half track) of the real robot.
    errors : OdometryErrors
        How the real robot differs from ``robot``: E_d, E_b and slip.
    odometry : WheelOdometry
        The robot's odometry model (nominal or already corrected); it plans each leg and turn
        in wheel rotations and stops on the nearest encoder tick.
    side : float
        Side L of the square [m], > 0 (UMBmark uses 4 m).
    runs : int
        Runs in each direction, >= 1 (UMBmark uses 5).
    seed : int or None
        Seed of the random errors: where within the last tick each wheel stops (uniform) and
        the slip of ``errors``.

    Returns
    -------
    UMBmarkResult
        The return position errors of every run.
    """
    side = positive("side", side, "m")
    runs = integer("runs", runs, minimum=1)
    rng = np.random.default_rng(None if seed is None else integer("seed", seed, minimum=0))
    r, ppr = odometry.wheel_radius, odometry.pulses_per_revolution
    tick = 2.0 * math.pi / ppr
    # Planned wheel rotations [rad] of one leg and of one left turn, from the odometry model.
    leg = np.array([side / (r * odometry.scale_left), side / (r * odometry.scale_right)])
    arc = 0.5 * math.pi * odometry.half_track
    turn = np.array([-arc / (r * odometry.scale_left), arc / (r * odometry.scale_right)])
    out: dict[str, tuple[np.ndarray, np.ndarray]] = {}
    for direction, sign in (("cw", -1.0), ("ccw", 1.0)):
        plan = np.array([leg, sign * turn] * 4)  # (8, 2): leg, turn, leg, turn, ...
        ticks = np.round(plan / tick)  # the robot stops on the nearest tick
        errs, paths = [], []
        for _ in range(runs):
            true_angles = (ticks + rng.uniform(-0.5, 0.5, ticks.shape)) * tick
            dc, phi = errors.ground_increments(
                robot.wheel_radius, robot.half_track, true_angles, rng
            )
            true_path = integrate_increments([0.0, 0.0, 0.0], dc, phi, "exact")
            estimate = odometry.integrate([0.0, 0.0, 0.0], ticks)
            errs.append(true_path[-1, :2] - estimate[-1, :2])
            paths.append(true_path)
        out[direction] = (np.array(errs), np.array(paths))
    return UMBmarkResult(
        errors_cw=out["cw"][0],
        errors_ccw=out["ccw"][0],
        paths_cw=out["cw"][1],
        paths_ccw=out["ccw"][1],
        side=side,
    )


def umbmark_correction(
    result: UMBmarkResult, odometry: WheelOdometry, use: str = "xy"
) -> UMBmarkCorrection:
    """Estimate α, β and the corrections from a square test (module docstring).

    Parameters
    ----------
    result : UMBmarkResult
        The test (:func:`umbmark_test`, or measured return errors of a real robot).
    odometry : WheelOdometry
        The odometry model the test was driven with; its track and scale factors are corrected.
    use : {"xy", "x"}
        ``x``: Borenstein & Feng's formulas from the x errors only; ``xy``: the mean of the x and
        y estimates.

    Returns
    -------
    UMBmarkCorrection
        α, β, E_d, E_b and the corrected half track and wheel factors.
    """
    check_choice("use", use, ("xy", "x"))
    big_l = result.side
    (x_cw, y_cw), (x_ccw, y_ccw) = result.cg_cw, result.cg_ccw
    alpha = (x_cw + x_ccw) / (-4.0 * big_l)
    beta = (x_cw - x_ccw) / (-4.0 * big_l)
    if use == "xy":
        alpha = 0.5 * (alpha + (y_cw - y_ccw) / (-4.0 * big_l))
        beta = 0.5 * (beta + (y_cw + y_ccw) / (-4.0 * big_l))
    if not abs(alpha) < 0.5 * math.pi or not abs(beta) < math.pi:
        raise ConfigError(
            f"the square test errors are too large for UMBmark (alpha={alpha:g}, beta={beta:g} rad)"
        )
    b = odometry.track
    k = b * math.sin(0.5 * beta) / big_l  # (b/2)/R with R = (L/2)/sin(β/2)
    diameter_ratio = (1.0 + k) / (1.0 - k)
    track_ratio = 0.5 * math.pi / (0.5 * math.pi - alpha)
    c_left = 2.0 / (diameter_ratio + 1.0)
    c_right = 2.0 / (1.0 / diameter_ratio + 1.0)
    return UMBmarkCorrection(
        alpha=float(alpha),
        beta=float(beta),
        diameter_ratio=diameter_ratio,
        track_ratio=track_ratio,
        half_track=odometry.half_track * track_ratio,
        scale_left=odometry.scale_left * c_left,
        scale_right=odometry.scale_right * c_right,
    )


@dataclass(frozen=True)
class UMBmarkCalibration:
    """A square test, the correction it gives, and the test again with the correction.

    Attributes
    ----------
    before : UMBmarkResult
        Test with the nominal odometry.
    correction : UMBmarkCorrection
        Estimated from ``before``.
    after : UMBmarkResult
        Test with the corrected odometry (new random draws).
    """

    before: UMBmarkResult
    correction: UMBmarkCorrection
    after: UMBmarkResult

    @property
    def reduction(self) -> float:
        """E_max,syst before / after [–]."""
        return self.before.e_max_syst / self.after.e_max_syst


def calibrate_umbmark(
    diameter_ratio: float = 1.005,
    track_ratio: float = 1.02,
    *,
    wheel_radius: float = 0.05,
    half_track: float = 0.2,
    pulses_per_revolution: int = 4096,
    side: float = 4.0,
    runs: int = 5,
    slip_std: float = 0.0,
    iterations: int = 1,
    seed: int | None = 0,
) -> UMBmarkCalibration:
    """Inject E_d and E_b into a simulated robot, run UMBmark, correct and run it again.

    Parameters
    ----------
    diameter_ratio : float
        Injected E_d = D_R/D_L [–], > 0.
    track_ratio : float
        Injected E_b = b_actual/b_nominal [–], > 0.
    wheel_radius : float
        Nominal wheel radius [m], > 0.
    half_track : float
        Nominal half track [m], > 0.
    pulses_per_revolution : int
        Encoder resolution [ticks/rev], > 0.
    side : float
        Square side [m], > 0.
    runs : int
        Runs in each direction, >= 1.
    slip_std : float
        Random relative wheel slip per segment [–] (0: quantisation is the only random error).
    iterations : int
        Test-and-correct rounds, >= 1. One round is UMBmark; a second round, driven with the
        corrected odometry, removes most of what the linearisation left (large errors).
    seed : int or None
        Seed of the random errors.

    Returns
    -------
    UMBmarkCalibration
        The first test, the final (composed) correction, and the test with it.

    Examples
    --------
    >>> cal = calibrate_umbmark(1.005, 1.02)
    >>> bool(cal.reduction > 10)
    True
    """
    errors = OdometryErrors(diameter_ratio, track_ratio, slip_std)
    robot = DiffDrive(wheel_radius=wheel_radius, half_track=half_track)
    odometry = WheelOdometry(wheel_radius, half_track, pulses_per_revolution, "exact")
    base_seed = None if seed is None else integer("seed", seed, minimum=0)
    if isinstance(iterations, bool) or not isinstance(iterations, (int, np.integer)):
        raise ConfigError(f"iterations must be an integer >= 1 (got {iterations!r})")
    if iterations < 1:
        raise ConfigError(f"iterations must be an integer >= 1 (got {iterations})")
    before = umbmark_test(robot, errors, odometry, side, runs, base_seed)
    test, model = before, odometry
    for round_ in range(int(iterations)):
        correction = umbmark_correction(test, model)
        model = correction.apply(model)
        next_seed = None if base_seed is None else base_seed + 1 + round_
        test = umbmark_test(robot, errors, model, side, runs, next_seed)
    # Report E_d, E_b of the composed correction against the nominal model.
    ratio = correction.scale_right / correction.scale_left
    correction = replace(
        correction, diameter_ratio=ratio, track_ratio=model.half_track / odometry.half_track
    )
    return UMBmarkCalibration(before, correction, test)
