"""Matplotlib figures and GIF animations of simulation results.

Everything here draws data that the algorithms returned; nothing here computes a trajectory.
Figures are created as :class:`matplotlib.figure.Figure` objects, not through ``pyplot``, so
the module works on any backend (Agg on a server), keeps no global state and never calls
``plt.show()``. Every function accepts an existing ``ax`` (or ``axes``) to draw into and
returns what it drew on, so figures compose.

Results are anything with ``t`` (T,) and ``poses`` (T, 3) or (T, N, 3) arrays, such as
:class:`wheelbase.SimResult`; a batch (T, N, 3) draws one path per robot. Units on the axes
are SI (m, s, rad).

Examples
--------
>>> from wheelbase import DiffDrive, simulate
>>> from wheelbase.plot import plot_path
>>> result = simulate(DiffDrive(0.05, 0.2), [0, 0, np.pi / 2], (0.8, 0.6), 100, 0.1, "euler")
>>> fig, ax = plot_path(result, footprint=(0.75, 0.4))
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.collections import LineCollection
from matplotlib.figure import Figure
from matplotlib.patches import Polygon
from numpy.typing import ArrayLike
from PIL import Image

from wheelbase._validate import as_float_array, finite, positive
from wheelbase.errors import ConfigError, InputError
from wheelbase.geometry import transform_points

__all__ = [
    "agg_pyplot",
    "animate",
    "footprint_outline",
    "plot_path",
    "plot_result",
    "plot_states",
    "save_and_close",
    "save_figure",
]

MAX_FRAMES = 150
"""Default cap on the number of frames of :func:`animate` (keeps GIFs small and fast)."""

_FOOTPRINT_COLOUR = "tab:green"


# --------------------------------------------------------------------------- helpers
def footprint_outline(
    pose: ArrayLike, footprint: tuple[float, float], center_offset: float = 0.0
) -> np.ndarray:
    """Corners of the robot rectangle in the world frame, closed (first corner repeated).

    Parameters
    ----------
    pose : array_like, shape (..., 3)
        Robot poses (x [m], y [m], θ [rad]); the rectangle is centred on (x, y).
    footprint : (float, float)
        Length along the body x axis and width along the body y axis [m], both > 0
        (document 000 §3.2 draws 0.6 × 0.4 m and 0.75 × 2d m).
    center_offset : float
        Distance [m] from the pose's point forward to the rectangle's centre (e.g. from the
        rear axle of a car); 0 centres the rectangle on (x, y).

    Returns
    -------
    numpy.ndarray, shape (..., 5, 2)
        Rear-right, front-right, front-left, rear-left, rear-right corners [m].
    """
    length, width = _check_footprint(footprint)
    corners = 0.5 * np.array(
        [[-length, -width], [length, -width], [length, width], [-length, width], [-length, -width]]
    )
    corners[:, 0] += finite("center_offset", center_offset, "m")
    return transform_points(as_float_array("pose", pose, 3), corners)


def save_figure(
    fig: Figure, path: str | Path, *, overwrite: bool = False, dpi: float = 100.0
) -> Path:
    """Save ``fig`` to ``path`` (format from the suffix), refusing to replace a file.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure to save.
    path : str or pathlib.Path
        Destination; missing parent folders are created.
    overwrite : bool
        Replace an existing file. Default False.
    dpi : float
        Resolution [dots per inch], > 0.

    Returns
    -------
    pathlib.Path
        The path written.

    Raises
    ------
    FileExistsError
        If ``path`` exists and ``overwrite`` is false.
    """
    path = _writable(path, overwrite)
    fig.savefig(path, dpi=positive("dpi", dpi, "dots/inch"))
    return path


def agg_pyplot() -> Any:
    """:mod:`matplotlib.pyplot` on the Agg backend (figures for files, never a window).

    Returns
    -------
    module
        ``matplotlib.pyplot``.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def save_and_close(fig: Any, path: str | Path, dpi: float = 110.0) -> Path:
    """Lay out a pyplot figure, write it to ``path`` and close it (a file already there is
    replaced: the command that chose ``path`` decides about overwriting).

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        A figure made through :func:`agg_pyplot`.
    path : str or pathlib.Path
        Destination (format from the suffix).
    dpi : float
        Resolution [dots per inch].

    Returns
    -------
    pathlib.Path
        The path written.
    """
    fig.tight_layout()
    path = Path(path)
    fig.savefig(path, dpi=dpi)
    agg_pyplot().close(fig)
    return path


def _writable(path: str | Path, overwrite: bool) -> Path:
    path = Path(path)
    if path.is_dir():
        raise ConfigError(f"{path} is a folder; give a file name")
    if path.exists() and not overwrite:
        raise FileExistsError(f"{path} exists; pass overwrite=True to replace it")
    path.parent.mkdir(parents=True, exist_ok=True)
    return path


def _check_footprint(footprint: Any) -> tuple[float, float]:
    try:
        length, width = footprint
    except (TypeError, ValueError):
        raise ConfigError(f"footprint must be (length, width) in m (got {footprint!r})") from None
    return positive("footprint length", length, "m"), positive("footprint width", width, "m")


def _check_every(every: Any) -> int | None:
    if every is None:
        return None
    if isinstance(every, bool) or not isinstance(every, (int, np.integer)) or every < 1:
        raise ConfigError(f"every must be an integer >= 1 (got {every!r})")
    return int(every)


def _poses(result: Any) -> np.ndarray:
    """Poses of a result (or a raw pose array) as a (T, N, 3) array."""
    poses = getattr(result, "poses", result)
    poses = as_float_array("poses", poses, 3, min_ndim=1, max_ndim=3)
    if poses.ndim == 1:
        poses = poses[None, :]
    if poses.ndim == 2:
        poses = poses[:, None, :]
    if poses.shape[0] == 0 or poses.shape[1] == 0:
        raise InputError(f"poses must hold at least one pose (got shape {poses.shape})")
    return poses


def _times(result: Any, n: int) -> np.ndarray:
    if not hasattr(result, "t"):
        raise InputError(f"expected a result with .t and .poses (got {type(result).__name__})")
    t = as_float_array("t", result.t, min_ndim=1, max_ndim=1)
    if t.size != n:
        raise InputError(f"result.t has {t.size} samples but result.poses has {n}")
    return t


def _robot_indices(n_robots: int, max_robots: int) -> np.ndarray:
    if isinstance(max_robots, bool) or not isinstance(max_robots, (int, np.integer)):
        raise ConfigError(f"max_robots must be an integer >= 1 (got {max_robots!r})")
    if max_robots < 1:
        raise ConfigError(f"max_robots must be an integer >= 1 (got {max_robots})")
    if n_robots <= max_robots:
        return np.arange(n_robots)
    return np.unique(np.linspace(0, n_robots - 1, max_robots).round().astype(np.int64))


def _labels(label: str | Sequence[str] | None, n_robots: int, keep: np.ndarray) -> list:
    """One legend label (or None) per drawn robot."""
    if label is None:
        return [None] * keep.size
    if isinstance(label, str):
        return [label] + [None] * (keep.size - 1)
    labels = [str(item) for item in label]
    if len(labels) != n_robots:
        raise ConfigError(f"label needs one entry per robot ({n_robots}) (got {len(labels)})")
    return [labels[i] for i in keep]


def _sample_indices(n: int, every: int | None, target: int) -> np.ndarray:
    """Sample indices 0, every, 2·every, …, always with the last; ``target`` of them if None."""
    if every is None:
        every = max(1, int(np.ceil((n - 1) / max(target - 1, 1))))
    index = np.arange(0, n, every)
    if index[-1] != n - 1:
        index = np.append(index, n - 1)
    return index


def _new_axes(ax: Axes | None, figsize: tuple[float, float]) -> tuple[Figure, Axes]:
    if ax is not None:
        return ax.figure, ax
    fig = Figure(figsize=figsize, layout="constrained")
    return fig, fig.add_subplot()


def _draw_footprint(ax: Axes, pose: np.ndarray, footprint, colour, **kw: Any) -> list[Any]:
    outline = footprint_outline(pose, footprint)
    patch = Polygon(outline[:-1], closed=True, facecolor=colour, edgecolor="k", **kw)
    ax.add_patch(patch)
    # A line from the centre to the middle of the front edge shows the heading.
    front = 0.5 * (outline[1] + outline[2])
    (nose,) = ax.plot([pose[0], front[0]], [pose[1], front[1]], color="k", lw=1.0)
    return [patch, nose]


def _limits(poses: np.ndarray, footprint) -> tuple[tuple[float, float], tuple[float, float]]:
    """x and y limits [m] that hold every pose and its footprint, with a 5 % margin."""
    xy = poses[..., :2].reshape(-1, 2)
    margin = 0.5 * float(np.hypot(*footprint)) if footprint is not None else 0.0
    low, high = xy.min(axis=0) - margin, xy.max(axis=0) + margin
    span = float(max(np.max(high - low), 1e-3))
    centre = 0.5 * (low + high)
    half = 0.5 * np.maximum(high - low, 0.2 * span) + 0.05 * span
    return (centre[0] - half[0], centre[0] + half[0]), (centre[1] - half[1], centre[1] + half[1])


def _fit_limits(ax: Axes, poses: np.ndarray, footprint) -> None:
    xlim, ylim = _limits(poses, footprint)
    ax.set_xlim(*xlim)
    ax.set_ylim(*ylim)


def _path_figsize(poses: np.ndarray, footprint) -> tuple[float, float]:
    """A figure size whose shape follows the path's bounding box (equal axes waste less)."""
    xlim, ylim = _limits(poses, footprint)
    aspect = (ylim[1] - ylim[0]) / (xlim[1] - xlim[0])
    box_width, box_height = 5.4, 5.4 * aspect  # inches of the axes box itself
    if box_height > 6.5:
        box_width, box_height = max(6.5 / aspect, 2.5), 6.5
    box_height = max(box_height, 2.0)
    return box_width + 1.2, box_height + 1.1  # room for the labels and a title


# --------------------------------------------------------------------------- figures
def plot_states(
    result: Any,
    *,
    axes: Sequence[Axes] | None = None,
    max_robots: int = 100,
    label: str | Sequence[str] | None = None,
    **line_kw: Any,
) -> tuple[Figure, np.ndarray]:
    """Plot x(t), y(t) and θ(t) in three stacked axes.

    θ is unwrapped along time with :func:`numpy.unwrap` (continuous instead of jumping at ±π)
    and labelled so. Document 000 §3.2's MATLAB code plots the first row of η three times; this
    plots the three rows.

    Parameters
    ----------
    result : SimResult or similar
        Anything with ``t`` (T,) [s] and ``poses`` (T, 3) or (T, N, 3).
    axes : sequence of three Axes, optional
        Where to draw; a new figure is created if omitted.
    max_robots : int
        For a batch, draw at most this many robots (evenly spaced indices).
    label : str or sequence of str, optional
        Legend label of the (first) robot, or one label per robot of a batch.
    **line_kw
        Passed to :meth:`matplotlib.axes.Axes.plot`.

    Returns
    -------
    (Figure, numpy.ndarray of three Axes)
    """
    poses = _poses(result)
    t = _times(result, poses.shape[0])
    keep = _robot_indices(poses.shape[1], max_robots)
    labels = _labels(label, poses.shape[1], keep)
    poses = poses[:, keep]
    if axes is None:
        fig = Figure(figsize=(6.4, 6.0), layout="constrained")
        axes = np.asarray(fig.subplots(3, 1, sharex=True))
    else:
        axes = np.asarray(axes, dtype=object).ravel()
        if axes.size != 3:
            raise ConfigError(f"axes must hold three Axes (got {axes.size})")
        fig = axes[0].figure
    theta = np.unwrap(poses[..., 2], axis=0)
    names = ("x [m]", "y [m]", "θ [rad] (unwrapped)")
    for ax, values, name in zip(axes, (poses[..., 0], poses[..., 1], theta), names, strict=True):
        for line, text in zip(ax.plot(t, values, **line_kw), labels, strict=True):
            if text is not None:
                line.set_label(text)
        ax.set_ylabel(name)
        ax.grid(True, alpha=0.3)
    axes[-1].set_xlabel("t [s]")
    return fig, axes


def plot_path(
    result: Any,
    *,
    footprint: tuple[float, float] | None = None,
    every: int | None = None,
    ax: Axes | None = None,
    max_robots: int = 100,
    label: str | Sequence[str] | None = None,
    colour: Any = None,
) -> tuple[Figure, Axes]:
    """Plot the x–y path with the robot rectangle drawn at intervals, on equal axes.

    Parameters
    ----------
    result : SimResult, array_like or similar
        Anything with ``poses`` (T, 3) or (T, N, 3), or such an array [m, m, rad].
    footprint : (float, float), optional
        Robot length and width [m]; no rectangles are drawn if omitted.
    every : int, optional
        Draw a rectangle every ``every`` recorded poses (and at the last one); by default about
        ten per path.
    ax : Axes, optional
        Where to draw; a new figure is created if omitted.
    max_robots : int
        For a batch, draw at most this many robots (evenly spaced indices).
    label : str or sequence of str, optional
        Legend label of the (first) path, or one label per robot of a batch.
    colour : matplotlib colour, optional
        Colour of the path line(s); the colour cycle by default.

    Returns
    -------
    (Figure, Axes)

    Notes
    -----
    Drawing into an ``ax`` that already holds paths widens its limits to show both.
    """
    poses = _poses(result)
    keep = _robot_indices(poses.shape[1], max_robots)
    labels = _labels(label, poses.shape[1], keep)
    poses = poses[:, keep]
    every = _check_every(every)
    if footprint is not None:
        footprint = _check_footprint(footprint)
    previous = (ax.get_xlim(), ax.get_ylim()) if ax is not None and ax.has_data() else None
    fig, ax = _new_axes(ax, _path_figsize(poses, footprint))
    batch = poses.shape[1] > 1
    for i in range(poses.shape[1]):
        path = poses[:, i]
        (line,) = ax.plot(
            path[:, 0],
            path[:, 1],
            color=colour,
            lw=1.5,
            label=labels[i],
            zorder=3,
        )
        ax.plot(*path[0, :2], "o", color=line.get_color(), ms=4, zorder=3)
        if footprint is not None:
            face = line.get_color() if batch or previous else _FOOTPRINT_COLOUR
            for k in _sample_indices(len(path), every, 9):
                _draw_footprint(ax, path[k], footprint, face, alpha=0.25, lw=0.5)
    ax.set_aspect("equal", adjustable="box")
    _fit_limits(ax, poses, footprint)
    if previous is not None:
        (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
        ax.set_xlim(min(x0, previous[0][0]), max(x1, previous[0][1]))
        ax.set_ylim(min(y0, previous[1][0]), max(y1, previous[1][1]))
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.grid(True, alpha=0.3)
    if any(text is not None for text in labels):
        ax.legend(loc="best")
    return fig, ax


def plot_result(
    result: Any,
    *,
    footprint: tuple[float, float] | None = None,
    every: int | None = None,
    title: str | None = None,
    max_robots: int = 100,
) -> Figure:
    """One figure with the path (left) and x(t), y(t), θ(t) (right).

    This is what :meth:`wheelbase.SimResult.plot` draws.

    Parameters
    ----------
    result : SimResult or similar
        Anything with ``t`` (T,) [s] and ``poses`` (T, 3) or (T, N, 3).
    footprint : (float, float), optional
        Robot length and width [m] drawn along the path.
    every : int, optional
        Rectangle spacing in recorded poses (see :func:`plot_path`).
    title : str, optional
        Figure title; by default the model and integration method when known.
    max_robots : int
        For a batch, draw at most this many robots.

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig = Figure(figsize=(11.0, 5.5), layout="constrained")
    grid = fig.add_gridspec(3, 2, width_ratios=(1.2, 1.0))
    path_ax = fig.add_subplot(grid[:, 0])
    state_axes = [fig.add_subplot(grid[0, 1])]
    state_axes += [fig.add_subplot(grid[k, 1], sharex=state_axes[0]) for k in (1, 2)]
    plot_path(result, footprint=footprint, every=every, ax=path_ax, max_robots=max_robots)
    plot_states(result, axes=state_axes, max_robots=max_robots)
    if title is None:
        model = getattr(result, "model", None)
        method = getattr(result, "method", None)
        if model is not None and method is not None:
            title = f"{type(model).__name__}, {method}"
    if title:
        fig.suptitle(title)
    return fig


# --------------------------------------------------------------------------- animation
def animate(
    result: Any,
    path: str | Path,
    *,
    footprint: tuple[float, float] = (0.6, 0.4),
    fps: float = 15.0,
    every: int | None = None,
    max_frames: int = MAX_FRAMES,
    overwrite: bool = False,
    dpi: float = 80.0,
    max_robots: int = 20,
    title: str | Callable[[int], str] | None = None,
    center_offset: float = 0.0,
    background: Callable[[Axes], None] | None = None,
    overlay: Callable[[int], Sequence[np.ndarray] | Mapping[str, Sequence[np.ndarray]]]
    | None = None,
) -> Path:
    """Write a GIF of the robot footprint moving along its path, with the path trace.

    Uses matplotlib's Pillow writer (no external program needed).

    Parameters
    ----------
    result : SimResult or similar
        Anything with ``t`` (T,) [s] and ``poses`` (T, 3) or (T, N, 3).
    path : str or pathlib.Path
        Output file; must end in ``.gif``.
    footprint : (float, float)
        Robot length and width [m]. Default 0.6 × 0.4 m (document 000 §3.2, program 1).
    fps : float
        Frames per second of the GIF, > 0.
    every : int, optional
        One frame every ``every`` recorded poses (plus the last); by default spaced so that
        there are ``max_frames`` frames.
    max_frames : int
        Cap on the number of frames; with more, the frames are thinned evenly.
    overwrite : bool
        Replace an existing file. Default False.
    dpi : float
        Resolution [dots per inch] of the frames (5.5 inches along the longer side).
    max_robots : int
        For a batch, animate at most this many robots.
    title : str or callable, optional
        Axes title, shown before the running time; a callable ``title(k)`` gives the title of
        the frame of recorded pose ``k`` (a run's status at that time, not its final one).
    center_offset : float
        Reference point to footprint centre [m] (see :func:`footprint_outline`).
    background : callable, optional
        ``background(ax)`` draws the static part (a map, a plan) once, after the axes limits
        are set from the path; it may change the limits.
    overlay : callable, optional
        ``overlay(k)`` returns polylines ``(M, 2)`` [m] (or a mapping of matplotlib colours to
        polylines, each drawn in its colour) drawn thinly in the frame of recorded
        pose ``k`` (e.g. a controller's sampled rollouts); an empty sequence draws none.

    Returns
    -------
    pathlib.Path
        The GIF written.

    Raises
    ------
    FileExistsError
        If ``path`` exists and ``overwrite`` is false.
    ConfigError
        For a suffix other than ``.gif`` or a bad ``fps``, ``every``, ``max_frames``.
    """
    path = Path(path)
    if path.suffix.lower() != ".gif":
        raise ConfigError(f"animation path must end in .gif (got {path.name!r})")
    footprint = _check_footprint(footprint)
    fps = positive("fps", fps, "frames/s")
    every = _check_every(every)
    if isinstance(max_frames, bool) or not isinstance(max_frames, (int, np.integer)):
        raise ConfigError(f"max_frames must be an integer >= 2 (got {max_frames!r})")
    if max_frames < 2:
        raise ConfigError(f"max_frames must be an integer >= 2 (got {max_frames})")
    poses = _poses(result)
    t = _times(result, poses.shape[0])
    poses = poses[:, _robot_indices(poses.shape[1], max_robots)]
    frames = _sample_indices(poses.shape[0], every, max_frames)
    if frames.size > max_frames:
        frames = frames[np.unique(np.linspace(0, frames.size - 1, max_frames).round().astype(int))]
    path = _writable(path, overwrite)

    width, height = _path_figsize(poses, footprint)
    scale = 5.5 / max(width, height)  # the longer side 5.5 inches
    fig = Figure(figsize=(width * scale, height * scale), layout="constrained")
    ax = fig.add_subplot()
    ax.set_aspect("equal", adjustable="box")
    _fit_limits(ax, poses, footprint)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.grid(True, alpha=0.3)
    n_robots = poses.shape[1]
    trails = [
        ax.plot([], [], "b-", lw=1.2, label="path" if i == 0 else None)[0] for i in range(n_robots)
    ]
    if background is not None:
        background(ax)
    corners = footprint_outline(poses, footprint, center_offset)  # (T, N, 5, 2)
    bodies = [
        Polygon(corners[0, i, :-1], closed=True, facecolor=_FOOTPRINT_COLOUR, edgecolor="k",
                label="robot" if i == 0 else None)
        for i in range(n_robots)
    ]  # fmt: skip
    for body in bodies:
        ax.add_patch(body)
    noses = [ax.plot([], [], "k-", lw=1.0)[0] for _ in range(n_robots)]
    ax.legend(loc="upper right")

    def caption(k: int) -> str:
        text = title(k) if callable(title) else title
        return f"{text}   t = {t[k]:.1f} s" if text else f"t = {t[k]:.1f} s"

    heading = ax.set_title(caption(int(frames[-1])))  # reserves room in the layout

    canvas = FigureCanvasAgg(fig)
    fig.set_dpi(positive("dpi", dpi, "dots/inch"))
    extra = LineCollection([], colors="tab:purple", linewidths=0.5, alpha=0.6)
    ax.add_collection(extra)
    moving = [extra, *trails, *bodies, *noses, heading]
    for artist in moving:
        artist.set_animated(True)
    canvas.draw()  # lays out and renders the static part once
    fig.set_layout_engine("none")
    background = canvas.copy_from_bbox(fig.bbox)
    images = []
    for k in frames:
        canvas.restore_region(background)
        for i in range(n_robots):
            trails[i].set_data(poses[: k + 1, i, 0], poses[: k + 1, i, 1])
            bodies[i].set_xy(corners[k, i, :-1])
            front = 0.5 * (corners[k, i, 1] + corners[k, i, 2])
            noses[i].set_data([poses[k, i, 0], front[0]], [poses[k, i, 1], front[1]])
        heading.set_text(caption(int(k)))
        drawn = overlay(int(k)) if overlay is not None else []
        if isinstance(drawn, Mapping):
            lines = [(line, colour) for colour, group in drawn.items() for line in group]
            extra.set_segments([line for line, _ in lines])
            extra.set_color([colour for _, colour in lines] or "tab:purple")
        else:
            extra.set_segments(list(drawn))
            extra.set_color("tab:purple")
        for artist in moving:
            fig.draw_artist(artist)
        images.append(
            Image.frombuffer("RGBA", canvas.get_width_height(), canvas.buffer_rgba()).convert("RGB")
        )
    # One palette for every frame, taken from the last (it holds every colour): smaller files
    # and no colour flicker between frames.
    palette = images[-1].quantize(colors=64, method=Image.Quantize.FASTOCTREE)
    gif = [image.quantize(palette=palette, dither=Image.Dither.NONE) for image in images]
    gif[0].save(path, save_all=True, append_images=gif[1:], duration=round(1000.0 / fps), loop=0)
    return path
