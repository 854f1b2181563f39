"""ROS 2 bags (``.db3`` and ``.mcap``) without ROS: laser scans, odometry and tf, read and
written with the ``rosbags`` package (``pip install wheelbase[bags]``).

Read: one ``sensor_msgs/msg/LaserScan`` topic (named, or the only one), the odometry from a
``nav_msgs/msg/Odometry`` topic (named, or the only one) or else from ``/tf``'s ``odom →
base_link`` transforms, interpolated to each scan's header time (linearly, the heading
unwrapped), and the laser's mount from ``/tf_static``'s ``base_link → <scan frame>``. An
optional second odometry topic (``reference_topic``, e.g. a simulator's ground truth) becomes
the record's ``reference``. Readings follow REP 117: +inf is no return (kept as
``range_max``), NaN, −inf and readings below ``range_min`` are invalid (NaN, counted).

Written (:func:`write_bag`): the scans on ``/scan`` (frame ``laser``), the odometry on ``/odom``
and as ``/tf`` ``odom → base_link``, the mount on ``/tf_static``, the reference on
``/ground_truth``: a bag that :func:`read_bag` reads back to the same record.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from wheelbase.datasets.scans import ScanLog
from wheelbase.errors import DataError, DependencyError
from wheelbase.geometry import wrap_angle

__all__ = ["BAG_STORAGES", "read_bag", "write_bag"]

BAG_STORAGES: tuple[str, ...] = ("mcap", "sqlite3")
"""Storage formats of :func:`write_bag`."""

_SCAN, _ODOM, _TF = "sensor_msgs/msg/LaserScan", "nav_msgs/msg/Odometry", "tf2_msgs/msg/TFMessage"


def _rosbags():
    try:
        from rosbags.rosbag2 import Reader, StoragePlugin, Writer
        from rosbags.typesys import Stores, get_typestore
    except ImportError as error:
        raise DependencyError(
            f"ROS 2 bags need the rosbags package: pip install wheelbase[bags] ({error})"
        ) from None
    return Reader, Writer, StoragePlugin, get_typestore(Stores.ROS2_HUMBLE)


def _stamp(header) -> float:
    return header.stamp.sec + 1e-9 * header.stamp.nanosec


def _yaw(q) -> float:
    return math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))


def _bag_dir(path: Path) -> Path:
    if path.is_dir():
        if not (path / "metadata.yaml").is_file():
            raise DataError(f"{path} is not a ROS 2 bag (no metadata.yaml)")
        return path
    if path.is_file() and (path.parent / "metadata.yaml").is_file():
        return path.parent
    if not path.exists():
        raise DataError(f"ROS 2 bag not found: {path}")
    raise DataError(
        f"{path}: a ROS 2 bag is a folder with metadata.yaml beside its .db3/.mcap files "
        "(give the folder)"
    )


def _pick(connections, msgtype: str, topic: str | None, what: str, bag: Path, required: bool):
    listing = ", ".join(sorted(f"{c.topic} ({c.msgtype})" for c in connections)) or "none"
    if topic is not None:
        found = [c for c in connections if c.topic == topic]
        if not found:
            raise DataError(f"{bag}: no topic {topic!r} ({what}); the bag has: {listing}")
        if found[0].msgtype != msgtype:
            raise DataError(
                f"{bag}: topic {topic!r} holds {found[0].msgtype}, not {msgtype}; the bag has: "
                f"{listing}"
            )
        return found
    found = [c for c in connections if c.msgtype == msgtype]
    topics = sorted({c.topic for c in found})
    if len(topics) > 1:
        raise DataError(f"{bag}: several {msgtype} topics ({', '.join(topics)}); name one")
    if not found and required:
        raise DataError(f"{bag}: no {msgtype} topic ({what}); the bag has: {listing}")
    return found


def read_bag(
    path: str | Path,
    *,
    scan_topic: str | None = None,
    odom_topic: str | None = None,
    reference_topic: str | None = None,
    base_frame: str = "base_link",
    odom_frame: str = "odom",
) -> ScanLog:
    """Read the laser scans of a ROS 2 bag with their odometry (module docstring).

    Parameters
    ----------
    path : str or Path
        The bag folder (or a file inside it).
    scan_topic, odom_topic : str or None
        Topics; None takes the only one of the type (odometry: else ``/tf``, else none).
    reference_topic : str or None
        An odometry topic with reference poses (ground truth).
    base_frame, odom_frame : str
        Frames of the tf odometry and of the mount.

    Returns
    -------
    ScanLog

    Raises
    ------
    DataError
        A missing or broken bag, a named topic that is absent (the message lists the bag's
        topics), no scan, or scans of differing geometry.
    """
    reader_cls, _, _, store = _rosbags()
    bag = _bag_dir(Path(path))
    try:
        with reader_cls(bag) as reader:
            connections = list(reader.connections)
            scans_c = _pick(connections, _SCAN, scan_topic, "laser scans", bag, True)
            ref_c = []
            if reference_topic is not None:
                ref_c = _pick(connections, _ODOM, reference_topic, "reference", bag, True)
            rest = [c for c in connections if c.topic != reference_topic]
            if odom_topic is None and any(c.topic == "/odom" for c in rest):
                odom_topic = "/odom"  # the REP 105 name, when there are several
            odom_c = _pick(rest, _ODOM, odom_topic, "odometry", bag, odom_topic is not None)
            tf_c = [c for c in connections if c.msgtype == _TF]
            scans, odom, ref, tf, static = [], [], [], [], {}
            wanted = scans_c + odom_c + ref_c + tf_c
            for connection, _, raw in reader.messages(connections=wanted):
                msg = store.deserialize_cdr(raw, connection.msgtype)
                if connection in scans_c:
                    scans.append(msg)
                elif connection in odom_c or connection in ref_c:
                    p = msg.pose.pose
                    row = (_stamp(msg.header), p.position.x, p.position.y, _yaw(p.orientation))
                    (odom if connection in odom_c else ref).append(row)
                else:
                    for t in msg.transforms:
                        pose = (t.transform.translation.x, t.transform.translation.y,
                                _yaw(t.transform.rotation))  # fmt: skip
                        if connection.topic == "/tf_static":
                            static[(t.header.frame_id, t.child_frame_id)] = pose
                        elif (t.header.frame_id, t.child_frame_id) == (odom_frame, base_frame):
                            tf.append((_stamp(t.header), *pose))
    except DataError:
        raise
    except Exception as error:  # rosbags raises its own types for broken files
        raise DataError(f"cannot read ROS 2 bag {bag}: {type(error).__name__}: {error}") from None
    if not scans:
        raise DataError(f"{bag}: the topic {scans_c[0].topic} holds no scan")
    first = scans[0]
    n = len(first.ranges)
    for msg in scans:
        if len(msg.ranges) != n or not math.isclose(msg.angle_min, first.angle_min) or not \
                math.isclose(msg.angle_increment, first.angle_increment):  # fmt: skip
            raise DataError(f"{bag}: scans of different geometry (one laser per record)")
    t = np.array([_stamp(m.header) for m in scans])
    ranges = np.array([np.asarray(m.ranges, dtype=np.float64) for m in scans]).reshape(-1, n)
    range_max = float(first.range_max)
    with np.errstate(invalid="ignore"):
        invalid = np.isnan(ranges) | (ranges == -np.inf) | (ranges < first.range_min)
        ranges = np.where(ranges == np.inf, range_max, ranges)
    ranges[invalid] = np.nan
    order = np.argsort(t, kind="stable")
    mount = static.get((base_frame, first.header.frame_id), (0.0, 0.0, 0.0))
    odometry = _interpolate(odom or tf, t) if (odom or tf) else None
    reference = _interpolate(ref, t) if ref else None
    return ScanLog(
        t=t[order],
        ranges=ranges[order],
        angles=first.angle_min + first.angle_increment * np.arange(n),
        max_range=range_max,
        odometry=None if odometry is None else odometry[order],
        reference=None if reference is None else reference[order],
        mount=tuple(float(v) for v in mount),
        invalid_readings=int(invalid.sum()),
        source=bag.name,
        extra={"scan_topic": scans_c[0].topic},
    )


def _interpolate(rows: list, t: np.ndarray) -> np.ndarray:
    data = np.array(sorted(rows))
    keep = np.concatenate([[True], np.diff(data[:, 0]) > 0])
    data = data[keep]
    if data.shape[0] == 1:
        return np.repeat(data[:, 1:], t.size, axis=0)
    heading = np.unwrap(data[:, 3])
    return np.column_stack([np.interp(t, data[:, 0], data[:, 1]),
                            np.interp(t, data[:, 0], data[:, 2]),
                            wrap_angle(np.interp(t, data[:, 0], heading))])  # fmt: skip


def write_bag(log: ScanLog, path: str | Path, *, storage: str = "mcap") -> Path:
    """Write a scan record as a ROS 2 bag folder (module docstring).

    Parameters
    ----------
    log : ScanLog
        The record (odometry and reference optional).
    path : str or Path
        The bag folder to create (it must not exist).
    storage : {"mcap", "sqlite3"}
        Storage plugin.

    Returns
    -------
    Path
    """
    from wheelbase._validate import check_choice

    check_choice("storage", storage, BAG_STORAGES)
    _, writer_cls, plugin, store = _rosbags()
    path = Path(path)
    if path.exists():
        raise FileExistsError(f"{path} exists; choose a new folder for the bag")
    types = store.types
    time_t, header_t = types["builtin_interfaces/msg/Time"], types["std_msgs/msg/Header"]
    vec3, quat = types["geometry_msgs/msg/Vector3"], types["geometry_msgs/msg/Quaternion"]

    def header(t: float, frame: str):
        sec = math.floor(t)
        return header_t(stamp=time_t(sec=int(sec), nanosec=round((t - sec) * 1e9)),
                        frame_id=frame)  # fmt: skip

    def q(yaw: float):
        return quat(x=0.0, y=0.0, z=math.sin(yaw / 2), w=math.cos(yaw / 2))

    def odometry(t, pose, frame="odom"):
        pose_t = types["geometry_msgs/msg/Pose"](
            position=types["geometry_msgs/msg/Point"](x=float(pose[0]), y=float(pose[1]), z=0.0),
            orientation=q(float(pose[2])),
        )
        zero6 = np.zeros(36)
        twist = types["geometry_msgs/msg/Twist"](linear=vec3(x=0.0, y=0.0, z=0.0),
                                                 angular=vec3(x=0.0, y=0.0, z=0.0))  # fmt: skip
        return types["nav_msgs/msg/Odometry"](
            header=header(t, frame), child_frame_id="base_link",
            pose=types["geometry_msgs/msg/PoseWithCovariance"](pose=pose_t, covariance=zero6),
            twist=types["geometry_msgs/msg/TwistWithCovariance"](twist=twist, covariance=zero6),
        )  # fmt: skip

    def transform(t, parent, child, pose):
        return types["geometry_msgs/msg/TransformStamped"](
            header=header(t, parent), child_frame_id=child,
            transform=types["geometry_msgs/msg/Transform"](
                translation=vec3(x=float(pose[0]), y=float(pose[1]), z=0.0),
                rotation=q(float(pose[2])),
            ),
        )  # fmt: skip

    step = float(log.angles[1] - log.angles[0]) if log.angles.size > 1 else 0.0
    kind = plugin.MCAP if storage == "mcap" else plugin.SQLITE3
    with writer_cls(path, version=9, storage_plugin=kind) as writer:
        c_scan = writer.add_connection("/scan", _SCAN, typestore=store)
        c_tf_static = writer.add_connection("/tf_static", _TF, typestore=store)
        c_odom = c_tf = c_ref = None
        if log.odometry is not None:
            c_odom = writer.add_connection("/odom", _ODOM, typestore=store)
            c_tf = writer.add_connection("/tf", _TF, typestore=store)
        if log.reference is not None:
            c_ref = writer.add_connection("/ground_truth", _ODOM, typestore=store)
        t0 = float(log.t[0]) if log.n_scans else 0.0
        static = types["tf2_msgs/msg/TFMessage"](
            transforms=[transform(t0, "base_link", "laser", log.mount)]
        )
        writer.write(c_tf_static, round(t0 * 1e9), store.serialize_cdr(static, _TF))
        for k in range(log.n_scans):
            t = float(log.t[k])
            ns = round(t * 1e9)
            ranges = np.where(np.isnan(log.ranges[k]), np.nan, log.ranges[k]).astype(np.float32)
            scan = types[_SCAN](
                header=header(t, "laser"), angle_min=float(log.angles[0]),
                angle_max=float(log.angles[-1]), angle_increment=step, time_increment=0.0,
                scan_time=0.0, range_min=0.0, range_max=float(log.max_range), ranges=ranges,
                intensities=np.zeros(0, np.float32),
            )  # fmt: skip
            writer.write(c_scan, ns, store.serialize_cdr(scan, _SCAN))
            if c_odom is not None:
                writer.write(c_odom, ns, store.serialize_cdr(odometry(t, log.odometry[k]), _ODOM))
                tf = types[_TF](transforms=[transform(t, "odom", "base_link", log.odometry[k])])
                writer.write(c_tf, ns, store.serialize_cdr(tf, _TF))
            if c_ref is not None:
                ref = odometry(t, log.reference[k], frame="map")
                writer.write(c_ref, ns, store.serialize_cdr(ref, _ODOM))
    return path
