"""``wheelbase plan``: files, metrics, refusal to overwrite, errors; PlannedPath.to_csv / plot."""

import csv
import json
import math

import numpy as np
import pytest
import typer
from typer.testing import CliRunner

from wheelbase.commands.options import PoseGroup
from wheelbase.commands.plan import register
from wheelbase.errors import ConfigError, PlanningError

app = typer.Typer(cls=PoseGroup)


@app.callback()
def _main() -> None:
    """Test app."""


register(app)
runner = CliRunner()
ARGS = ["warehouse", "--start", "6.2", "6", "90", "--goal", "16.9", "14", "-90deg"]
ROBOT = ["--turning-radius", "1.5", "--footprint", "1.6", "1.0", "--rear-axle-to-center", "0.5"]


def test_plan_writes_files_and_metrics(tmp_path):
    result = runner.invoke(app, ["plan", *ARGS, *ROBOT, "--out", str(tmp_path)])
    assert result.exit_code == 0, result.output
    metrics = json.loads((tmp_path / "metrics.json").read_text())
    assert metrics["success"] is True
    assert metrics["length_m"] > math.dist((6.2, 6), (16.9, 14))
    assert metrics["min_clearance_m"] > 0 and metrics["expanded_nodes"] > 0
    assert "length_m" in result.output
    with (tmp_path / "path.csv").open() as handle:
        rows = list(csv.DictReader(handle))
    first, last = rows[0], rows[-1]
    assert (float(first["x_m"]), float(first["y_m"])) == (6.2, 6.0)
    assert float(last["theta_rad"]) == pytest.approx(-math.pi / 2, abs=1e-6)
    assert float(last["s_m"]) == pytest.approx(metrics["length_m"], abs=1e-5)
    assert (tmp_path / "path.png").stat().st_size > 10_000
    again = runner.invoke(app, ["plan", *ARGS, *ROBOT, "--out", str(tmp_path)])
    assert again.exit_code != 0 and isinstance(again.exception, FileExistsError)
    forced = runner.invoke(app, ["plan", *ARGS, *ROBOT, "--out", str(tmp_path), "--force"])
    assert forced.exit_code == 0


def test_plan_no_reverse_and_errors(tmp_path):
    result = runner.invoke(app, ["plan", *ARGS, *ROBOT, "--no-reverse", "--out", str(tmp_path)])
    assert result.exit_code == 0, result.output
    with (tmp_path / "path.csv").open() as handle:
        assert {row["direction"] for row in csv.DictReader(handle)} == {"1"}
    bad = runner.invoke(
        app,
        [
            "plan",
            "warehouse",
            "--start",
            "0.2",
            "0.2",
            "0",
            "--goal",
            "16.9",
            "14",
            "-90",
            *ROBOT,
            "--out",
            str(tmp_path / "x"),
        ],
    )
    assert isinstance(bad.exception, PlanningError) and "start" in str(bad.exception)
    heading = runner.invoke(
        app,
        [
            "plan",
            "warehouse",
            "--start",
            "6.2",
            "6",
            "north",
            "--goal",
            "16.9",
            "14",
            "-90",
            "--out",
            str(tmp_path / "y"),
        ],
    )
    assert heading.exit_code == 2 and "start heading must be an angle" in heading.output
    unknown = runner.invoke(
        app,
        [
            "plan",
            "nowhere",
            "--start",
            "1",
            "1",
            "0",
            "--goal",
            "2",
            "2",
            "0",
            "--out",
            str(tmp_path / "z"),
        ],
    )
    assert isinstance(unknown.exception, ConfigError) and "map" in str(unknown.exception)


def test_path_plot_and_curve_csv(tmp_path):
    import matplotlib

    matplotlib.use("Agg")
    from wheelbase.planning import Footprint, load_map, reeds_shepp_path
    from wheelbase.planning.plot import plot_path

    path = reeds_shepp_path((5.0, 5.0, 0.0), (4.0, 5.0, math.pi), 1.5).sample(0.05)
    ax = plot_path(path, grid=load_map("maze"), footprint=Footprint.rectangle(0.6, 0.4))
    assert len(ax.lines) >= 2
    written = path.to_csv(tmp_path / "rs.csv")
    data = np.loadtxt(written, delimiter=",", skiprows=1)
    np.testing.assert_allclose(data[:, 1:4], path.poses, atol=1e-6)
    np.testing.assert_array_equal(data[:, 4], path.directions)


def test_plan_on_a_geojson_world_measures_clearance_on_the_polygons(tmp_path):
    import shapely

    from wheelbase.planning import Footprint, load_map
    from wheelbase.planning.plot import plot_grid

    wall = [[4.0, 0.0], [5.0, 0.0], [5.0, 4.5], [4.0, 4.5], [4.0, 0.0]]
    ring = [[7.0, 3.0], [10.0, 3.0], [10.0, 6.0], [7.0, 6.0], [7.0, 3.0]]
    hole = [[8.0, 4.0], [9.0, 4.0], [9.0, 5.0], [8.0, 5.0], [8.0, 4.0]]
    doc = {
        "type": "FeatureCollection",
        "bbox": [0.0, 0.0, 12.0, 7.0],
        "resolution": 0.05,
        "features": [
            {"type": "Feature", "properties": {},
             "geometry": {"type": "Polygon", "coordinates": [wall]}},
            {"type": "Feature", "properties": {},
             "geometry": {"type": "Polygon", "coordinates": [ring, hole]}},
            {"type": "Feature", "properties": {"radius": 0.5},
             "geometry": {"type": "Point", "coordinates": [2.0, 5.5]}},
        ],
    }  # fmt: skip
    world_file = tmp_path / "world.geojson"
    world_file.write_text(json.dumps(doc))
    out = tmp_path / "out"
    args = ["plan", str(world_file), "--start", "1", "1", "0", "--goal", "11", "1.5", "0"]
    result = runner.invoke(app, [*args, "--footprint", "0.6", "0.4", "--out", str(out)])
    assert result.exit_code == 0, result.output
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["success"] is True
    with (out / "path.csv").open() as handle:
        rows = list(csv.DictReader(handle))
    poses = np.array([[float(r["x_m"]), float(r["y_m"]), float(r["theta_rad"])] for r in rows])
    assert poses[:, 1].max() > 4.5  # over the wall
    # the clearance is the exact distance to the polygons and the disc (shapely agrees)
    fp = Footprint.rectangle(0.6, 0.4)
    c, s = np.cos(poses[:, 2]), np.sin(poses[:, 2])
    px, py = fp.polygon[:, 0], fp.polygon[:, 1]
    shapes = shapely.polygons(
        np.stack([poses[:, None, 0] + c[:, None] * px - s[:, None] * py,
                  poses[:, None, 1] + s[:, None] * px + c[:, None] * py], -1)
    )  # fmt: skip
    disc = shapely.Point(2, 5.5).buffer(0.5, 512)
    obstacles = shapely.union_all([shapely.Polygon(wall), shapely.Polygon(ring, [hole]), disc])
    truth = float(shapely.distance(shapes, obstacles).min())
    assert metrics["min_clearance_m"] == pytest.approx(truth, abs=1e-4)
    assert (out / "path.png").stat().st_size > 10_000
    # the figure draws the polygons themselves (with the hole open) and the disc
    ax = plot_grid(load_map(world_file))
    assert len(ax.patches) == 3 and len(ax.images) == 0
    hole_centre, solid = (8.5, 4.5), (7.5, 3.5)
    fig = ax.figure
    fig.canvas.draw()
    pixels = np.asarray(fig.canvas.buffer_rgba())[..., :3].astype(float).mean(-1)
    height = pixels.shape[0]

    def shade(point):
        col, row = ax.transData.transform(point)
        return pixels[int(height - row), int(col)]

    assert shade(solid) < 60 and shade(hole_centre) > 200  # black polygon, white hole


def test_plan_takes_a_bundled_case_and_the_search_settings(tmp_path):
    # A slot 1.15 car lengths long needs moves of centimetres: with the case's settings, from
    # --case or as flags, the car parks in 13 moves, the same path both ways, ending on the
    # case's goal; with the planner's default (coarser) bins, by moves to contact too.
    from wheelbase.planning.maps import bundled_scenarios

    case = next(sc for sc in bundled_scenarios() if sc.name == "parallel_115_in")
    poses = ["--start", "13.014", "3.61", "0", "--goal", "6.972", "1.17", "0"]
    car = ["--turning-radius", "3.006", "--footprint", "4.69", "1.94",
           "--rear-axle-to-center", "1.415"]  # fmt: skip
    settings = ["--headings", "144", "--xy-resolution", "0.1", "--collision-step", "0.02",
                "--moves-to-contact"]  # fmt: skip
    runs = {
        "case": ["--case", "parallel_115_in"],
        "flags": ["parallel_115", *poses, *car, *settings],
        "defaults": ["parallel_115", *poses, *car],
    }
    metrics = {}
    for name, args in runs.items():
        result = runner.invoke(app, ["plan", *args, "--out", str(tmp_path / name)])
        assert result.exit_code == 0, result.output
        metrics[name] = json.loads((tmp_path / name / "metrics.json").read_text())
    assert metrics["defaults"]["success"] and metrics["defaults"]["cusps"] >= 5
    assert metrics["case"]["success"] and metrics["case"]["cusps"] >= 5
    assert metrics["flags"]["length_m"] == pytest.approx(metrics["case"]["length_m"], abs=1e-9)
    with (tmp_path / "case" / "path.csv").open() as handle:
        last = list(csv.DictReader(handle))[-1]
    end = [float(last["x_m"]), float(last["y_m"]), float(last["theta_rad"])]
    assert np.allclose(end, case.goal, atol=1e-9)
    # a flag beside --case overrides it: without moves cut at contact (and so without the
    # escape that follows them) the lattice cannot find the 13 moves
    coarse = runner.invoke(app, ["plan", "--case", "parallel_115_in", "--no-moves-to-contact",
                                 "--out", str(tmp_path / "coarse")])  # fmt: skip
    assert coarse.exit_code == 0, coarse.output
    assert json.loads((tmp_path / "coarse" / "metrics.json").read_text())["success"] is False


def test_plan_case_errors(tmp_path):
    for args, words in (
        (["--case", "nope"], "--case must be one of"),
        (["warehouse", "--case", "maze_car"], "leave out MAP"),
        (["--start", "1", "1", "0", "--goal", "2", "2", "0"], "give MAP"),
        (["warehouse", "--goal", "2", "2", "0"], "give --start"),
    ):
        result = runner.invoke(app, ["plan", *args, "--out", str(tmp_path / "o")])
        assert isinstance(result.exception, ConfigError), result.output
        assert words in str(result.exception)


def test_plan_accepts_empty_like_run_and_control(tmp_path):
    # `wheelbase run` and `control --map empty` took 'empty'; plan said "unknown map"
    from wheelbase.scenario import EMPTY_MAP_MARGIN, empty_map

    result = runner.invoke(app, ["plan", "empty", "--start", "0", "0", "0", "--goal", "6,-2,90",
                                 "--turning-radius", "1", "--out", str(tmp_path)])  # fmt: skip
    assert result.exit_code == 0, result.output
    metrics = json.loads((tmp_path / "metrics.json").read_text())
    assert metrics["success"] is True and metrics["length_m"] >= math.dist((0, 0), (6, -2))
    grid = empty_map([(0.0, 0.0, 0.0), (6.0, -2.0, 0.0)])
    assert not grid.occupied.any()
    np.testing.assert_allclose(grid.origin, (-EMPTY_MAP_MARGIN, -2 - EMPTY_MAP_MARGIN))
    assert grid.width_m == pytest.approx(6 + 2 * EMPTY_MAP_MARGIN)


def test_a_bare_image_map_needs_its_resolution(tmp_path):
    # a screenshot was read at an assumed 0.05 m/pixel without a word
    from PIL import Image

    from wheelbase.cli import app as wheelbase
    from wheelbase.errors import MapError
    from wheelbase.planning import load_map

    pixels = np.full((40, 60), 255, np.uint8)
    pixels[:, 28:32] = 0  # a wall with a gap at the top
    pixels[:8, 28:32] = 255
    image = tmp_path / "screenshot.png"
    Image.fromarray(pixels).save(image)
    with pytest.raises(MapError, match=r"bare image: give its resolution \[m/pixel\]"):
        load_map(image)
    grid = load_map(image, resolution=0.2)
    assert grid.resolution == 0.2 and grid.width_m == pytest.approx(12.0)
    with pytest.raises(MapError, match="resolution applies to a bare image map only"):
        load_map("maze", resolution=0.2)
    args = [
        "plan",
        str(image),
        "--start",
        "2,4,0",
        "--goal",
        "10,4,0",
        "--out",
        str(tmp_path / "p"),
    ]
    refused = runner.invoke(wheelbase, args)
    assert refused.exit_code == 2 and "--resolution" in refused.stderr
    assert not (tmp_path / "p").exists()
    planned = runner.invoke(wheelbase, [*args, "--resolution", "0.2"])
    assert planned.exit_code == 0, planned.output
    assert json.loads((tmp_path / "p" / "metrics.json").read_text())["success"] is True
