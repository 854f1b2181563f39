"""
PPO (Stable-Baselines3) learns wheelbase/Navigate-v0 in the empty room
======================================================================

Usage::

    pip install -e ".[rl]"
    python examples/gym_ppo.py [OUT_DIR] [--timesteps N]      # default: examples/out/

A differential drive learns to reach goals sampled in the walled 10 m room from its 60-beam
lidar, the goal's distance and bearing and its own twist. PPO steps 32 robots at once through
:class:`wheelbase.gym.NavigateVectorEnv` (one engine step and one lidar call per step of all
32), adapted to Stable-Baselines3's ``VecEnv`` with Gymnasium's ``same_step`` autoreset.
Writes ``gym_ppo.png`` (the success rate of the training episodes against the time steps) and
prints JSON: the success rate of the trained policy on 500 new episodes (deterministic
actions), the steps it took to reach 90 % and the training wall time. The figure in the
documentation, ``docs/images/gym_ppo.png``, is this script's output. Not run by the
documentation build or CI (minutes, and the ``rl`` extra).
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
import torch
from stable_baselines3 import PPO
from stable_baselines3.common.vec_env import VecEnv

from wheelbase.gym import NavigateVectorEnv


class NavigateSB3(VecEnv):
    """Stable-Baselines3's VecEnv over the native vector env (same-step autoreset).

    Parameters
    ----------
    envs : NavigateVectorEnv
        Built with ``autoreset_mode="same_step"``.
    seed : int
        Seed of the first reset.
    """

    def __init__(self, envs: NavigateVectorEnv, seed: int = 0) -> None:
        super().__init__(envs.num_envs, envs.single_observation_space, envs.single_action_space)
        self.envs, self.first_seed = envs, seed
        self.finished: list[tuple[int, bool]] = []  # (time step, success) of each episode
        self.steps = 0
        self.returns = np.zeros(envs.num_envs)
        self.lengths = np.zeros(envs.num_envs, dtype=np.int64)

    def reset(self) -> np.ndarray:
        observations, _ = self.envs.reset(seed=self.first_seed)
        self.returns[:] = 0.0
        self.lengths[:] = 0
        return observations

    def step_async(self, actions: np.ndarray) -> None:
        self.actions = np.clip(actions, -1.0, 1.0)

    def step_wait(self):
        observations, rewards, terminated, truncated, infos = self.envs.step(self.actions)
        self.steps += self.num_envs
        self.returns += rewards
        self.lengths += 1
        done = terminated | truncated
        info_list: list[dict] = [{} for _ in range(self.num_envs)]
        for i in np.flatnonzero(done):
            success = bool(infos["final_info"][i]["is_success"])
            info_list[i] = {
                "terminal_observation": infos["final_obs"][i],
                "TimeLimit.truncated": bool(truncated[i] and not terminated[i]),
                "is_success": success,
                "episode": {"r": float(self.returns[i]), "l": int(self.lengths[i])},
            }
            self.finished.append((self.steps, success))
            self.returns[i], self.lengths[i] = 0.0, 0
        return observations, rewards.astype(np.float32), done, info_list

    def close(self) -> None:
        self.envs.close()

    def get_attr(self, attr_name, indices=None):
        return [getattr(self.envs, attr_name)] * self.num_envs

    def set_attr(self, attr_name, value, indices=None) -> None:
        setattr(self.envs, attr_name, value)

    def env_method(self, method_name, *method_args, indices=None, **method_kwargs):
        return [getattr(self.envs, method_name)(*method_args, **method_kwargs)]

    def env_is_wrapped(self, wrapper_class, indices=None):
        return [False] * self.num_envs


def evaluate(model: PPO, episodes: int, seed: int) -> float:
    """Success rate of the deterministic policy on ``episodes`` new episodes."""
    envs = NavigateVectorEnv(episodes, autoreset_mode="disabled")
    observations, _ = envs.reset(seed=seed)
    running = np.ones(episodes, dtype=bool)
    success = np.zeros(episodes, dtype=bool)
    while running.any():
        actions, _ = model.predict(observations, deterministic=True)
        observations, _, terminated, truncated, infos = envs.step(np.clip(actions, -1.0, 1.0))
        success |= running & infos["is_success"]
        running &= ~(terminated | truncated)
    return float(success.mean())


def learning_curve(finished: list[tuple[int, bool]], window: int = 100):
    steps = np.array([s for s, _ in finished])
    ok = np.array([v for _, v in finished], dtype=float)
    window = max(1, min(window, len(ok)))
    kernel = np.ones(window) / window
    rate = np.convolve(ok, kernel, mode="valid")
    return steps[window - 1 :], rate


def main(out_dir: Path, timesteps: int) -> None:
    out_dir.mkdir(parents=True, exist_ok=True)
    torch.set_num_threads(1)
    env = NavigateSB3(NavigateVectorEnv(32, autoreset_mode="same_step"), seed=0)
    model = PPO("MlpPolicy", env, n_steps=128, batch_size=256, n_epochs=10, gamma=0.99,
                learning_rate=3e-4, seed=0, device="cpu", verbose=0)  # fmt: skip
    started = time.perf_counter()
    model.learn(total_timesteps=timesteps)
    wall = time.perf_counter() - started
    rate = evaluate(model, 500, seed=12345)
    steps, curve = learning_curve(env.finished)
    fig, ax = plt.subplots(figsize=(7, 4))
    ax.plot(steps, 100 * curve, color="tab:blue")
    ax.axhline(90, color="0.5", ls="--", lw=0.8)
    ax.set_xlabel("environment steps")
    ax.set_ylabel("success of the last 100 episodes [%]")
    ax.set_ylim(0, 100)
    ax.grid(alpha=0.3)
    ax.set_title(f"PPO on wheelbase/Navigate-v0, empty room: {100 * rate:.1f} % of 500 new "
                 f"episodes\nreach their goal after {timesteps:,} steps ({wall:.0f} s on 2 cores)",
                 fontsize=10)  # fmt: skip
    fig.tight_layout()
    fig.savefig(out_dir / "gym_ppo.png", dpi=110)
    print(json.dumps({
        "timesteps": timesteps,
        "training_wall_time_s": wall,
        "training_episodes": len(env.finished),
        "success_rate_500_new_episodes": rate,
        "last_100_training_episodes_success_rate": float(curve[-1]) if len(curve) else None,
        "steps_to_90_percent": int(steps[np.argmax(curve >= 0.9)]) if np.any(curve >= 0.9)
        else None,
    }, indent=2))  # fmt: skip


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description="PPO on wheelbase/Navigate-v0")
    parser.add_argument("out", nargs="?", type=Path, default=Path(__file__).parent / "out")
    parser.add_argument("--timesteps", type=int, default=150_000)
    args = parser.parse_args()
    main(args.out, args.timesteps)
