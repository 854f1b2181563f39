"""N robots of ``wheelbase/Navigate-v0`` stepped in one call: a native Gymnasium vector env.

Every call steps all N robots through one :meth:`wheelbase.sim.Engine.step` (the batch axis of
the engine), one footprint collision check and one lidar scan of ``(N, beams)`` rays, instead
of N Python environments. The task is the same :class:`~wheelbase.gym.task.NavigateTask` as the
single environment's, so robot ``i`` behaves exactly as a :class:`~wheelbase.gym.NavigateEnv`
given the same start, goal and actions.

Autoreset follows Gymnasium's modes (https://farama.org/Vector-Autoreset-Mode):

``next_step`` (default, ``AutoresetMode.NEXT_STEP``)
    The step that ends an episode returns its last observation; on the next call that
    robot's action is ignored, a new episode starts, and its reward is 0 and both flags
    False.
``same_step``
    The step that ends an episode starts the next one at once: the observation returned is
    the new episode's first, and ``info["final_obs"]`` / ``info["final_info"]`` (with their
    ``_final_obs`` masks) hold the last one's.
``disabled``
    Nothing restarts by itself; ``reset(options={"reset_mask": mask})`` restarts robots.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium import error as gym_error
from gymnasium import spaces
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from wheelbase.errors import ConfigError, InputError
from wheelbase.gym.env import close_window, render_frame, show_window
from wheelbase.gym.task import NavigateTask, check_actions

__all__ = ["NavigateVectorEnv"]

_MODES = {
    "next_step": AutoresetMode.NEXT_STEP,
    "same_step": AutoresetMode.SAME_STEP,
    "disabled": AutoresetMode.DISABLED,
}


class NavigateVectorEnv(VectorEnv):
    """``num_envs`` robots navigating to their own goals on one map, stepped in one call.

    Parameters
    ----------
    num_envs : int
        Number of robots N, >= 1.
    autoreset_mode : str or AutoresetMode
        ``next_step`` (default), ``same_step`` or ``disabled`` (module docstring).
    render_mode : {None, "rgb_array", "human"}
        ``rgb_array``: :meth:`render` returns one image with every robot; ``human``: every
        reset and step redraws them in a matplotlib window (at ``render_fps``).
    **task : dict
        Keyword arguments of :class:`~wheelbase.gym.task.NavigateTask`, as for
        :class:`~wheelbase.gym.NavigateEnv`.

    Examples
    --------
    >>> import gymnasium, wheelbase.gym
    >>> envs = gymnasium.make_vec("wheelbase/Navigate-v0", num_envs=8,
    ...                           vectorization_mode="vector_entry_point")
    >>> observations, infos = envs.reset(seed=0)
    >>> observations.shape
    (8, 65)
    """

    def __init__(
        self,
        num_envs: int = 1,
        autoreset_mode: str | AutoresetMode = "next_step",
        render_mode: str | None = None,
        **task: Any,
    ) -> None:
        mode = autoreset_mode
        if isinstance(mode, str) and mode in _MODES:
            mode = _MODES[mode]
        if not isinstance(mode, AutoresetMode):
            raise ConfigError(
                f"autoreset_mode must be one of {', '.join(_MODES)} (got {autoreset_mode!r})"
            )
        if render_mode not in (None, "rgb_array", "human"):
            raise ConfigError(
                f"render_mode must be None, 'rgb_array' or 'human' (got {render_mode!r})"
            )
        self.task = NavigateTask(num_envs, **task)
        self.num_envs = self.task.n
        self.render_mode = render_mode
        self.metadata = {
            "autoreset_mode": mode,
            "render_modes": ["rgb_array", "human"],
            "render_fps": round(1.0 / self.task.dt),
        }
        self.single_observation_space = spaces.Box(
            *self.task.observation_bounds(), dtype=np.float32
        )
        self.single_action_space = spaces.Box(-1.0, 1.0, (2,), dtype=np.float32)
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self._restart_next = np.zeros(self.num_envs, dtype=bool)
        self._figure: Any = None

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """Start new episodes for every robot (or those of ``options["reset_mask"]``).

        Parameters
        ----------
        seed : int, optional
            Seed of the one generator of the batch (starts, goals, lidar noise).
        options : dict, optional
            ``reset_mask`` (N,) bool: restart only these robots; ``start`` / ``goal``: poses
            (M, 3) [m, m, rad] for the restarted robots instead of sampled ones.

        Returns
        -------
        observations : numpy.ndarray, shape (N, beams + 5)
        infos : dict
            ``distance`` (N,) [m] with its ``_distance`` mask.
        """
        if seed is not None:
            self._np_random, self._np_random_seed = seeding.np_random(seed)
        options = dict(options or {})
        mask = np.ones(self.num_envs, dtype=bool)
        if "reset_mask" in options:
            mask = np.asarray(options.pop("reset_mask"))
            if mask.shape != (self.num_envs,) or mask.dtype != bool:
                raise InputError(
                    f"reset_mask must be a bool array of shape ({self.num_envs},) "
                    f"(got {mask.dtype} {mask.shape})"
                )
            if self.task.state is None and not mask.all():
                raise InputError("the first reset starts every robot: leave out reset_mask")
        self._restart(mask, options.get("start"), options.get("goal"))
        self._restart_next[mask] = False
        if self.render_mode == "human":
            self.render()
        return self.task.observations(), self._infos()

    def _restart(self, mask: np.ndarray, start: Any = None, goal: Any = None) -> None:
        count = int(mask.sum())
        if count == 0:
            return
        sampled_start, sampled_goal = self.task.sample(count, self.np_random)
        self.task.restart(
            mask,
            sampled_start if start is None else start,
            sampled_goal if goal is None else goal,
        )

    def _infos(self, arrived: Any = None) -> dict[str, Any]:
        every = np.ones(self.num_envs, dtype=bool)
        infos: dict[str, Any] = {"distance": self.task.distance.copy(), "_distance": every}
        if arrived is not None:
            infos["is_success"], infos["_is_success"] = arrived, every
        return infos

    def step(
        self, actions: Any
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]:
        """Step every robot by its normalised action (see :mod:`wheelbase.gym.task`).

        Parameters
        ----------
        actions : array_like, shape (N, 2)
            In [−1, 1]; NaN or outside: InputError (``gymnasium.wrappers.vector.ClipAction``
            clips a policy's raw output).

        Returns
        -------
        observations : numpy.ndarray, shape (N, beams + 5)
        rewards : numpy.ndarray, shape (N,)
        terminations, truncations : numpy.ndarray of bool, shape (N,)
        infos : dict
            ``distance`` [m], ``is_success`` (arrived this step), with ``_`` masks; in
            ``same_step`` mode also ``final_obs`` and ``final_info``.
        """
        task = self.task
        if task.state is None:
            raise gym_error.ResetNeeded("call reset() before step()")
        mode = self.metadata["autoreset_mode"]
        restart = self._restart_next
        command = check_actions(actions, self.num_envs)
        if restart.any():
            command[restart] = 0.0  # ignored: these robots start anew below
        reward, arrived, collided, truncated = task.step(command, self.np_random)
        terminated = arrived | collided
        if mode == AutoresetMode.NEXT_STEP and restart.any():
            self._restart(restart)
            reward[restart] = 0.0
            terminated[restart] = truncated[restart] = arrived[restart] = False
        done = terminated | truncated
        infos = self._infos(arrived)
        observations = task.observations()
        if mode == AutoresetMode.SAME_STEP and done.any():
            final_obs = np.full(self.num_envs, None, dtype=object)
            final_info = np.full(self.num_envs, None, dtype=object)
            for i in np.flatnonzero(done):
                final_obs[i] = observations[i].copy()
                final_info[i] = {"distance": float(infos["distance"][i]),
                                 "is_success": bool(arrived[i])}  # fmt: skip
            self._restart(done)
            observations = task.observations()
            infos = self._infos(arrived)
            infos.update(final_obs=final_obs, _final_obs=done.copy(),
                         final_info=final_info, _final_info=done.copy())  # fmt: skip
        self._restart_next = done if mode == AutoresetMode.NEXT_STEP else np.zeros_like(done)
        if self.render_mode == "human":
            self.render()
        return observations, reward, terminated, truncated, infos

    def render(self) -> np.ndarray | None:
        """One RGB image of every robot (``rgb_array``), the window redrawn (``human``), or
        None."""
        if self.render_mode is None or self.task.state is None:
            return None
        if self.render_mode == "rgb_array":
            return render_frame(self.task)
        self._figure = show_window(self._figure, self.task, self.metadata["render_fps"])
        return None

    def close_extras(self, **kwargs: Any) -> None:
        """Close the window of ``human`` rendering (``VectorEnv.close`` calls this)."""
        self._figure = close_window(self._figure)
