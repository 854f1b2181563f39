"""Lidar pose-graph SLAM: scan-to-submap matching, keyframes, loop closures, optimisation.

For each scan, in time order:

1. **Prediction.** The pose change since the previous scan is the odometry's where the log
   has odometry and ``use_odometry`` is set, else the previous scan's pose change again
   (constant velocity).
2. **Scan-to-submap matching.** The scan is matched (:class:`ScanMatcher`: the correlative
   search around the prediction over ``linear_window`` × ``angular_window``, refined by
   point-to-line ICP) against the points of the last ``submap_keyframes`` keyframes at their
   current estimates. A match whose mean likelihood is below ``min_score`` keeps the
   prediction (counted in ``failed_matches``). With odometry, the match is fused with the
   prediction, each weighed by its covariance (``odometry_std``). With ``last_check`` the
   match is checked against the last keyframe alone (scan to scan), which a submap bent by
   the drift of its older keyframes does not mislead.
3. **Keyframes.** A scan becomes a keyframe when the robot has moved ``keyframe_distance`` or
   turned ``keyframe_angle`` since the last one; it is a vertex of the pose graph, joined to
   the previous keyframe by an edge: the relative pose of the two matched poses, with the
   match's covariance (with odometry: the fused one) expressed in the new keyframe's frame
   (the frame of the residual) and floored at ``min_std``. With ``local_frontend`` the front
   end (prediction, submap, edges) keeps the keyframes' poses as it matched them, and the
   graph places each new keyframe by its edge from the last one (Cartographer's split of
   local and global SLAM, Hess et al. 2016): the sequential edges are those of a run without
   loop closures, whatever the closures do to the graph.
4. **Loop closure.** Every ``loop_every`` keyframes, the keyframes at least
   ``loop_min_separation`` keyframes older whose estimate lies within ``loop_radius`` of the
   current one are candidates (the nearest ``loop_candidates``, one per stretch of the path).
   Each candidate's submap (its neighbours along the path) is searched by branch and bound
   over the wide window ``loop_linear_window`` × ``loop_angular_window`` around the current
   estimate, pruned below ``loop_min_score``; a found pose is refined by ICP and gated: at least
   ``loop_min_inliers`` of the scan's points within the ICP's pairing distance and an RMS
   point-to-line distance at most ``loop_max_rms``; with ``loop_gate``, a closure whose squared
   Mahalanobis distance from the graph's estimate exceeds it is rejected (``loops_gated``):
   the relative pose's covariance is propagated along the sequential edges from the candidate
   to the current keyframe (an upper bound of the graph's, which the loop edges only tighten)
   and the closure's ``loop_std`` added. An accepted closure is an edge between the candidate
   and the current keyframe, and the graph is optimised (:func:`optimize_pose_graph`, dynamic
   covariance scaling on the loop edges against false closures; with ``robust_sequential`` on
   every edge). The scans after the last keyframe follow it rigidly.
5. **Relocalisation** (``relocalize``). Each scan is searched for again in the final map:
   the keyframes nearest its estimate (``relocalize_keyframes`` within ``relocalize_radius``,
   its own left out) at their optimised poses, by the correlative search over
   ``relocalize_window`` refined by ICP. The found pose replaces the estimate when ICP from it
   stays within a matcher cell, at least ``loop_min_inliers`` of the points pair, their RMS
   point-to-line distance is at most the matcher's ``huber``, it lies more than a cell from
   the estimate, and its likelihood (:meth:`ScanMatcher.likelihood`) beats the estimate's (or
   that of ICP from the estimate, where ICP stays within a cell) by ``relocalize_gain``: a
   scan that the front end placed in an aliased spot and that no closure reaches (the first
   scan of a log without odometry has no earlier keyframe to close against) is put where the
   rest of the map says it is. Only the scans' estimates move, not the graph.
6. **The map** is rendered from the final poses (:class:`OccupancyMapper`).
"""

from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass, field

import numpy as np

from wheelbase._validate import flag, integer, nonnegative, positive
from wheelbase.datasets.g2o import PoseGraph
from wheelbase.datasets.scans import ScanLog, stamps_advance
from wheelbase.errors import ConfigError, DataError
from wheelbase.geometry import compose, inverse_pose, relative_pose
from wheelbase.mapping.occupancy import LogOddsMap, OccupancyMapper
from wheelbase.mapping.posegraph import optimize_pose_graph
from wheelbase.mapping.scan_matching import (
    LikelihoodTable,
    MatchResult,
    PointReference,
    ScanMatcher,
    _transform,
    scan_points,
    surface_points,
)
from wheelbase.mapping.se2 import se2_adjoint, se2_log

__all__ = ["LidarSlam", "SlamResult", "SlamSession", "turn_prior"]

_LOOP_TABLES_KEPT = 8  # candidate submaps whose tables a session keeps


@dataclass(frozen=True)
class LidarSlam:
    """Parameters of lidar SLAM (module docstring); one set for every log.

    Parameters
    ----------
    matcher : ScanMatcher
        Scan-to-submap matcher (search cell 0.1 m, σ 0.05 m, ±1.5 m, ±90° by default, σ 0.1 m
        in :meth:`without_odometry`: the CARMEN logs' scans are up to 1.5 m and 78° apart).
    max_range : float
        Readings beyond this are not matched [m].
    min_score : float
        Least mean likelihood of a scan-to-submap match.
    prior_std : tuple of float
        Standard deviations of the prediction as a prior of the match (translation [m],
        rotation [rad]).
    turn_prior : bool
        Without odometry, the prior's rotation standard deviation is at least the last step's
        turn (:func:`turn_prior`; :meth:`without_odometry`: on): the constant-velocity
        prediction knows the next turn no better than the last one. In the FHW museum's log
        the robot turns back and forth by up to 63° a scan (scan 58: +63° after −32°), the
        prediction was 95° off and 15° of prior ranked a wrong pose first; the chain broke and
        the start's part of the map turned 86° (relative error 0.49 m, loop relations 1.8 m;
        with it 0.052 m and 0.048 m). CSAIL 0.067 → 0.045 m, Intel 0.0322 m (± 0.026 →
        0.025), ACES 0.0388 m and the MIT infinite corridor 0.17 m unchanged, no other Radish
        log worse (``benchmarks/README.md``). Halving the predicted turn instead: CSAIL 0.040
        m, but ACES 0.0399 m; both together broke CSAIL's loops.
    odometry_gate : tuple of float
        With odometry, a match farther than this from the odometry's prediction (translation
        [m], rotation [rad]) is not believed: the prediction is kept (``failed_matches``).
    keyframe_distance, keyframe_angle : float
        Motion that makes a keyframe [m], [rad].
    submap_keyframes : int
        Keyframes in the local submap.
    min_std : tuple of float
        Floor of a sequential edge's standard deviations (x [m], y [m], θ [rad]). In
        simulation with odometry (maze and warehouse, 60 and 360 beams) the edges' real errors
        were 2.7–3.4 mm along, 1.1–1.8 mm across and 0.02–0.10° rms (χ² 0.09–0.15 under this
        floor instead of 3), but a floor of 1 mm and 0.01° with the loop edges' covariance
        from the match (χ² 4–12 for both kinds of edge), measured 0.0142 / 0.0254 / 0.0192 /
        0.0294 m ATE on the four simulated cases (0.0148 / 0.0261 / 0.0192 / 0.0296 m with
        this floor), sent the warehouse's exploration astray (ATE 0.34 m, 93 % explored): a
        graph that sure of itself follows a wrong closure.
    use_odometry : bool
        Predict with the log's odometry (when it has one).
    loop_every : int
        Search for loop closures at every n-th keyframe.
    loop_min_separation : int
        Least keyframes between a candidate and the current keyframe.
    loop_radius : float
        Candidates within this distance of the current estimate [m].
    loop_candidates : int
        Most candidates per search.
    loop_linear_window, loop_angular_window : float
        Half-widths of the loop-closure search [m], [rad].
    loop_min_score : float
        Least mean likelihood of a closure.
    loop_min_inliers : float
        Least fraction of points ICP pairs.
    loop_max_rms : float
        Largest RMS point-to-line distance [m].
    loop_submap : int
        Keyframes on each side of a candidate in its submap.
    loop_std : tuple of float
        Standard deviations of a loop edge (x [m], y [m], θ [rad]). In simulation the
        closures' real errors were 4.4–6.6 mm along and 1.7–3.6 mm across (χ² 0.01–0.04), one of
        234 aliased: 2.7 m along a warehouse aisle, which the robust kernel weighs to nothing.
    loop_gate : float or None
        Largest squared Mahalanobis distance of a closure from the graph's estimate, e.g. 16.27
        (χ² with 3 degrees of freedom at 0.999), None for no gate (the default; step 4). In
        simulation it rejected the aliased closure and no true one, the ATE unchanged (the
        kernel had weighed it to nothing); in the warehouse's exploration, with
        ``local_frontend``, ATE 0.080 m against 0.037 m without it (97.7 % against 98.1 %
        explored), with the front end re-anchored 0.017 m against 0.040 m: left off there
        until understood. :meth:`without_odometry` gates at 16.27: along the MIT infinite
        corridor, whose walls look alike for hundreds of metres, closures aliased along it
        broke the big loop (relative error 1.00 m, loop relations 5.33 m; gated 0.17 m, 0.70 m,
        12 closures rejected); Intel unchanged (0.0322 m, none rejected), ACES 0.0390 → 0.0388
        m, CSAIL 0.0668 → 0.0665 m, FHW unchanged.
    robust_scale : float
        Φ of dynamic covariance scaling on the loop edges.
    two_stage : bool
        Solve the graph first without a robust kernel, then from that solution with dynamic
        covariance scaling (:meth:`without_odometry`: on). From an estimate that the front end
        left metres off along a corridor, the kernel alone weighed Intel's true closures of its
        first loop down to nothing (residuals of 2.4 m on edges whose own error was 2–5 cm).
    anchor_by_overlap : bool
        A closure's edge joins the keyframe of the candidate's submap whose own scan the match
        overlaps most, not the candidate (:meth:`without_odometry`: on): a candidate misplaced
        against its neighbours (Intel's scan 0, 0.5 m) carried its error into every closure.
    optimize_every : int
        Optimise after every n-th accepted closure (and at the end).
    surfaces : bool
        Submaps (local and of loop closures) hold each keyframe's returns filled in along the
        surfaces between neighbouring beams (:func:`surface_points`), not the returns alone
        (:meth:`without_odometry`: on). Without odometry, along a corridor whose walls the
        last keyframe sampled sparsely, the next scan matched best on the same samples: Intel
        scans 108–110 and 822–826, ACES 46 and 252 matched 0–0.6 m short of 1 m steps.
    odometry_std : tuple of float or None
        With odometry, a match is fused with the odometry's prediction (the product of the two
        Gaussians, the match's covariance against the prediction's): the prediction's standard
        deviations are ``a``·d + 1 mm in x and y and ``b``·(|Δθ| + d / 1 m) + 10⁻⁴ rad in θ
        for a step of d [m] and Δθ [rad] since the previous scan (``(a, b)``, [m/m] and
        [rad/rad]); None keeps the match alone. The match alone slid along the simulated
        warehouse's aisles with a 60-beam lidar (steps 9 times the odometry's error, 4 cm off
        where the aisle's two walls were all it saw): ATE 0.090 m, fused 0.030 m (0.034 m with
        ``a = b = 0.01``, 0.038 m with 0.05).
    local_frontend : bool
        The front end matches against its own keyframe poses, not the optimised ones (step 3;
        :meth:`without_odometry`: off, where re-anchoring on the corrected graph stops a slide).
        Matching against the submap as the optimisation moved it bent the front end: the
        sequential edges of the simulated maze's run with closures, chained, were 0.021 m ATE
        off against 0.013 m without closures (360 beams; 60 beams 0.032 against 0.026 m).
    robust_sequential : bool
        The robust kernel weighs the sequential edges too, not only the closures
        (:meth:`without_odometry`: on). Without odometry a wrong step of the front end is as
        sure of itself as a right one (floored at ``min_std``, 5 times the closures'
        ``loop_std``), and the kernel weighed the true closures against it to nothing: Intel's
        scans 1-11 (a turn on the spot where the scene repeats 0.45 m along the robot's
        heading) stayed 0.45 m off scans 0 and 12 against closures from scans 105-108 and
        754-755. Relative error without and with: Intel 0.040 / 0.036 m, 0.51 / 0.49°; ACES
        0.041 / 0.047 m (the chain broke in ACES's corridor at scans 314-318), with
        :attr:`keyframe_normals` 0.039 / 0.039 m.
    keyframe_normals : bool
        The ICP reference of a submap joins each keyframe's own lines (fitted once, in its own
        frame: ``PointReference.merge``) instead of fitting lines to the submap's merged
        points at every new keyframe (:meth:`without_odometry`: on). Refitting took 24 of the
        52 s that Intel's front end spent; own lines are not blurred by the neighbouring
        keyframes' scatter. Without and with (no ``robust_sequential``): Intel 0.040 / 0.041 m,
        0.51 / 0.48°, 62 / 46 s; ACES 0.041 / 0.039 m, 0.31 / 0.31°, 39 / 24 s.
    last_check : bool
        Check each submap match against the last keyframe alone (:meth:`without_odometry`:
        on; ``SlamSession._check_last``): ICP against that keyframe's own reference from the
        match; where it moves the pose more than a matcher cell, across a direction the
        keyframe constrains, and the two references' summed likelihood prefers the moved pose,
        that pose is the match. A submap of 30 keyframes whose oldest had drifted 5–20 cm
        from the newest (Intel scans 752–781) ranked a pose 0.4 m across the true one first
        (7–69 % of the scan's points within 5 cm of the last keyframe's there, 46–91 % at the
        reference's pose), and the chain broke at scans 781, 793, 798 and 814 (0.36–0.45 m
        relative errors that the closures did not undo); the check
        replaced those 4 matches and left 1 (Intel) and 4 (ACES, the corridor of scans
        314–318, where the scan-to-scan pose slid 1.3 m along it) as unconstrained. Without
        and with: Intel 0.0364 ± 0.047 / 0.0335 ± 0.036 m, 0.48 / 0.47°; ACES unchanged
        (0.0390 ± 0.031 m, 0.31°).
    relocalize : bool
        Step 5 (:meth:`without_odometry`: on; needs :attr:`keyframe_normals`). On Intel it
        moved scan 0 alone, by 0.53 m (likelihood gain 24.9, RMS 5.6 mm, all points paired):
        turning on the spot where the scene repeats every ~0.45 m, the first match put scan 1
        half a period from scan 0, and the optimiser holds the first vertex fixed, so the
        closures of scans 106-108 and 188 could not move it. Intel 0.0335 ± 0.036 / 0.0322 ±
        0.026 m (loops 0.0343 / 0.0300 m) without / with; on ACES it moves
        nothing (scan 315 alone passed the other gates, with an RMS of 49 mm).
    relocalize_keyframes : int
        Keyframes of the map a scan is relocalised in (the nearest).
    relocalize_radius : float
        Only keyframes this close to the scan's estimate [m].
    relocalize_window : tuple of float
        Half-widths of the search (translation [m], rotation [rad]).
    relocalize_gain : float
        Least log-likelihood gain that moves a scan.
    mapper : OccupancyMapper
        The map's parameters (the counting model by default: with log odds and hits first, the
        free cell before a wall's face, where range noise puts half the returns short of the
        face, came out occupied, and the simulated maze's map from its true poses agreed with
        the truth on 97.1 % of the cells both know, from the SLAM poses 97.0 %; counted, 100 %
        and 99.1 %).
    """

    matcher: ScanMatcher = field(default_factory=lambda: ScanMatcher(
        resolution=0.1, sigma=0.05, linear_window=1.5, angular_window=math.radians(90.0),
        max_correspondence=0.3, huber=0.03))  # fmt: skip
    max_range: float = 30.0
    min_score: float = 0.2
    prior_std: tuple[float, float] = (0.2, math.radians(15.0))
    odometry_gate: tuple[float, float] = (0.05, math.radians(2.0))
    keyframe_distance: float = 0.2
    keyframe_angle: float = math.radians(10.0)
    submap_keyframes: int = 12
    min_std: tuple[float, float, float] = (0.01, 0.01, math.radians(0.5))
    use_odometry: bool = False
    loop_every: int = 2
    loop_min_separation: int = 25
    loop_radius: float = 5.0
    loop_candidates: int = 2
    loop_linear_window: float = 3.0
    loop_angular_window: float = math.radians(30.0)
    loop_min_score: float = 0.45
    loop_min_inliers: float = 0.7
    loop_max_rms: float = 0.05
    loop_submap: int = 6
    loop_std: tuple[float, float, float] = (0.05, 0.05, math.radians(1.0))
    robust_scale: float = 1.0
    two_stage: bool = False
    anchor_by_overlap: bool = False
    optimize_every: int = 1
    surfaces: bool = False
    odometry_std: tuple[float, float] | None = (0.02, 0.02)
    mapper: OccupancyMapper = field(default_factory=lambda: OccupancyMapper(model="counting"))
    local_frontend: bool = True
    loop_gate: float | None = None
    robust_sequential: bool = False
    keyframe_normals: bool = False
    last_check: bool = False
    turn_prior: bool = False
    relocalize: bool = False
    relocalize_keyframes: int = 30
    relocalize_radius: float = 5.0
    relocalize_window: tuple[float, float] = (0.6, math.radians(10.0))
    relocalize_gain: float = 5.0

    def __post_init__(self) -> None:
        for name in ("max_range", "keyframe_distance", "keyframe_angle", "loop_radius",
                     "loop_linear_window", "loop_angular_window", "loop_max_rms",
                     "robust_scale"):  # fmt: skip
            positive(name, getattr(self, name))
        for name in ("submap_keyframes", "loop_every", "loop_min_separation",
                     "loop_candidates", "loop_submap", "optimize_every"):  # fmt: skip
            integer(name, getattr(self, name), 1)
        if self.last_check and not self.keyframe_normals:
            # the check matches against the last keyframe's own reference, which only
            # keyframe_normals keeps: without it the option would do nothing
            raise ConfigError("last_check needs keyframe_normals=True")
        if self.relocalize and not self.keyframe_normals:
            raise ConfigError("relocalize needs keyframe_normals=True")
        positive("relocalize_radius", self.relocalize_radius)
        integer("relocalize_keyframes", self.relocalize_keyframes, 1)
        window = self.relocalize_window
        if not (isinstance(window, tuple | list) and len(window) == 2):
            raise ConfigError(f"relocalize_window must be (metres, radians) (got {window!r})")
        for value in window:
            positive("relocalize_window", value)
        nonnegative("relocalize_gain", self.relocalize_gain)
        for item in dataclasses.fields(self):
            if isinstance(item.default, bool):  # the switches: "no" would read as on
                flag(item.name, getattr(self, item.name))

    @classmethod
    def without_odometry(cls, **overrides: object) -> LidarSlam:
        """The parameters for logs without odometry (scan matching alone, as CARMEN's
        corrected logs): a 30-keyframe submap (a longer history holds the door frames and
        corners that fix the position along a corridor: ACES's scan-to-scan slides over 0.3 m
        summed to 14.5 m with 12 keyframes, 1.5 m with 30), the loop search ±5 m within 8 m
        (the drift when a big loop comes back exceeds 3 m), :attr:`two_stage` and
        :attr:`anchor_by_overlap`, :attr:`surfaces` and a matcher table of σ = 0.1 m (one
        cell: with σ 0.05 m the correlative optimum on the 0.1 m grid fell between a
        corridor's true pose and one 0.8 m short, ACES scans 314–322). Relative translation
        error against the logs' corrected poses: Intel 0.41 ± 0.98 m → 0.20 ± 0.66 m (as
        measured before the surfaces) → 0.040 ± 0.057 m → 0.036 ± 0.047 m (with
        :attr:`robust_sequential` and :attr:`keyframe_normals`), ACES 0.70 ± 2.40 m → 0.084 ±
        0.22 m → 0.041 ± 0.034 m → 0.039 ± 0.031 m; with :attr:`last_check` Intel 0.0335 ±
        0.036 m, ACES unchanged; with :attr:`relocalize` Intel 0.0322 ± 0.026 m, ACES
        unchanged; :attr:`loop_gate` 16.27 and :attr:`turn_prior`. Kept off with odometry,
        which bridges a corridor (and the exploration loop's time stays).

        Parameters
        ----------
        **overrides : object
            Further parameters (the class's names).

        Returns
        -------
        LidarSlam
        """
        base = {"submap_keyframes": 30, "loop_linear_window": 5.0, "loop_radius": 8.0,
                "local_frontend": False, "two_stage": True,
                "anchor_by_overlap": True, "surfaces": True, "robust_sequential": True,
                "keyframe_normals": True, "last_check": True, "relocalize": True,
                "loop_gate": 16.27, "turn_prior": True,
                "matcher": ScanMatcher(resolution=0.1, sigma=0.1, linear_window=1.5,
                                       angular_window=math.radians(90.0),
                                       max_correspondence=0.3, huber=0.03)}  # fmt: skip
        return cls(**{**base, **overrides})

    def run(self, log: ScanLog, *, snapshot_every: int = 0) -> SlamResult:
        """SLAM over a whole log (module docstring).

        Parameters
        ----------
        log : ScanLog
            The scans (a reader's record).
        snapshot_every : int
            Keep the estimated trajectory after every n-th scan (for the animation of the map
            growing), 0 for none.

        Returns
        -------
        SlamResult

        Raises
        ------
        DataError
            A log with no scan, or no scan with a usable return.
        """
        if log.n_scans == 0:
            raise DataError(f"{log.source or 'the log'} holds no scan")
        session = self.session(log.angles, log.max_range, mount=log.mount, source=log.source,
                               snapshot_every=snapshot_every)  # fmt: skip
        session.add(log.ranges, log.odometry, log.t)
        return session.result()

    def session(
        self,
        angles: np.ndarray,
        max_range: float,
        *,
        mount: tuple[float, float, float] | np.ndarray = (0.0, 0.0, 0.0),
        source: str = "",
        snapshot_every: int = 0,
    ) -> SlamSession:
        """An incremental run: scans are added as they come (:meth:`SlamSession.add`) and the
        result asked for at any time; the result after adding a log's scans in any number of
        batches equals :meth:`run` on the log (the same computation, continued).

        Parameters
        ----------
        angles : numpy.ndarray, shape (B,)
            Beam angles in the sensor frame [rad].
        max_range : float
            The sensor's largest reading [m].
        mount : array_like, shape (3,)
            Sensor pose in the robot frame [m, m, rad].
        source : str
            Name of the data for messages.
        snapshot_every : int
            As in :meth:`run`.

        Returns
        -------
        SlamSession
        """
        return SlamSession(self, np.asarray(angles, np.float64), float(max_range),
                           np.asarray(mount, np.float64), source, int(snapshot_every))  # fmt: skip

    def render(self, log: ScanLog, poses: np.ndarray, **kwargs) -> LogOddsMap:
        """The occupancy map of ``log`` from robot ``poses`` (e.g. the SLAM estimate).

        Parameters
        ----------
        log : ScanLog
            The scans.
        poses : numpy.ndarray, shape (N, 3)
            A robot pose per scan.
        **kwargs
            Passed to :meth:`OccupancyMapper.build` (``max_cells``, ``margin``).

        Returns
        -------
        LogOddsMap
        """
        return self.mapper.build(poses, log.ranges, log.angles, mount=log.mount,
                                 sensor_max_range=log.max_range, **kwargs)  # fmt: skip

    def _tables(self, world, parts=None, poses=None):
        """The matcher's tables of a submap's points; with ``parts`` (the keyframes' own
        references, :attr:`keyframe_normals`) at ``poses`` the ICP reference joins them instead
        of fitting lines to the merged points. (Penalising the points that land in the free
        space the submap's scans saw was measured worse on Intel: local relations 0.061 m
        against 0.056 m, loop relations 2.9 m against 1.7 m.)"""
        table = LikelihoodTable.build(world, self.matcher.resolution, self.matcher.sigma)
        if parts is not None:
            return table, PointReference.merge(parts, poses)
        return table, PointReference.build(world)

    def _edge_information(self, cov: np.ndarray, theta: float) -> np.ndarray:
        """Ω of an edge from a world-frame covariance of the new pose: rotated into the pose's
        frame (that of the residual Log(Z⁻¹X_i⁻¹X_j)), floored at ``min_std``."""
        c, s = math.cos(theta), math.sin(theta)
        rot = np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])
        body = rot @ cov @ rot.T
        body = 0.5 * (body + body.T) + np.diag(np.square(self.min_std))
        return np.linalg.inv(body)

    def _close_loops(self, points, kf_points, kf_scan, kf_pose, edges, meas, info, loop_edge,
                     stats, cache=None, kf_refs=None):  # fmt: skip
        """Step 4 of the module docstring at the newest keyframe; True when a closure was
        accepted. ``cache`` (a dict kept by the session) holds the tables of the last
        candidate submaps with their keyframes' poses: the next search usually picks the same
        candidate, and until the graph is optimised its submap is the same."""
        j = len(kf_scan) - 1
        if j < self.loop_min_separation:
            return False
        stats["loop_searches"] += 1
        current = kf_pose[j]
        older = np.array(kf_pose[: j - self.loop_min_separation + 1])
        d = np.hypot(*(older[:, :2] - current[:2]).T)
        near = np.flatnonzero(d <= self.loop_radius)
        if near.size == 0:
            return False
        # the nearest candidates, one per stretch of the path (candidates ≥ 2·submap apart)
        chosen: list[int] = []
        for c in near[np.argsort(d[near])]:
            if all(abs(int(c) - o) > 2 * self.loop_submap for o in chosen):
                chosen.append(int(c))
            if len(chosen) >= self.loop_candidates:
                break
        closed = False
        matcher = self.matcher
        for c in chosen:
            stats["loop_candidates"] += 1
            lo, hi = max(0, c - self.loop_submap), min(j - self.loop_min_separation,
                                                       c + self.loop_submap)  # fmt: skip
            keys = range(lo, hi + 1)
            poses = np.array([kf_pose[i] for i in keys])
            hit = cache.get((lo, hi)) if cache is not None else None
            if hit is not None and np.array_equal(hit[0], poses):
                table, reference = hit[1], hit[2]
            else:
                world = np.vstack([_transform(kf_pose[i], kf_points[i]) for i in keys])
                table, reference = self._tables(
                    world, None if kf_refs is None else [kf_refs[i] for i in keys], poses
                )
                if cache is not None:
                    cache.pop((lo, hi), None)
                    cache[(lo, hi)] = (poses, table, reference)
                    while len(cache) > _LOOP_TABLES_KEPT:
                        cache.pop(next(iter(cache)))
            found = matcher.match(table, reference, points[kf_scan[j]], current,
                                  linear_window=self.loop_linear_window,
                                  angular_window=self.loop_angular_window,
                                  min_score=self.loop_min_score)  # fmt: skip
            if (
                found is None
                or found.inliers < self.loop_min_inliers
                or not (found.rms <= self.loop_max_rms)
            ):
                stats["loops_rejected"] += 1
                continue
            loop_info = np.diag(1.0 / np.square(self.loop_std))
            if self.loop_gate is not None:
                z = relative_pose(kf_pose[c], found.pose)
                if (
                    _closure_chi2(kf_pose, meas, info, loop_edge, c, j, z, loop_info)
                    > self.loop_gate
                ):
                    stats["loops_rejected"] += 1
                    stats["loops_gated"] += 1
                    continue
            stats["loops_accepted"] += 1
            if self.anchor_by_overlap:
                c = _most_overlapped(kf_pose, kf_scan, points, keys, found.pose, points[kf_scan[j]],
                                     0.5 * matcher.max_correspondence)  # fmt: skip
            edges.append((c, j))
            meas.append(relative_pose(kf_pose[c], found.pose))
            info.append(loop_info)
            loop_edge.append(True)
            closed = True
        return closed

    def _optimize(self, kf_pose, edges, meas, info, loop_edge) -> None:
        graph = PoseGraph(np.arange(len(kf_pose)), np.array(kf_pose),
                          np.array(edges, np.int64), np.array(meas), np.array(info))  # fmt: skip
        if self.two_stage:  # the closures first without a kernel (``two_stage``)
            first = optimize_pose_graph(graph, max_iterations=20, tolerance=1e-6)
            graph = PoseGraph(graph.ids, first.poses, graph.edges, graph.measurements,
                              graph.information)  # fmt: skip
        result = optimize_pose_graph(graph, robust="dcs", robust_scale=self.robust_scale,
                                     robust_edges=(None if self.robust_sequential
                                                   else np.array(loop_edge, bool)),
                                     max_iterations=20, tolerance=1e-6)  # fmt: skip
        for k, p in enumerate(result.poses):
            kf_pose[k] = p


class SlamSession:
    """The state of an incremental :class:`LidarSlam` run (made by :meth:`LidarSlam.session`):
    the keyframes, the pose graph and the submap carry over from one :meth:`add` to the next,
    so that the work per scan does not grow with the scans before it (except at a loop
    closure, which re-optimises the graph)."""

    def __init__(self, slam, angles, max_range, mount, source, snapshot_every) -> None:
        self.slam = slam
        self.angles, self.max_range, self.mount = angles, max_range, mount
        self.source, self.snapshot_every = source, snapshot_every
        self.points: list[np.ndarray] = []
        self.usable: list[bool] = []
        self.odometry: list[np.ndarray] | None = None
        self.times: list[float] = []
        self.offsets: list[np.ndarray] = []  # each scan's pose relative to its keyframe
        self.frontend: list[np.ndarray] = []
        self.anchor: list[int] = []  # the keyframe each scan hangs from
        self.kf_scan: list[int] = []
        self.kf_points: list[np.ndarray] = []  # a keyframe's points in submaps (``surfaces``)
        self.loop_tables: dict = {}  # candidate submaps' tables (LidarSlam._close_loops)
        # each keyframe's ICP reference in its own frame (``keyframe_normals``)
        self.kf_refs: list[PointReference] | None = [] if slam.keyframe_normals else None
        self._last_ref: tuple[tuple, PointReference] | None = None  # see _last_reference
        self.kf_pose: list[np.ndarray] = []
        # the front end's keyframe poses: the graph's own, or (``local_frontend``) the poses
        # as matched, which the optimisation leaves alone
        self.kf_local: list[np.ndarray] = [] if slam.local_frontend else self.kf_pose
        self.edges: list[tuple[int, int]] = []
        self.meas: list[np.ndarray] = []
        self.info: list[np.ndarray] = []
        self.loop_edge: list[bool] = []
        self.stats = {"failed_matches": 0, "loop_searches": 0, "loop_candidates": 0,
                      "loops_accepted": 0, "loops_rejected": 0, "loops_gated": 0,
                      "skipped_scans": 0, "optimizations": 0, "last_checks": 0,
                      "last_degenerate": 0, "relocalized": 0}  # fmt: skip
        self.snapshots: list[tuple[int, np.ndarray]] = []
        self.first: int | None = None
        self.pose = self.previous = self.velocity = np.zeros(3)
        self.table = self.reference = None
        self.since_closure = 0
        self.pending_optimizations = 0
        self.processing_time_s = 0.0

    @property
    def n_scans(self) -> int:
        """Scans added so far."""
        return len(self.points)

    def add(self, ranges: np.ndarray, odometry: np.ndarray | None = None,
            times: np.ndarray | None = None) -> None:  # fmt: skip
        """Process more scans, in time order after those added before.

        Parameters
        ----------
        ranges : numpy.ndarray, shape (M, B)
            Readings [m] (NaN or out of range: no return).
        odometry : numpy.ndarray, shape (M, 3), optional
            Odometry pose at each scan [m, m, rad], in one frame with the earlier ones; used
            when the SLAM's ``use_odometry`` is set. Give it with every batch or with none.
        times : numpy.ndarray, shape (M,), optional
            Scan times [s] (for ``duration_s``).

        Raises
        ------
        DataError
            Odometry given with some batches and not others, or shapes that do not match.
        """
        tick = time.perf_counter()
        slam = self.slam
        ranges = np.asarray(ranges, np.float64).reshape(-1, self.angles.size)
        m = ranges.shape[0]
        use = slam.use_odometry and odometry is not None
        if self.points and use != (self.odometry is not None):
            raise DataError(f"{self.source or 'the log'}: odometry with every batch or none")
        if use:
            odometry = np.asarray(odometry, np.float64)
            if odometry.shape != (m, 3):
                raise DataError(f"{self.source or 'the log'}: odometry shape {odometry.shape} "
                                f"for {m} scans")  # fmt: skip
            if self.odometry is None:
                self.odometry = []
            self.odometry.extend(odometry)
        if times is not None:
            self.times.extend(np.asarray(times, np.float64).reshape(-1)[:m].tolist())
        reach = min(slam.max_range, self.max_range)
        for row in ranges:
            self.points.append(scan_points(row, self.angles, reach, mount=self.mount))
            self.usable.append(self.points[-1].shape[0] >= 10)
            self._step(len(self.points) - 1)
        self.processing_time_s += time.perf_counter() - tick

    def _rebuild_submap(self):
        slam, kf_scan, kf_pose = self.slam, self.kf_scan, self.kf_local
        first_kf = max(0, len(kf_scan) - slam.submap_keyframes)
        keys = range(first_kf, len(kf_scan))
        world = np.vstack([_transform(kf_pose[k], self.kf_points[k]) for k in keys])
        if self.kf_refs is None:
            return slam._tables(world)
        return slam._tables(world, [self.kf_refs[k] for k in keys], [kf_pose[k] for k in keys])

    def _add_keyframe(self, scan: int, p: np.ndarray, cov: np.ndarray | None) -> None:
        kf_scan, kf_pose = self.kf_scan, self.kf_local
        kf_scan.append(scan)
        if kf_pose is not self.kf_pose:  # the graph's vertex: placed by the edge from the last
            self.kf_pose.append(compose(self.kf_pose[-1], relative_pose(kf_pose[-1], p))
                                if self.kf_pose else p.copy())  # fmt: skip
        kf_pose.append(p.copy())
        own = self.points[scan]
        self.kf_points.append(surface_points(own) if self.slam.surfaces else own)
        if self.kf_refs is not None:
            self.kf_refs.append(PointReference.build(self.kf_points[-1]))
        if cov is not None:
            i = len(kf_scan) - 2
            self.edges.append((i, i + 1))
            self.meas.append(relative_pose(kf_pose[i], p))
            self.info.append(self.slam._edge_information(cov, p[2]))
            self.loop_edge.append(False)

    def _last_reference(self) -> PointReference:
        """The last keyframe's own ICP reference placed at its pose: made again only when a
        keyframe is added or the graph moves the last one, not for every scan."""
        key = (len(self.kf_refs), self.kf_local[-1].tobytes())
        if self._last_ref is None or self._last_ref[0] != key:
            placed = PointReference.merge([self.kf_refs[-1]], [self.kf_local[-1]])
            self._last_ref = (key, placed)
        return self._last_ref[1]

    def _check_last(self, k: int, result: MatchResult, guess: np.ndarray) -> MatchResult:
        """The submap match of scan ``k``, or the pose that point-to-line ICP against the last
        keyframe alone moves it to where both references together like that one better
        (``LidarSlam.last_check``).

        The alternative is taken when it lies more than a matcher cell from the match, it is
        not a move along the direction the last keyframe leaves unconstrained (the smaller
        eigenvalue of the ICP's xy information below 0.2 of the larger and the move within
        45° of its axis: a corridor, where scan-to-scan slides and the submap's history
        decides), and the sum of the likelihoods (:meth:`ScanMatcher.likelihood`) against the
        submap and against the last keyframe is higher there; it is then refined against the
        submap when that raises the sum.
        """
        slam = self.slam
        matcher = slam.matcher
        last = self._last_reference()
        points = self.points[k]
        alt, alt_cov, alt_in, alt_rms = matcher.icp(last, points, result.pose)
        jump = alt[:2] - result.pose[:2]
        if math.hypot(jump[0], jump[1]) <= matcher.resolution:
            return result
        lam, axes = np.linalg.eigh(np.linalg.inv(alt_cov)[:2, :2])
        along = abs(jump @ axes[:, 0]) / math.hypot(jump[0], jump[1])
        if lam[0] < 0.2 * lam[1] and along > math.cos(math.radians(45.0)):
            self.stats["last_degenerate"] += 1
            return result

        def both(q: np.ndarray) -> float:
            return matcher.likelihood(self.reference, points, q, guess, slam.prior_std) + (
                matcher.likelihood(last, points, q, guess, slam.prior_std)
            )

        if both(alt) <= both(result.pose):
            return result
        self.stats["last_checks"] += 1
        sub, sub_cov, sub_in, sub_rms = matcher.icp(self.reference, points, alt)
        if both(sub) > both(alt):
            alt, alt_cov, alt_in, alt_rms = sub, sub_cov, sub_in, sub_rms
        return MatchResult(alt, alt_cov + np.diag([1e-6, 1e-6, 1e-8]), result.score, alt_in,
                           alt_rms)  # fmt: skip

    def _relocalize(self, estimate: np.ndarray, kf: np.ndarray) -> int:
        """Step 5 of the module docstring on ``estimate`` in place, in the map of the
        keyframes at ``kf``; returns the number of scans moved."""
        slam = self.slam
        matcher = slam.matcher
        kf_scan = np.asarray(self.kf_scan)
        moved = 0
        cached = None
        for k, points in enumerate(self.points):
            if not self.usable[k]:
                continue
            d = np.hypot(kf[:, 0] - estimate[k, 0], kf[:, 1] - estimate[k, 1])
            near = np.argsort(d)[: slam.relocalize_keyframes + 1]
            keys = [int(i) for i in near if d[i] <= slam.relocalize_radius and kf_scan[i] != k]
            keys = keys[: slam.relocalize_keyframes]
            if len(keys) < 2:
                continue
            if cached is None or cached[0] != keys:  # neighbouring scans share their map
                world = np.vstack([_transform(kf[i], self.kf_points[i]) for i in keys])
                parts = [self.kf_refs[i] for i in keys]
                cached = (keys, *slam._tables(world, parts, kf[keys]))
            table, reference = cached[1], cached[2]
            found = matcher.correlative(table, points, estimate[k],
                                        linear_window=slam.relocalize_window[0],
                                        angular_window=slam.relocalize_window[1],
                                        min_score=slam.min_score)  # fmt: skip
            # most scans are where the map puts them: nothing more to do
            if found is None or math.hypot(*(found[0][:2] - estimate[k, :2])) <= matcher.resolution:
                continue
            # the found pose must hold under ICP, pass a closure's inlier gate and fit the map
            # within ICP's Huber scale: along a corridor the coarse table can rank the window's
            # edge first where ICP slides back (Intel scans 12-82 alone: the first scan, 0.6 m
            # off), and where the map itself disagrees along a corridor a pose that fits it
            # loosely can still score higher (ACES scan 315: 0.2 m along, RMS 0.049 m)
            pose, _, inliers, rms = matcher.icp(reference, points, found[0])
            if (
                math.hypot(*(pose[:2] - found[0][:2])) > matcher.resolution
                or inliers < slam.loop_min_inliers
                or not rms <= matcher.huber
                or math.hypot(*(pose[:2] - estimate[k, :2])) <= matcher.resolution
            ):
                continue
            # the estimate at its best nearby: ICP from it, unless ICP itself leaves the cell
            here, *_ = matcher.icp(reference, points, estimate[k])
            starts = [estimate[k]]
            if math.hypot(*(here[:2] - estimate[k, :2])) <= matcher.resolution:
                starts.append(here)
            fits = [matcher.likelihood(reference, points, q, q, (1, 1)) for q in [pose, *starts]]
            if fits[0] - max(fits[1:]) > slam.relocalize_gain:
                estimate[k] = pose
                moved += 1
        return moved

    def _odometry_cov(self, k: int) -> np.ndarray:
        """World-frame covariance of the odometry's prediction of scan ``k`` from scan k − 1
        (``LidarSlam.odometry_std``)."""
        step = relative_pose(self.odometry[k - 1], self.odometry[k])
        a, b = self.slam.odometry_std
        moved = math.hypot(step[0], step[1])
        s_xy = a * moved + 1e-3
        s_th = b * (abs(step[2]) + moved) + 1e-4
        return np.diag([s_xy * s_xy, s_xy * s_xy, s_th * s_th])

    def _step(self, k: int) -> None:
        """Scan ``k`` through steps 1–4 of the module docstring."""
        slam, stats, odometry = self.slam, self.stats, self.odometry
        if self.first is None:
            if not self.usable[k]:  # before the first usable scan: follows the first keyframe
                self.anchor.append(-1)
                self.offsets.append(np.zeros(3))
                self.frontend.append(np.zeros(3))
                return
            self.first = k
            self.pose = odometry[k].copy() if odometry is not None else np.zeros(3)
            self.previous = self.pose.copy()
            self.velocity = np.zeros(3)
        first, pose = self.first, self.pose
        if not self.usable[k]:
            stats["skipped_scans"] += 1
            self.anchor.append(len(self.kf_scan) - 1)
            self.offsets.append(pose.copy())
            self.frontend.append(pose.copy())
            return
        if odometry is not None and k > first:
            guess = compose(pose, relative_pose(odometry[k - 1], odometry[k]))
        else:
            guess = compose(pose, self.velocity)
        if self.table is None:
            pose = guess
            self._add_keyframe(k, pose, None)
            self.table, self.reference = self._rebuild_submap()
            cov = None
        else:
            # the same window with odometry: a narrower one (±0.3 m, ±10°, prior 5 cm)
            # was measured worse on the maze (ATE 0.095 m against 0.016 m)
            prior = slam.prior_std
            if slam.turn_prior and odometry is None:
                prior = turn_prior(prior, float(self.velocity[2]))
            result = slam.matcher.match(self.table, self.reference, self.points[k], guess,
                                        prior_std=prior)  # fmt: skip
            if result is not None and slam.last_check and self.kf_refs is not None:
                result = self._check_last(k, result, guess)
            if result is not None and odometry is not None:
                jump = relative_pose(guess, result.pose)
                if (np.hypot(jump[0], jump[1]) > slam.odometry_gate[0]
                        or abs(jump[2]) > slam.odometry_gate[1]):  # fmt: skip
                    result = None  # farther from the odometry than it drifts in a scan
            if result is None or result.score < slam.min_score:
                stats["failed_matches"] += 1
                pose, cov = guess, np.diag([0.1, 0.1, 0.05]) ** 2
            else:
                pose, cov = result.pose, result.covariance
                if odometry is not None and slam.odometry_std is not None:
                    pose, cov = _fuse(pose, cov, guess, self._odometry_cov(k))
        self.velocity = relative_pose(self.previous, pose) if odometry is None else np.zeros(3)
        self.previous = pose.copy()
        last = self.kf_local[-1]
        moved = relative_pose(last, pose)
        if k != self.kf_scan[-1] and (np.hypot(moved[0], moved[1]) >= slam.keyframe_distance
                                      or abs(moved[2]) >= slam.keyframe_angle):  # fmt: skip
            self._add_keyframe(k, pose, cov)
            self.since_closure += 1
            closed = False
            if len(self.kf_scan) % slam.loop_every == 0:
                closed = slam._close_loops(self.points, self.kf_points, self.kf_scan,
                                           self.kf_pose, self.edges, self.meas, self.info,
                                           self.loop_edge, stats, self.loop_tables,
                                           self.kf_refs)  # fmt: skip
            if closed:
                self.pending_optimizations += 1
            if self.pending_optimizations >= slam.optimize_every:
                slam._optimize(self.kf_pose, self.edges, self.meas, self.info, self.loop_edge)
                stats["optimizations"] += 1
                self.pending_optimizations = 0
                if not slam.local_frontend:
                    pose = self.kf_pose[-1].copy()
                    self.previous = pose.copy()
            self.table, self.reference = self._rebuild_submap()
        self.anchor.append(len(self.kf_scan) - 1)
        # the scan's pose relative to its keyframe: follows it when the graph moves
        self.offsets.append(relative_pose(self.kf_local[self.anchor[k]], pose))
        self.frontend.append(compose(self.kf_pose[-1], self.offsets[-1]) if slam.local_frontend
                             else pose.copy())  # fmt: skip
        self.pose = pose
        if self.snapshot_every and (k - first) % self.snapshot_every == 0:
            self.snapshots.append((k, np.array(self.kf_pose)))

    def result(self) -> SlamResult:
        """The estimate after the scans added so far; the session can go on after it (the
        final optimisation :meth:`LidarSlam.run` makes is applied to a copy of the graph).

        Returns
        -------
        SlamResult

        Raises
        ------
        DataError
            No scan yet, or no scan with a usable return.
        """
        tick = time.perf_counter()
        slam, stats = self.slam, dict(self.stats)
        if not self.points:
            raise DataError(f"{self.source or 'the log'} holds no scan")
        if self.first is None:
            raise DataError(
                f"{self.source or 'the log'}: no scan has 10 returns within {slam.max_range:g} m"
            )
        kf_pose = [p.copy() for p in self.kf_pose]
        if (self.pending_optimizations or not stats["optimizations"]) and any(self.loop_edge):
            slam._optimize(kf_pose, self.edges, self.meas, self.info, self.loop_edge)
            stats["optimizations"] += 1
        n, first = len(self.points), self.first
        kf = np.array(kf_pose)
        offsets = np.array(self.offsets).reshape(n, 3)
        estimate = np.empty((n, 3))
        for k in range(n):
            a = self.anchor[k]
            if a < 0:  # scans before the first usable one
                estimate[k] = kf[0]
            elif k >= first and self.usable[k]:
                estimate[k] = compose(kf[a], offsets[k])
            else:
                estimate[k] = kf[a]
        if slam.relocalize:
            stats["relocalized"] = self._relocalize(estimate, kf)
        graph = PoseGraph(
            np.arange(len(self.kf_scan)), kf, np.array(self.edges, np.int64).reshape(-1, 2),
            np.array(self.meas).reshape(-1, 3), np.array(self.info).reshape(-1, 3, 3),
        )  # fmt: skip
        loop_edge = np.array(self.loop_edge, bool)
        loops = graph.edges[loop_edge] if loop_edge.any() else np.zeros((0, 2), int)
        kf_scan = np.array(self.kf_scan, np.int64)
        # stamps that are not times (one for every scan, a jump to 2³² s) give no duration
        timed = len(self.times) == n and stamps_advance(np.array(self.times))
        duration = float(self.times[-1] - self.times[0]) if timed else 0.0
        processing = self.processing_time_s + time.perf_counter() - tick
        return SlamResult(
            poses=estimate,
            frontend_poses=np.array(self.frontend).reshape(n, 3),
            keyframes=kf_scan,
            graph=graph,
            loop_edges=loop_edge,
            loops=kf_scan[loops] if len(loops) else np.zeros((0, 2), int),
            processing_time_s=processing,
            duration_s=duration,
            stats=stats,
            snapshots=list(self.snapshots),
            anchors=np.array(self.anchor, np.int64),
            offsets=offsets,
        )


def turn_prior(prior_std: tuple[float, float], last_turn: float) -> tuple[float, float]:
    """The match's prior (``LidarSlam.turn_prior``): the rotation's standard deviation at least
    the last step's turn.

    Parameters
    ----------
    prior_std : tuple of float
        Translation [m] and rotation [rad] standard deviations.
    last_turn : float
        The last step's turn [rad].

    Returns
    -------
    tuple of float
    """
    return prior_std[0], max(prior_std[1], abs(last_turn))


def _fuse(pose, cov, guess, guess_cov):
    """The product of two Gaussians on SE(2) poses (the match and the prediction), linearised
    at the match: mean and covariance."""
    d = np.asarray(guess, np.float64) - pose
    d[2] = math.remainder(d[2], 2 * math.pi)
    info_a = np.linalg.inv(cov)
    info_b = np.linalg.inv(guess_cov)
    fused_cov = np.linalg.inv(info_a + info_b)
    out = pose + fused_cov @ (info_b @ d)
    out[2] = math.remainder(out[2], 2 * math.pi)
    return out, fused_cov


def _chain_covariance(meas, info, loop_edge, c: int, j: int) -> np.ndarray:
    """Covariance of the relative pose of keyframe ``j`` in keyframe ``c``'s frame along the
    sequential edges between them (each edge's Σ = Ω⁻¹ on the right of its measurement,
    moved to the right of the product by the adjoint): an upper bound of the graph's own, which
    the loop edges only tighten."""
    sequential = [k for k, is_loop in enumerate(loop_edge) if not is_loop]  # edge k: (k, k + 1)
    total = np.zeros((3, 3))
    after = np.zeros(3)  # Z_{i+1} ... Z_{j-1}
    for i in range(j - 1, c - 1, -1):
        k = sequential[i]
        a = se2_adjoint(inverse_pose(after))
        total += a @ np.linalg.inv(info[k]) @ a.T
        after = compose(meas[k], after)
    return total


def _closure_chi2(kf_pose, meas, info, loop_edge, c: int, j: int, z, loop_info) -> float:
    """Squared Mahalanobis distance of a closure ``z`` (keyframe ``j`` in ``c``'s frame, of
    information ``loop_info``) from the graph's estimate of it, under the sum of the
    closure's covariance and the estimate's along the path (:func:`_chain_covariance`)."""
    r = se2_log(compose(inverse_pose(z), relative_pose(kf_pose[c], kf_pose[j])))
    cov = _chain_covariance(meas, info, loop_edge, c, j) + np.linalg.inv(loop_info)
    return float(r @ np.linalg.solve(cov, r))


def _most_overlapped(kf_pose, kf_scan, points, keys, pose, scan, reach) -> int:
    """The keyframe of ``keys`` whose own scan holds most points of ``scan`` placed at
    ``pose`` within ``reach`` [m] (``LidarSlam.anchor_by_overlap``)."""
    from scipy.spatial import cKDTree

    placed = _transform(pose, scan)
    counts = [
        np.count_nonzero(
            cKDTree(_transform(kf_pose[i], points[kf_scan[i]])).query(
                placed, distance_upper_bound=reach
            )[0]
            < np.inf
        )
        for i in keys
    ]
    return int(keys[int(np.argmax(counts))])


@dataclass(frozen=True)
class SlamResult:
    """A lidar SLAM run.

    Attributes
    ----------
    poses : numpy.ndarray, shape (N, 3)
        The final estimate of every scan's robot pose.
    frontend_poses : numpy.ndarray, shape (N, 3)
        The poses as matched online (before later loop closures moved them).
    keyframes : numpy.ndarray, shape (K,)
        Scan index of each keyframe (vertex of ``graph``).
    graph : PoseGraph
        Keyframe poses (optimised), odometry and loop edges.
    loop_edges : numpy.ndarray, shape (E,)
        Which edges of ``graph`` are loop closures.
    loops : numpy.ndarray, shape (L, 2)
        Scan indices joined by each loop closure.
    processing_time_s : float
        Wall time of the run [s].
    duration_s : float
        Time the log covers [s].
    stats : dict
        Counts: ``failed_matches``, ``loop_searches``, ``loop_candidates``,
        ``loops_accepted``, ``loops_rejected`` (of which ``loops_gated`` by ``loop_gate``),
        ``skipped_scans``, ``optimizations``, ``last_checks`` (matches that
        :attr:`LidarSlam.last_check` replaced), ``last_degenerate`` (alternatives it left
        because the last keyframe does not constrain the move), ``relocalized`` (scans that
        :attr:`LidarSlam.relocalize` moved).
    snapshots : list
        ``(scan index, keyframe poses at that time)`` every ``snapshot_every`` scans.
    anchors : numpy.ndarray, shape (N,)
        The keyframe each scan follows.
    offsets : numpy.ndarray, shape (N, 3)
        Each scan's pose in its keyframe's frame.
    """

    poses: np.ndarray
    frontend_poses: np.ndarray
    keyframes: np.ndarray
    graph: PoseGraph
    loop_edges: np.ndarray
    loops: np.ndarray
    processing_time_s: float
    duration_s: float
    stats: dict
    snapshots: list = field(default_factory=list, repr=False)
    anchors: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64), repr=False)
    offsets: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)), repr=False)

    def snapshot_poses(self, index: int) -> tuple[int, np.ndarray]:
        """The scans up to snapshot ``index`` and their poses as estimated then.

        Parameters
        ----------
        index : int
            Row of ``snapshots``.

        Returns
        -------
        tuple
            ``(last scan index, poses of scans 0 … last)``.
        """
        last, keyframes = self.snapshots[index]
        anchors = np.clip(self.anchors[: last + 1], 0, len(keyframes) - 1)
        return last, compose(keyframes[anchors], self.offsets[: last + 1])

    @property
    def real_time_factor(self) -> float:
        """Log duration over processing time (15: fifteen times faster than real time); NaN
        for a log whose stamps are not times (no duration)."""
        if not self.duration_s > 0:
            return math.nan
        return self.duration_s / max(self.processing_time_s, 1e-12)
