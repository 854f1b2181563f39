"""The UTIAS MRCLAM data set (Leung, Halpern, Barfoot and Liu, IJRR 2011): one reader for the
files of a data set's folder, returning plain records.

One data set's folder holds, per robot N, ``RobotN_Odometry.dat`` (time [s], forward velocity
[m/s], angular velocity [rad/s] at about 100 Hz: the robot's velocity command),
``RobotN_Groundtruth.dat`` (time [s], x [m], y [m], orientation [rad] from a Vicon system) and
``RobotN_Measurement.dat`` (time [s], barcode, range [m], bearing [rad] from its camera), plus
``Barcodes.dat`` (subject → barcode) and ``Landmark_Groundtruth.dat`` (the 15 landmarks,
subjects 6–20: x, y and their survey standard deviations). The file names may carry the data
set's prefix (``Dataset6_Robot1_Odometry.dat``). Lines starting with ``#`` are comments.

:func:`load_mrclam` aligns a robot's odometry and ground truth: odometry samples outside the
ground-truth span are dropped and the ground truth is interpolated linearly to the odometry
times, the heading through ``numpy.unwrap`` so that interpolation never crosses the ±π cut.
The second column of a measurement is a *barcode*, although the file's header says "Subject
#": :func:`load_measurements` maps it to a subject through the barcodes file. Sightings of
subjects 1–5 are other robots, not landmarks, and are left out (counted); barcodes that belong
to no subject get the identity −1.

The algorithms on these records live with their kind: dead reckoning and the command response
in :mod:`wheelbase.odometry.mrclam`, the filters in :mod:`wheelbase.localization.mrclam`, landmark
SLAM in :mod:`wheelbase.mapping.landmark_slam`.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from wheelbase._validate import positive
from wheelbase.errors import ConfigError, DataError
from wheelbase.geometry import wrap_angle

__all__ = [
    "MrclamData",
    "MrclamLandmarks",
    "MrclamMeasurements",
    "find_mrclam_files",
    "load_groundtruth",
    "load_landmarks",
    "load_measurements",
    "load_mrclam",
]


@dataclass(frozen=True)
class MrclamData:
    """Time-aligned odometry and ground truth of one MRCLAM robot.

    Attributes
    ----------
    t : numpy.ndarray, shape (T,)
        Odometry times [s] (Unix time, as in the files), strictly increasing.
    v : numpy.ndarray, shape (T,)
        Odometry forward velocity [m/s], held until the next sample.
    omega : numpy.ndarray, shape (T,)
        Odometry yaw rate [rad/s], held until the next sample.
    true_pose : numpy.ndarray, shape (T, 3)
        Ground truth (x [m], y [m], θ [rad]) interpolated to ``t``.
    """

    t: np.ndarray
    v: np.ndarray
    omega: np.ndarray
    true_pose: np.ndarray

    @property
    def duration(self) -> float:
        """Time covered [s]."""
        return float(self.t[-1] - self.t[0])

    def window(self, start: float, length: float) -> MrclamData:
        """The samples with ``start <= t − t[0] <= start + length`` (times in seconds).

        Parameters
        ----------
        start : float
            Start of the window, relative to the first sample [s].
        length : float
            Length of the window [s], > 0.
        """
        rel = self.t - self.t[0]
        keep = (rel >= start) & (rel <= start + positive("length", length, "s"))
        if keep.sum() < 2:
            raise DataError(f"the window [{start:g}, {start + length:g}] s holds < 2 samples")
        return MrclamData(self.t[keep], self.v[keep], self.omega[keep], self.true_pose[keep])


def _series(path: str | Path, columns: int, what: str) -> np.ndarray:
    """A time series file: >= 2 finite rows, sorted by time, repeated time stamps dropped."""
    data = _table(Path(path), columns, what)
    if data.shape[0] < 2:
        raise DataError(
            f"{what} file {path} must have {columns} columns and >= 2 rows (got {data.shape})"
        )
    data = data[np.argsort(data[:, 0], kind="stable")]
    keep = np.concatenate([[True], np.diff(data[:, 0]) > 0])  # drop repeated time stamps
    return data[keep]


def load_mrclam(odometry_path: str | Path, groundtruth_path: str | Path) -> MrclamData:
    """Read one MRCLAM robot's odometry and ground truth, aligned on the odometry times.

    Parameters
    ----------
    odometry_path : str or Path
        ``…_Odometry.dat``: time [s], v [m/s], ω [rad/s].
    groundtruth_path : str or Path
        ``…_Groundtruth.dat``: time [s], x [m], y [m], θ [rad].

    Returns
    -------
    MrclamData
        Odometry samples within the ground-truth time span, with the ground truth linearly
        interpolated to their times (heading unwrapped, interpolated, wrapped to (−π, π]).

    Raises
    ------
    DataError
        A missing or malformed file, or files whose times do not overlap.
    """
    odometry = _series(odometry_path, 3, "odometry")
    truth = _series(groundtruth_path, 4, "ground-truth")
    inside = (odometry[:, 0] >= truth[0, 0]) & (odometry[:, 0] <= truth[-1, 0])
    if inside.sum() < 2:
        raise DataError("the odometry and ground-truth files do not overlap in time")
    odometry = odometry[inside]
    t = odometry[:, 0]
    heading = np.unwrap(truth[:, 3])
    pose = np.column_stack(
        [
            np.interp(t, truth[:, 0], truth[:, 1]),
            np.interp(t, truth[:, 0], truth[:, 2]),
            wrap_angle(np.interp(t, truth[:, 0], heading)),
        ]
    )
    return MrclamData(t=t, v=odometry[:, 1], omega=odometry[:, 2], true_pose=pose)


@dataclass(frozen=True)
class MrclamLandmarks:
    """The landmarks of a data set.

    Attributes
    ----------
    subjects : numpy.ndarray, shape (L,)
        Subject numbers (6–20).
    xy : numpy.ndarray, shape (L, 2)
        Positions [m] from the Vicon survey.
    """

    subjects: np.ndarray
    xy: np.ndarray


@dataclass(frozen=True)
class MrclamMeasurements:
    """One robot's landmark measurements, identities resolved.

    Attributes
    ----------
    t : numpy.ndarray, shape (K,)
        Times [s].
    landmark : numpy.ndarray, shape (K,)
        Row of the landmark array, or −1 for a barcode that names no subject.
    z : numpy.ndarray, shape (K, 2)
        (range [m], bearing [rad]).
    robot_sightings : int
        Measurements of other robots, left out.
    moved : numpy.ndarray or None, shape (K, 3)
        How far the robot moved (x [m], y [m], θ [rad] in the frame of the pose the image was
        taken at) between taking the image and the time stamp (set by :func:`localize`).
    """

    t: np.ndarray
    landmark: np.ndarray
    z: np.ndarray
    robot_sightings: int
    moved: np.ndarray | None = None


def _table(path: Path, columns: int, what: str) -> np.ndarray:
    if not path.is_file():
        raise DataError(f"{what} file not found: {path}")
    try:
        data = np.loadtxt(path, comments="#", ndmin=2)
    except ValueError as error:
        raise DataError(f"{what} file {path} is malformed: {error}") from None
    if data.size == 0:
        return np.zeros((0, columns))
    if data.shape[1] != columns or not np.all(np.isfinite(data)):
        raise DataError(
            f"{what} file {path} must have {columns} columns of finite numbers (got {data.shape})"
        )
    return data


def find_mrclam_files(data_dir: str | Path, robot: int) -> dict[str, Path]:
    """The files of one robot in a data set's folder, with or without the data set's prefix.

    Parameters
    ----------
    data_dir : str or Path
        The folder.
    robot : int
        Robot number, 1–5.

    Returns
    -------
    dict
        Paths under the keys ``odometry``, ``groundtruth``, ``measurement``, ``barcodes``,
        ``landmarks``.

    Raises
    ------
    DataError
        A missing folder or file, or two candidates for one file.
    """
    folder = Path(data_dir)
    if not folder.is_dir():
        raise DataError(f"MRCLAM folder not found: {folder}")
    if isinstance(robot, bool) or not isinstance(robot, int | np.integer) or not 1 <= robot <= 5:
        raise ConfigError(f"robot must be 1, 2, 3, 4 or 5 (got {robot!r})")
    wanted = {
        "odometry": f"Robot{robot}_Odometry.dat",
        "groundtruth": f"Robot{robot}_Groundtruth.dat",
        "measurement": f"Robot{robot}_Measurement.dat",
        "barcodes": "Barcodes.dat",
        "landmarks": "Landmark_Groundtruth.dat",
    }
    found = {}
    for key, name in wanted.items():
        matches = sorted(
            p for p in folder.iterdir() if p.name == name or p.name.endswith("_" + name)
        )
        if not matches:
            raise DataError(f"{folder} holds no {name} (nor *_{name}) for robot {robot}")
        if len(matches) > 1:
            names = ", ".join(p.name for p in matches)
            raise DataError(f"{folder} holds several files for {name}: {names}")
        found[key] = matches[0]
    return found


def load_landmarks(path: str | Path) -> MrclamLandmarks:
    """Read ``Landmark_Groundtruth.dat``.

    Parameters
    ----------
    path : str or Path
        The file: subject, x [m], y [m], σ_x [m], σ_y [m].

    Returns
    -------
    MrclamLandmarks
    """
    data = _table(Path(path), 5, "landmark")
    if data.shape[0] == 0:
        raise DataError(f"landmark file {path} holds no landmark")
    return MrclamLandmarks(data[:, 0].astype(np.int64), data[:, 1:3].copy())


def load_measurements(
    measurement_path: str | Path, barcodes_path: str | Path, landmarks: MrclamLandmarks
) -> MrclamMeasurements:
    """Read a robot's measurements and resolve their barcodes to landmark rows.

    Parameters
    ----------
    measurement_path : str or Path
        ``RobotN_Measurement.dat``: time [s], barcode, range [m], bearing [rad].
    barcodes_path : str or Path
        ``Barcodes.dat``: subject, barcode.
    landmarks : MrclamLandmarks
        The landmarks (subjects 6–20).

    Returns
    -------
    MrclamMeasurements
        Sorted by time; other robots' sightings removed and counted.
    """
    data = _table(Path(measurement_path), 4, "measurement")
    codes = _table(Path(barcodes_path), 2, "barcode").astype(np.int64)
    subject_of = {int(code): int(subject) for subject, code in codes}
    row_of = {int(s): i for i, s in enumerate(landmarks.subjects)}
    subjects = np.array([subject_of.get(round(b), -1) for b in data[:, 1]], dtype=np.int64)
    robots = (subjects >= 1) & (subjects <= 5)
    data, subjects = data[~robots], subjects[~robots]
    rows = np.array([row_of.get(int(s), -1) for s in subjects], dtype=np.int64)
    order = np.argsort(data[:, 0], kind="stable")
    return MrclamMeasurements(
        data[order, 0], rows[order], data[order][:, 2:4].copy(), int(robots.sum())
    )


def load_groundtruth(path: str | Path) -> np.ndarray:
    """A robot's Vicon ground truth, sorted by time (stable).

    Parameters
    ----------
    path : str or Path
        ``…_Groundtruth.dat``: time [s], x [m], y [m], θ [rad].

    Returns
    -------
    numpy.ndarray, shape (T, 4)
    """
    truth = _table(Path(path), 4, "ground-truth")
    return truth[np.argsort(truth[:, 0], kind="stable")]
