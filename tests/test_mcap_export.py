"""MCAP export: read the file back and compare it with the log it came from."""

import json
import math
import sys
from collections import Counter

import numpy as np
import pytest

pytest.importorskip("mcap")
pytest.importorskip("foxglove_schemas_protobuf")

from mcap.reader import make_reader
from mcap_protobuf.decoder import DecoderFactory
from typer.testing import CliRunner

from wheelbase.cli import app
from wheelbase.errors import DependencyError, InputError
from wheelbase.geometry import compose, wrap_angle
from wheelbase.mcap_export import write_log_mcap, write_mcap
from wheelbase.runner import run

SCENARIO = {
    "name": "mcap",
    "map": "warehouse",
    "robot": {"model": "diffdrive", "preset": "rm100"},
    "plant": "dynamic",
    "controller": {"law": "kanayama"},
    "odometry": {"mode": "encoders", "wheel_radius_scale": [1.01, 0.99]},
    "start": [3.0, 2.0, 0.0],
    "goals": [[5.0, 2.5, 0.0], [8.0, 2.5, 0.0]],
    "trajectory": {"max_speed": 0.8, "max_acceleration": 0.8},
    "goal_tolerance": [0.2, 20.0],
    "dt": 0.05,
}

PROTOBUF_TOPICS = {
    "/map": "foxglove.Grid",
    "/plan": "foxglove.PosesInFrame",
    "/pose/true": "foxglove.PoseInFrame",
    "/pose/estimated": "foxglove.PoseInFrame",
    "/tf": "foxglove.FrameTransforms",
    "/tf_true": "foxglove.FrameTransforms",
    "/markers": "foxglove.SceneUpdate",
}
JSON_TOPICS = ("/command", "/twist", "/wheel_rates", "/torques", "/metrics")


@pytest.fixture(scope="module")
def result():
    return run(SCENARIO)


@pytest.fixture(scope="module")
def decoded(result, tmp_path_factory):
    path = write_mcap(result, tmp_path_factory.mktemp("mcap") / "run.mcap")
    messages: dict[str, list] = {}
    with path.open("rb") as handle:
        reader = make_reader(handle, decoder_factories=[DecoderFactory()])
        summary = reader.get_summary()
        for schema, channel, message in reader.iter_messages():
            payload = json.loads(message.data) if channel.message_encoding == "json" else None
            messages.setdefault(channel.topic, []).append((schema, channel, message, payload))
        handle.seek(0)
        reader = make_reader(handle, decoder_factories=[DecoderFactory()])
        protobuf = {}
        for _, channel, message, proto in reader.iter_decoded_messages(
            topics=list(PROTOBUF_TOPICS)
        ):
            protobuf.setdefault(channel.topic, []).append((message.log_time, proto))
    return summary, messages, protobuf


def _theta(q) -> float:
    assert q.x == 0.0 and q.y == 0.0
    assert math.isclose(q.z**2 + q.w**2, 1.0, abs_tol=1e-15)
    return 2.0 * math.atan2(q.z, q.w)


def _tree(messages):
    """(map → odom, odom → base_link) poses of every /tf message."""
    correction, odometry = [], []
    for _, message in messages:
        first, second = message.transforms
        assert (first.parent_frame_id, first.child_frame_id) == ("map", "odom")
        assert (second.parent_frame_id, second.child_frame_id) == ("odom", "base_link")
        correction.append([first.translation.x, first.translation.y, _theta(first.rotation)])
        odometry.append([second.translation.x, second.translation.y, _theta(second.rotation)])
    return np.array(correction), np.array(odometry)


def _same_poses(got, expected):
    got, expected = np.asarray(got), np.asarray(expected)
    np.testing.assert_allclose(got[:, :2], expected[:, :2], rtol=0, atol=1e-9)
    assert np.max(np.abs(wrap_angle(got[:, 2] - expected[:, 2]))) < 1e-9


def test_a_filter_publishes_its_correction_as_map_to_odom(tmp_path):
    ekf = {
        "name": "ekf", "map": "empty", "robot": {"model": "diffdrive"},
        "controller": {"law": "kanayama"},
        "odometry": {"tick_noise_std": 0.5, "wheel_radius_scale": [1.02, 1.0]},
        "sensors": {"landmarks": {"positions": [[0.5, 1.0], [1.5, -0.5]], "max_range": 5.0}},
        "localization": {"method": "ekf"}, "start": [0.0, 0.0, 0.0], "goal": [1.5, 0.5, 0.0],
        "trajectory": {"max_speed": 1.0, "max_acceleration": 1.0}, "dt": 0.02,
    }  # fmt: skip
    result = run(ekf)
    path = write_mcap(result, tmp_path / "ekf.mcap")
    with path.open("rb") as handle:
        reader = make_reader(handle, decoder_factories=[DecoderFactory()])
        tf = [(m.log_time, p) for _, _, m, p in reader.iter_decoded_messages(topics=["/tf"])]
    correction, odometry = _tree(tf)
    log = result.log
    _same_poses(odometry, log.extras["odom_pose"][0])  # the wheel odometry alone
    _same_poses([compose(a, b) for a, b in zip(correction, odometry, strict=True)],
                log.estimated_pose[0])  # fmt: skip
    assert np.hypot(*correction[-1, :2]) > 1e-3  # the filter corrected the 2 % wheel error


def test_schemas_are_foxglove_and_counts_match_the_log(result, decoded):
    summary, messages, _ = decoded
    log = result.log
    rows = len(log.t)
    assert result.metrics["status"] in ("arrived", "missed_goal")
    schemas = {
        channel.topic: (summary.schemas[channel.schema_id].name, channel.message_encoding)
        for channel in summary.channels.values()
    }
    for topic, name in PROTOBUF_TOPICS.items():
        assert schemas[topic] == (name, "protobuf")
    for topic in JSON_TOPICS:
        assert schemas[topic][1] == "json"
        assert summary.schemas[messages[topic][0][1].schema_id].encoding == "jsonschema"
    counts = Counter({topic: len(values) for topic, values in messages.items()})
    per_row = ("/pose/true", "/pose/estimated", "/tf", "/tf_true", "/command", "/twist",
               "/wheel_rates")  # fmt: skip
    assert counts == Counter(
        {"/map": 1, "/plan": 1, "/markers": 1, "/metrics": 1, "/torques": rows}
        | dict.fromkeys(per_row, rows)
    )
    assert sum(summary.statistics.channel_message_counts.values()) == sum(counts.values())


def test_poses_and_times_equal_the_log(result, decoded):
    _, messages, protobuf = decoded
    log = result.log
    t = log.t
    for topic, poses in (("/pose/true", log.true_pose[0]), ("/pose/estimated",
                                                          log.estimated_pose[0])):  # fmt: skip
        got = protobuf[topic]
        times = np.array([log_time for log_time, _ in got]) * 1e-9
        stamps = np.array([m.timestamp.seconds + 1e-9 * m.timestamp.nanos for _, m in got])
        np.testing.assert_allclose(times, t, rtol=0, atol=1e-9)
        np.testing.assert_allclose(stamps, t, rtol=0, atol=1e-9)
        assert {m.frame_id for _, m in got} == {"map"}
        xy = np.array([[m.pose.position.x, m.pose.position.y] for _, m in got])
        theta = np.array([_theta(m.pose.orientation) for _, m in got])
        np.testing.assert_allclose(xy, poses[:, :2], rtol=0, atol=1e-9)
        assert np.max(np.abs(wrap_angle(theta - poses[:, 2]))) < 1e-9
    # The frame tree is the robot's (REP 105): map → odom → base_link composes to the
    # estimate; with odometry alone map → odom is the identity. The truth has its own topic.
    correction, odometry = _tree(protobuf["/tf"])
    np.testing.assert_allclose(correction, 0.0, atol=1e-12)
    _same_poses(odometry, log.estimated_pose[0])
    drift = np.hypot(*(log.true_pose[0, -1, :2] - log.estimated_pose[0, -1, :2]))
    assert drift > 1e-3  # the wheel radii are off by 1 %: the tree is not the truth
    truth = [message.transforms[0] for _, message in protobuf["/tf_true"]]
    assert {(f.parent_frame_id, f.child_frame_id) for f in truth} == {("map", "base_link_true")}
    _same_poses([[f.translation.x, f.translation.y, _theta(f.rotation)] for f in truth],
                log.true_pose[0])  # fmt: skip
    # JSON signals: the command columns, torques and wheel rates of every row.
    command = messages["/command"]
    assert [p["t"] for *_, p in command] == t.tolist()
    names = log.command_names
    np.testing.assert_array_equal(
        [[p[name] for name in names] for *_, p in command], log.command[0]
    )
    np.testing.assert_array_equal(
        [[p["left"], p["right"]] for *_, p in messages["/torques"]], log.torques[0]
    )
    np.testing.assert_array_equal(
        [[p["left"], p["right"]] for *_, p in messages["/wheel_rates"]], log.wheel_rates[0]
    )
    ((_, _, message, metrics),) = messages["/metrics"]
    assert message.log_time == round(t[-1] * 1e9)
    assert metrics["status"] == result.metrics["status"]
    assert metrics["path_length_m"] == result.metrics["path_length_m"]


def test_map_plan_and_markers(result, decoded):
    _, _, protobuf = decoded
    grid = result.grid
    ((_, message),) = protobuf["/map"]
    rows, cols = grid.occupied.shape
    assert message.column_count == cols and message.row_stride == cols
    assert message.cell_size.x == grid.resolution
    assert (message.pose.position.x, message.pose.position.y) == tuple(grid.origin)
    data = np.frombuffer(message.data, dtype=np.uint8).reshape(rows, cols)
    np.testing.assert_array_equal(data == 100, grid.occupied)
    ((_, plan),) = protobuf["/plan"]
    poses = np.array([[p.position.x, p.position.y, _theta(p.orientation)] for p in plan.poses])
    np.testing.assert_allclose(poses[:, :2], result.plan.poses[:, :2], rtol=0, atol=1e-12)
    ((_, scene),) = protobuf["/markers"]
    entities = {entity.id: entity for entity in scene.entities}
    assert set(entities) == {"footprint", "goal0", "goal1"}
    footprint = entities["footprint"]
    assert footprint.frame_id == "base_link" and footprint.frame_locked
    outline = [(p.x, p.y) for p in footprint.lines[0].points]
    np.testing.assert_allclose(outline, result.footprint_polygon, rtol=0, atol=1e-12)
    goal = entities["goal1"].arrows[0].pose
    assert (goal.position.x, goal.position.y) == (8.0, 2.5)


def test_batch_log_has_one_prefix_per_robot(tmp_path):
    from wheelbase.control import PolarPose
    from wheelbase.models import Unicycle
    from wheelbase.sim import closed_loop

    log = closed_loop(PolarPose(), Unicycle(), [[-1.0, 0.5, 0.0], [1.0, 1.0, 1.0]], [0, 0, 0],
                      20.0, 0.05, goal=[0, 0, 0], tolerance=(0.05, 0.1))  # fmt: skip
    path = write_log_mcap(log, tmp_path / "batch.mcap")
    with path.open("rb") as handle:
        reader = make_reader(handle)
        topics = Counter(channel.topic for _, channel, _ in reader.iter_messages())
    for i in range(2):
        assert topics[f"/robot{i}/pose/true"] == log.length[i]
        assert topics[f"/robot{i}/metrics"] == 1
    assert "/map" not in topics and "/robot0/torques" not in topics
    # A polygon world is a scene of line loops: rings (a hole too), discs, bounds.
    from wheelbase.planning import PolygonWorld

    square = [(2, 2), (4, 2), (4, 4), (2, 4)]
    world = PolygonWorld([(square, [[(2.5, 2.5), (3, 2.5), (3, 3)]])], discs=[[6, 3, 0.5]],
                         bounds=(0, 10, 0, 6))  # fmt: skip
    path = write_log_mcap(log, tmp_path / "world.mcap", grid=world)
    with path.open("rb") as handle:
        reader = make_reader(handle, decoder_factories=[DecoderFactory()])
        ((*_, scene),) = reader.iter_decoded_messages(topics=["/map/obstacles"])
    loops = scene.entities[0].lines
    assert len(loops) == 4 and scene.entities[0].frame_id == "map"
    np.testing.assert_array_equal([(p.x, p.y) for p in loops[0].points], square)
    radius = [math.hypot(p.x - 6, p.y - 3) for p in loops[2].points]
    np.testing.assert_allclose(radius, 0.5, rtol=0, atol=1e-12)
    assert [(p.x, p.y) for p in loops[3].points] == [(0, 0), (10, 0), (10, 6), (0, 6)]
    with pytest.raises(FileExistsError, match="overwrite"):
        write_log_mcap(log, path)
    with pytest.raises(InputError, match="one dict per robot"):
        write_log_mcap(log, path, overwrite=True, metrics=[{}])


def test_cli_run_mcap_and_missing_extra(tmp_path, monkeypatch):
    scenario = tmp_path / "short.yaml"
    scenario.write_text(
        "name: short\nmap: empty\nrobot: {model: diffdrive}\ncontroller: {law: kanayama}\n"
        "start: [0.0, 0.0, 0.0]\ngoal: [1.0, 0.5, 0.0]\ndt: 0.05\n"
    )
    out = tmp_path / "report"
    runner = CliRunner()
    done = runner.invoke(app, ["run", str(scenario), "--out", str(out), "--no-gif", "--mcap"])
    assert done.exit_code == 0, done.output
    assert (out / "run.mcap").stat().st_size > 0
    again = runner.invoke(app, ["run", str(scenario), "--out", str(out), "--no-gif", "--mcap"])
    assert again.exit_code == 2 and "use --force" in again.output
    # Without the extra: one clear line naming it, and nothing run or written.
    monkeypatch.setitem(sys.modules, "foxglove_schemas_protobuf", None)
    other = tmp_path / "other"
    missing = runner.invoke(app, ["run", str(scenario), "--out", str(other), "--mcap"])
    assert missing.exit_code == 2 and "wheelbase[foxglove]" in missing.output
    assert not other.exists()
    with pytest.raises(DependencyError, match=r"wheelbase\[foxglove\]"):
        write_mcap(run(scenario), tmp_path / "x.mcap")


def test_saved_foxglove_layout_names_topics_the_export_writes():
    from pathlib import Path

    from wheelbase.mcap_export import MCAP_TOPICS

    layout = json.loads(
        (Path(__file__).parents[1] / "docs" / "foxglove" / "wheelbase_layout.json").read_text()
    )
    panels = layout["configById"]
    assert set(panels["3D!wheelbase"]["topics"]) <= set(MCAP_TOPICS)
    fields = {"/command": {"v", "omega"}, "/wheel_rates": {"left", "right"},
              "/torques": {"left", "right"}}  # fmt: skip
    for key, panel in panels.items():
        for series in panel.get("paths", []):
            topic, name = series["value"].split(".")
            assert name in fields[topic], (key, series)
    assert panels["RawMessages!metrics"]["topicPath"] in MCAP_TOPICS


def test_lidar_scans_are_laser_scans_in_the_robot_frame(tmp_path):
    scenario = {
        **SCENARIO,
        "plant": "kinematic",
        "goals": [[5.0, 2.5, 0.0]],
        "sensors": {"lidar": {"beams": 36, "fov_deg": 270, "max_range": 8.0, "rate_hz": 5}},
        "localization": {"method": "amcl", "max_particles": 300, "min_particles": 100},
    }
    result = run(scenario)
    path = write_mcap(result, tmp_path / "scan.mcap")
    with path.open("rb") as handle:
        reader = make_reader(handle, decoder_factories=[DecoderFactory()])
        scans = [(m.log_time, p) for _, _, m, p in reader.iter_decoded_messages(topics=["/scan"])]
    with path.open("rb") as handle:
        reader = make_reader(handle, decoder_factories=[DecoderFactory()])
        messages = reader.iter_decoded_messages(topics=["/particles"])
        clouds = [(m.log_time, p) for _, _, m, p in messages]
    log = result.log
    # the particle clouds the log kept, as PosesInFrame in the map frame, poses to 1e-9 m
    kept = sorted(row for _, row in log.particles)
    assert len(clouds) == len(kept) > 0
    for (stamp, cloud), row in zip(clouds, kept, strict=True):
        particles = np.asarray(log.particles[(0, row)])
        assert stamp == round(log.t[row] * 1e9) and cloud.frame_id == "map"
        xy = np.array([[p.position.x, p.position.y] for p in cloud.poses])
        np.testing.assert_allclose(xy, particles[:, :2], atol=1e-9)
    rows = sorted(row for _, row in log.scans)
    assert len(scans) == len(rows) > 5
    for (stamp, scan), row in zip(scans, rows, strict=True):
        assert stamp == round(log.t[row] * 1e9) and scan.frame_id == "base_link"
        np.testing.assert_array_equal(scan.ranges, log.scans[(0, row)])
    assert scan.start_angle == pytest.approx(-math.radians(135))
    assert scan.end_angle == pytest.approx(math.radians(135))
    assert scan.pose.position.x == 0.0 and scan.pose.orientation.w == 1.0


def test_agents_costmap_and_tracks_of_a_run_among_walkers(tmp_path):
    scenario = {
        "name": "walkers",
        "map": "room20",
        "robot": {"model": "unicycle", "footprint": [0.4, 0.4]},
        "controller": {"law": "mppi", "gains": {"samples": 200}},
        "control_rate_hz": 10,
        "odometry": {"mode": "perfect"},
        "sensors": {"lidar": {"beams": 90, "max_range": 6.0, "range_std": 0.01, "rate_hz": 10}},
        "world": {
            "obstacles": [{"box": [10.0, 4.0, 0.6, 0.6, 0.0]}],
            "agents": [{"count": 4, "radius": 0.25, "region": [4, 4, 9, 9]}],
        },
        "start": [2.0, 2.0, 45.0],
        "goal": [8.0, 8.0, 45.0],
        "dt": 0.05,
        "duration": 4.0,
    }
    result = run(scenario)
    path = write_mcap(result, tmp_path / "walkers.mcap")
    topics: dict[str, list] = {}
    with path.open("rb") as handle:
        reader = make_reader(handle, decoder_factories=[DecoderFactory()])
        for _, channel, message, proto in reader.iter_decoded_messages(
            topics=["/world/obstacles", "/world/agents", "/costmap", "/tracks"]
        ):
            topics.setdefault(channel.topic, []).append((message.log_time, proto))
    log = result.log
    # agents every 0.1 s at their logged positions, discs of their radius
    agents = topics["/world/agents"]
    assert len(agents) == pytest.approx(log.t[-1] / 0.1 + 1, abs=1)
    stamp, update = agents[-1]
    row = int(np.argmin(np.abs(log.t - stamp / 1e9)))
    first = update.entities[0]
    centre = np.mean([[p.x, p.y] for p in first.lines[0].points], axis=0)
    np.testing.assert_allclose(centre, log.agents[0, row, 0, :2], atol=1e-6)
    assert len(update.entities) == 4
    # the box off the map, once
    ((_, obstacles),) = topics["/world/obstacles"]
    ring = np.array([[p.x, p.y] for p in obstacles.entities[0].lines[0].points])
    np.testing.assert_allclose(np.sort(ring[:, 0]), [9.7, 9.7, 10.3, 10.3], atol=1e-9)
    # what the robot believes, once a second: the map plus the cells its lidar marked
    assert len(topics["/costmap"]) == len(log.perceived) >= 3
    _, grid = topics["/costmap"][-1]
    cells = np.frombuffer(grid.data, np.uint8).reshape(-1, grid.column_count)
    marked = np.asarray(max(log.perceived.items())[1]["marks"], dtype=np.float64)
    assert len(marked) > 0  # the walls at least
    where = result.grid.world_to_cell(marked)
    assert np.all(cells[where[:, 0], where[:, 1]] == 100)
    np.testing.assert_array_equal(cells[result.grid.occupied], 100)
    assert len(topics["/tracks"]) == len(log.perceived)
