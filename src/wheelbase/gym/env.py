"""``wheelbase/Navigate-v0``: one robot drives to a sampled goal on a map (a Gymnasium env)."""

from __future__ import annotations

from typing import Any

import gymnasium
import numpy as np
from gymnasium import spaces

from wheelbase.gym.task import NavigateTask, check_actions

__all__ = ["NavigateEnv", "close_window", "render_frame", "show_window"]


def render_frame(task: NavigateTask, robots: Any = None, size: float = 5.0) -> np.ndarray:
    """An RGB image ``(H, W, 3)`` uint8 of the map, robots, lidar rays and goals.

    Parameters
    ----------
    task : NavigateTask
        The task to draw.
    robots : iterable of int, optional
        Which robots (default: all).
    size : float
        Figure size [inch] (100 dpi).
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    figure = Figure(figsize=(size, size), dpi=100)
    canvas = FigureCanvasAgg(figure)
    ax = figure.add_axes((0, 0, 1, 1))
    task.draw(ax, robots)
    canvas.draw()
    return np.asarray(canvas.buffer_rgba())[..., :3].copy()


class NavigateEnv(gymnasium.Env):
    """One robot of any scenario model drives to a goal sampled in free space.

    The task (observation, action, reward, termination) is documented in
    :mod:`wheelbase.gym.task`; this environment is that task with N = 1 on
    :class:`wheelbase.sim.Engine`. ``reset(seed=...)`` seeds the start and goal sampling (and
    the lidar noise); ``reset(options={"start": (x, y, θ), "goal": (x, y, θ)})`` fixes them.

    Parameters
    ----------
    render_mode : {None, "rgb_array", "human"}
        ``rgb_array``: :meth:`render` returns an image; ``human``: a matplotlib window.
    max_episode_steps : int or None
        Steps after which the environment itself truncates an episode; None (the default):
        never, as Gymnasium's environments do: ``gymnasium.make`` wraps it in a ``TimeLimit``
        of ``make(..., max_episode_steps=N)``, or of the registered
        :data:`~wheelbase.gym.task.EPISODE_STEPS` (300).
    **task : dict
        Keyword arguments of :class:`~wheelbase.gym.task.NavigateTask` (``map``, ``robot``,
        ``lidar``, ``dt``, ``max_speed``, ``max_yaw_rate``,
        ``goal_tolerance``, ``stop_at_goal``, ``min_goal_distance``, ``clearance``,
        ``rewards``).

    Examples
    --------
    >>> import gymnasium, wheelbase.gym
    >>> env = gymnasium.make("wheelbase/Navigate-v0")
    >>> observation, info = env.reset(seed=0)
    >>> observation.shape
    (65,)
    """

    metadata: dict[str, Any] = {"render_modes": ["rgb_array", "human"], "render_fps": 10}  # noqa: RUF012

    def __init__(
        self, render_mode: str | None = None, max_episode_steps: int | None = None, **task: Any
    ) -> None:
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            from wheelbase.errors import ConfigError

            raise ConfigError(
                f"render_mode must be None, 'rgb_array' or 'human' (got {render_mode!r})"
            )
        self.render_mode = render_mode
        self.task = NavigateTask(1, max_episode_steps=max_episode_steps, **task)
        self.metadata = {**self.metadata, "render_fps": round(1.0 / self.task.dt)}
        self.observation_space = spaces.Box(*self.task.observation_bounds(), dtype=np.float32)
        self.action_space = spaces.Box(-1.0, 1.0, (2,), dtype=np.float32)
        self._figure: Any = None

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """Start an episode: a new start and goal (sampled, or given in ``options``).

        Parameters
        ----------
        seed : int, optional
            Seed of the environment's generator.
        options : dict, optional
            ``start`` and/or ``goal``: poses (x [m], y [m], θ [rad]) instead of sampled ones.

        Returns
        -------
        observation : numpy.ndarray, shape (beams + 5,)
        info : dict
            ``distance`` to the goal [m], ``start``, ``goal``.
        """
        super().reset(seed=seed)
        start, goal = self.task.sample(1, self.np_random)
        options = options or {}
        if "start" in options:
            start = np.asarray(options["start"], dtype=np.float64).reshape(1, 3)
        if "goal" in options:
            goal = np.asarray(options["goal"], dtype=np.float64).reshape(1, 3)
        self.task.restart(np.array([0]), start, goal)
        if self.render_mode == "human":
            self.render()
        return self.task.observations()[0], self._info(False)

    def _info(self, arrived: bool) -> dict[str, Any]:
        return {
            "distance": float(self.task.distance[0]),
            "is_success": bool(arrived),
            "goal": self.task.goal[0].copy(),
        }

    def step(self, action: Any) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        """Apply a normalised action for one control step.

        Parameters
        ----------
        action : array_like, shape (2,)
            In [−1, 1] (see :mod:`wheelbase.gym.task`); NaN or outside: InputError.

        Returns
        -------
        observation, reward, terminated, truncated, info
        """
        if self.task.state is None:
            raise gymnasium.error.ResetNeeded("call reset() before step()")
        command = check_actions(action, 1)
        reward, arrived, collided, truncated = self.task.step(command, self.np_random)
        info = self._info(bool(arrived[0]))
        info["collision"] = bool(collided[0])
        if self.render_mode == "human":
            self.render()
        return (
            self.task.observations()[0],
            float(reward[0]),
            bool(arrived[0] or collided[0]),
            bool(truncated[0]),
            info,
        )

    def render(self) -> np.ndarray | None:
        """An RGB image (``rgb_array``) or a redrawn window (``human``); None otherwise."""
        if self.render_mode is None or self.task.state is None:
            return None
        if self.render_mode == "rgb_array":
            return render_frame(self.task)
        self._figure = show_window(self._figure, self.task, self.metadata["render_fps"])
        return None

    def close(self) -> None:
        """Close the window of ``human`` rendering."""
        self._figure = close_window(self._figure)


def show_window(figure: Any, task: NavigateTask, fps: float) -> Any:
    """Redraw ``task`` (every robot) in a matplotlib window and let it show for one frame.

    Parameters
    ----------
    figure : matplotlib.figure.Figure or None
        The window of earlier frames; None opens one.
    task : NavigateTask
        What to draw.
    fps : float
        Frames per second: the window shows this frame for 1/fps s.

    Returns
    -------
    matplotlib.figure.Figure
        The window, for the next frame.
    """
    import matplotlib.pyplot as plt

    if figure is None:
        figure = plt.figure(figsize=(5, 5))
    figure.clear()
    task.draw(figure.add_axes((0, 0, 1, 1)))
    plt.pause(1.0 / fps)
    return figure


def close_window(figure: Any) -> None:
    """Close a window of :func:`show_window` (None: nothing to close); returns None.

    Parameters
    ----------
    figure : matplotlib.figure.Figure or None
        The window.
    """
    if figure is not None:
        import matplotlib.pyplot as plt

        plt.close(figure)
