"""wheelbase.plot: the figures draw the simulated data, compose, and never overwrite silently."""

import subprocess
import sys
import types

import numpy as np
import pytest
from matplotlib.figure import Figure
from PIL import Image

from wheelbase import ConfigError, DiffDrive, InputError, simulate
from wheelbase.plot import (
    animate,
    footprint_outline,
    plot_path,
    plot_result,
    plot_states,
    save_figure,
)

ROBOT = DiffDrive(wheel_radius=0.05, half_track=0.2)
START = [0.0, 0.0, np.pi / 2]


@pytest.fixture(scope="module")
def arc():
    """Document 000 §3.2, case 1 (ω_L, ω_R) = (0.8, 0.6), Euler, 100 s."""
    return simulate(ROBOT, START, (0.8, 0.6), t_end=100.0, dt=0.1, method="euler")


@pytest.fixture(scope="module")
def spin():
    """Spinning in place for 100 s: θ wraps around ±π more than twice."""
    return simulate(ROBOT, START, (0.6, -0.6), t_end=100.0, dt=0.1, method="euler")


@pytest.fixture(scope="module")
def batch():
    pose0 = np.tile(START, (3, 1))
    speeds = np.array([(0.8, 0.6), (0.6, 0.6), (0.6, -0.6)])
    return simulate(ROBOT, pose0, speeds, t_end=20.0, dt=0.1, method="euler")


# --------------------------------------------------------------------------- footprint
def test_footprint_outline_is_the_rotated_rectangle():
    corners = footprint_outline([1.0, 2.0, np.pi / 2], (0.6, 0.4))
    assert corners.shape == (5, 2)
    np.testing.assert_allclose(corners[0], corners[-1])
    # Heading +y: the rear-right body corner (−l/2, −w/2) lies at (x + w/2, y − l/2).
    np.testing.assert_allclose(corners[0], [1.2, 1.7], atol=1e-12)
    # Front-left (l/2, w/2) at (x − w/2, y + l/2).
    np.testing.assert_allclose(corners[2], [0.8, 2.3], atol=1e-12)
    sides = np.hypot(*np.diff(corners, axis=0).T)
    np.testing.assert_allclose(sides, [0.6, 0.4, 0.6, 0.4])
    x, y = corners[:-1].T
    area = 0.5 * abs(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))
    assert area == pytest.approx(0.24)


def test_footprint_outline_batches():
    poses = np.random.default_rng(0).normal(size=(7, 4, 3))
    corners = footprint_outline(poses, (0.75, 0.4))
    assert corners.shape == (7, 4, 5, 2)
    np.testing.assert_allclose(corners[..., :4, :].mean(axis=-2), poses[..., :2], atol=1e-12)


@pytest.mark.parametrize("footprint", [(0.6,), (-0.6, 0.4), (0.6, float("nan")), None, "ab"])
def test_bad_footprint_is_a_config_error(footprint):
    with pytest.raises(ConfigError, match="footprint"):
        footprint_outline([0, 0, 0], footprint)


# --------------------------------------------------------------------------- states
def test_plot_states_draws_the_three_rows(arc):
    fig, axes = plot_states(arc)
    assert isinstance(fig, Figure) and len(axes) == 3
    for ax, column in zip(axes[:2], (0, 1), strict=True):
        (line,) = ax.get_lines()
        np.testing.assert_array_equal(line.get_xdata(), arc.t)
        np.testing.assert_array_equal(line.get_ydata(), arc.poses[:, column])
    assert [ax.get_ylabel() for ax in axes] == ["x [m]", "y [m]", "θ [rad] (unwrapped)"]
    assert axes[-1].get_xlabel() == "t [s]"


def test_plot_states_unwraps_theta(spin):
    _, axes = plot_states(spin)
    theta = axes[2].get_lines()[0].get_ydata()
    # ψ(t) = ψ0 + a(ω_R − ω_L)/(2d)·t: a straight line through several wraps of ±π.
    expected = np.pi / 2 + 0.05 * (-0.6 - 0.6) / (2 * 0.2) * spin.t
    np.testing.assert_allclose(theta, expected, atol=1e-9)
    assert np.max(np.abs(np.diff(spin.poses[:, 2]))) > np.pi  # the raw data does jump


def test_plot_states_into_given_axes_and_batch(batch):
    fig, axes = plot_states(batch, label=["a", "b", "c"])
    assert all(len(ax.get_lines()) == 3 for ax in axes)
    assert [line.get_label() for line in axes[0].get_lines()] == ["a", "b", "c"]
    fig2, axes2 = plot_states(batch.robot(0), axes=axes)
    assert fig2 is fig and len(axes2[0].get_lines()) == 4
    with pytest.raises(ConfigError, match="three"):
        plot_states(batch, axes=axes[:2])
    with pytest.raises(ConfigError, match="one entry per robot"):
        plot_states(batch, label=["a", "b"])


def test_plot_states_needs_times():
    with pytest.raises(InputError, match=r"\.t"):
        plot_states(np.zeros((4, 3)))


# --------------------------------------------------------------------------- path
def test_plot_path_draws_path_and_footprints(arc):
    _, ax = plot_path(arc, footprint=(0.75, 0.4), every=100)
    path_line = ax.get_lines()[0]
    np.testing.assert_array_equal(path_line.get_xydata(), arc.poses[:, :2])
    # Rectangles at samples 0, 100, …, 1000: 11 of them, each a 0.75 × 0.4 m rectangle.
    assert len(ax.patches) == 11
    last = ax.patches[-1].get_xy()[:4]
    np.testing.assert_allclose(last.mean(axis=0), arc.poses[-1, :2], atol=1e-12)
    assert ax.get_aspect() == 1.0
    (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
    assert x0 < arc.poses[:, 0].min() and x1 > arc.poses[:, 0].max()
    assert y0 < arc.poses[:, 1].min() and y1 > arc.poses[:, 1].max()


def test_plot_path_without_footprint_and_from_an_array(arc):
    _, ax = plot_path(arc.poses)
    assert len(ax.patches) == 0
    np.testing.assert_array_equal(ax.get_lines()[0].get_xydata(), arc.poses[:, :2])


def test_plot_path_batch_and_composition(batch, arc):
    fig, ax = plot_path(batch, footprint=(0.75, 0.4), label=["a", "b", "c"])
    paths = [line for line in ax.get_lines() if line.get_label() in "abc"]
    assert len(paths) == 3
    for i, line in enumerate(paths):
        np.testing.assert_array_equal(line.get_xydata(), batch.poses[:, i, :2])
    limits_before = ax.get_xlim(), ax.get_ylim()
    fig2, ax2 = plot_path(arc, ax=ax)  # the arc reaches x ≈ 2.5 m, beyond the 20 s batch
    assert fig2 is fig and ax2 is ax
    assert ax.get_xlim()[1] > arc.poses[:, 0].max() > limits_before[0][1]
    assert ax.get_ylim()[0] <= limits_before[1][0]


def test_plot_path_caps_robots(batch):
    _, ax = plot_path(batch, max_robots=2)
    assert sum(1 for line in ax.get_lines() if len(line.get_xdata()) > 1) == 2
    with pytest.raises(ConfigError, match="max_robots"):
        plot_path(batch, max_robots=0)


@pytest.mark.parametrize("every", [0, -3, 1.5, True])
def test_bad_every_is_a_config_error(arc, every):
    with pytest.raises(ConfigError, match="every"):
        plot_path(arc, footprint=(0.6, 0.4), every=every)


def test_non_finite_poses_are_an_input_error():
    with pytest.raises(InputError, match="finite"):
        plot_path(np.array([[0.0, 0.0, 0.0], [np.nan, 1.0, 0.0]]))
    with pytest.raises(InputError, match="at least one pose"):
        plot_path(np.zeros((0, 3)))
    with pytest.raises(InputError, match="at least one pose"):
        plot_path(np.zeros((5, 0, 3)))


# --------------------------------------------------------------------------- result
def test_plot_result_and_simresult_plot(arc, batch):
    fig = arc.plot(footprint=(0.75, 0.4))
    assert isinstance(fig, Figure)
    assert len(fig.axes) == 4
    assert "DiffDrive" in fig.get_suptitle() and "euler" in fig.get_suptitle()
    fig = plot_result(batch, title="three robots")
    assert fig.get_suptitle() == "three robots"
    assert len(fig.axes[1].get_lines()) == 3


def test_save_figure_refuses_to_overwrite(tmp_path, arc):
    target = tmp_path / "sub" / "path.png"
    fig, _ = plot_path(arc)
    assert save_figure(fig, target) == target
    assert target.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    target.write_bytes(b"user data")
    with pytest.raises(FileExistsError, match="overwrite=True"):
        save_figure(fig, target)
    assert target.read_bytes() == b"user data"
    save_figure(fig, target, overwrite=True)
    assert target.read_bytes()[:4] == b"\x89PNG"
    with pytest.raises(ConfigError, match="folder"):
        save_figure(fig, tmp_path)


# --------------------------------------------------------------------------- animation
def test_animate_writes_a_small_gif(tmp_path, arc):
    target = tmp_path / "a.gif"
    assert animate(arc, target, footprint=(0.75, 0.4), max_frames=12, fps=10, dpi=40) == target
    with Image.open(target) as gif:
        assert gif.format == "GIF"
        assert gif.n_frames == 12
        assert gif.info["duration"] == 100
        first = np.asarray(gif.convert("RGB"))
        gif.seek(gif.n_frames - 1)
        last = np.asarray(gif.convert("RGB"))
    assert np.any(first != last)  # the robot moved
    assert target.stat().st_size < 2_000_000


def test_animate_frame_spacing(tmp_path, arc):
    # every=250 on 1001 samples: frames at 0, 250, 500, 750, 1000.
    target = animate(arc, tmp_path / "b.gif", every=250, dpi=30)
    with Image.open(target) as gif:
        assert gif.n_frames == 5


def test_animate_batch(tmp_path, batch):
    target = animate(batch, tmp_path / "batch.gif", max_frames=5, dpi=30)
    with Image.open(target) as gif:
        assert gif.n_frames == 5


def test_animate_refuses_overwrite_and_bad_options(tmp_path, arc):
    target = tmp_path / "c.gif"
    target.write_bytes(b"keep")
    with pytest.raises(FileExistsError, match="exists"):
        animate(arc, target, max_frames=3)
    assert target.read_bytes() == b"keep"
    animate(arc, target, max_frames=3, dpi=30, overwrite=True)
    assert target.read_bytes()[:3] == b"GIF"
    with pytest.raises(ConfigError, match=r"\.gif"):
        animate(arc, tmp_path / "c.mp4")
    with pytest.raises(ConfigError, match="fps"):
        animate(arc, tmp_path / "d.gif", fps=0)
    with pytest.raises(ConfigError, match="max_frames"):
        animate(arc, tmp_path / "d.gif", max_frames=1)
    assert not (tmp_path / "d.gif").exists()


def test_importing_plot_does_not_load_pyplot():
    code = "import sys, wheelbase.plot; print('matplotlib.pyplot' in sys.modules)"
    output = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True
    ).stdout
    assert output.strip() == "False"


def test_the_animation_title_is_the_status_at_that_time(tmp_path):
    # every frame said "arrived t = 9.6 s", the final status, from the first frame on
    from wheelbase.control import PolarPose
    from wheelbase.models import Unicycle
    from wheelbase.plot import animate
    from wheelbase.report import status_at
    from wheelbase.sim import closed_loop

    log = closed_loop(PolarPose(), Unicycle(), [1.0, 0.5, 0.0], [0, 0, 0], 20.0, 0.05,
                      goal=[0, 0, 0], tolerance=(0.01, 0.02))  # fmt: skip
    last = int(log.length[0]) - 1
    assert log.statuses[0] == "arrived"
    assert [status_at(log, k) for k in (0, last // 2, last - 1)] == ["running"] * 3
    assert status_at(log, last) == "arrived"
    asked = []

    def title(k: int) -> str:
        asked.append(k)
        return status_at(log, k)

    run = types.SimpleNamespace(t=log.t, poses=log.true_pose[0])
    animate(run, tmp_path / "run.gif", title=title, max_frames=12)
    frames = sorted(set(asked))
    assert len(frames) == 12 and frames[0] == 0 and frames[-1] == log.t.size - 1
