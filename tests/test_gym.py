"""wheelbase.gym: the Navigate-v0 task, its Gymnasium env and the native vector env."""

import importlib
import math
import sys
import warnings

import numpy as np
import pytest

gymnasium = pytest.importorskip("gymnasium")

from gymnasium.utils.env_checker import check_env  # noqa: E402

from wheelbase.errors import ConfigError, DependencyError, InputError, MapError  # noqa: E402
from wheelbase.geometry import relative_pose  # noqa: E402
from wheelbase.gym import NavigateEnv, NavigateVectorEnv, RewardWeights  # noqa: E402
from wheelbase.planning import OccupancyGrid  # noqa: E402
from wheelbase.sensors import Lidar  # noqa: E402

BEAMS = 60


@pytest.mark.parametrize("robot", [None, {"model": "bicycle"}, {"model": "unicycle"}])
def test_check_env_passes_without_a_warning(robot):
    env = gymnasium.make("wheelbase/Navigate-v0", robot=robot)
    assert isinstance(env.unwrapped, NavigateEnv)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        check_env(env.unwrapped)
    env.close()


def _steps_to_truncation(env, limit: int) -> int:
    """Steps until the episode ends while the robot turns on the spot (never arriving)."""
    env.reset(seed=3)
    for k in range(1, limit + 1):
        _, _, terminated, truncated, _ = env.step(np.array([0.0, 1.0], np.float32))
        assert not terminated
        if truncated:
            return k
    return limit + 1


@pytest.mark.parametrize(("limit", "expected"), [(None, 300), (1000, 1000), (7, 7)])
def test_make_honours_max_episode_steps(limit, expected):
    # gymnasium.make(..., max_episode_steps=1000) was cut at the task's own 300 steps
    kwargs = {} if limit is None else {"max_episode_steps": limit}
    env = gymnasium.make("wheelbase/Navigate-v0", **kwargs)
    assert env.spec.max_episode_steps == expected
    assert _steps_to_truncation(env, 1100) == expected
    envs = gymnasium.make_vec("wheelbase/Navigate-v0", num_envs=2,
                              vectorization_mode="vector_entry_point", **kwargs)  # fmt: skip
    assert envs.unwrapped.task.max_episode_steps == expected
    # Built directly, the environment cuts episodes only when asked to (Gymnasium's way: the
    # TimeLimit wrapper of gymnasium.make does it).
    assert _steps_to_truncation(NavigateEnv(max_episode_steps=5), 10) == 5
    assert NavigateEnv().task.max_episode_steps is None


def test_observation_is_lidar_goal_and_twist():
    env = NavigateEnv()
    start, goal = np.array([3.0, 4.0, 0.5]), np.array([7.0, 6.0, 0.0])
    obs, info = env.reset(seed=1, options={"start": start, "goal": goal})
    assert obs.shape == (BEAMS + 5,) and obs.dtype == np.float32
    scan = Lidar(beams=BEAMS, max_range=5.0).scan(env.task.grid, start, noise=False)
    np.testing.assert_allclose(obs[:BEAMS], scan / 5.0, rtol=0, atol=1e-7)
    local = relative_pose(start, goal)  # the goal in the body frame
    distance = math.hypot(local[0], local[1])
    assert info["distance"] == pytest.approx(distance, abs=1e-12)
    assert obs[BEAMS] == pytest.approx(distance / (10.0 * math.sqrt(2)), abs=1e-7)
    assert obs[BEAMS + 1 : BEAMS + 3] == pytest.approx(np.array(local[:2]) / distance, abs=1e-7)
    assert obs[BEAMS + 3 :].tolist() == [0.0, 0.0]  # at rest
    # One step at (v, ω) = (0.5, 0.4)·(max_speed, max_yaw_rate): the twist is observed.
    obs, *_ = env.step(np.array([0.5, 0.4], np.float32))
    assert obs[BEAMS + 3 :] == pytest.approx([0.5, 0.4], abs=1e-6)


def test_rewards_sum_to_the_progress_less_time_and_terminal_terms():
    weights = RewardWeights(progress=2.0, time=0.05, arrival=7.0, collision=3.0)
    env = NavigateEnv(rewards=weights)
    start, goal = np.array([2.0, 5.0, 0.0]), np.array([4.0, 5.0, 0.0])
    _, info = env.reset(seed=0, options={"start": start, "goal": goal})
    d0, total, steps = info["distance"], 0.0, 0
    while True:
        _, reward, terminated, truncated, info = env.step(np.array([1.0, 0.0], np.float32))
        total, steps = total + reward, steps + 1
        if terminated or truncated:
            break
    assert terminated and info["is_success"] and not info["collision"]
    assert info["distance"] <= 0.3  # within the goal tolerance
    assert steps == math.ceil((2.0 - 0.3) / 0.1)  # 1 m/s, dt = 0.1 s
    expected = weights.progress * (d0 - info["distance"]) - weights.time * steps + weights.arrival
    assert total == pytest.approx(expected, abs=1e-12)


def test_collision_terminates_with_the_penalty_and_time_limit_truncates():
    env = NavigateEnv(max_episode_steps=4)
    # The wall begins at x = 9.95 m; the 0.48 m square robot's front is at 9.89 m.
    env.reset(seed=0, options={"start": [9.65, 5.0, 0.0], "goal": [5.0, 5.0, 0.0]})
    _, reward, terminated, truncated, info = env.step(np.array([1.0, 0.0], np.float32))
    assert terminated and not truncated and info["collision"] and not info["is_success"]
    assert reward == pytest.approx(-0.1 - 0.01 - 10.0, abs=1e-9)  # moved 0.1 m away
    env.reset(seed=0, options={"start": [5.0, 5.0, 0.0], "goal": [8.0, 8.0, 0.0]})
    flags = [env.step(np.zeros(2, np.float32))[2:4] for _ in range(4)]
    assert flags == [(False, False)] * 3 + [(False, True)]


def test_reset_seed_reproduces_starts_and_goals():
    env = NavigateEnv()
    first = env.reset(seed=7)[1]["goal"]
    again = env.reset(seed=7)[1]["goal"]
    other = env.reset(seed=8)[1]["goal"]
    np.testing.assert_array_equal(first, again)
    assert not np.array_equal(first, other)
    pose = env.task.state.pose[0]
    assert math.hypot(*(pose[:2] - other[:2])) >= 1.0  # min_goal_distance
    assert not env.task.grid.in_collision(env.task.footprint, pose)


def test_vector_env_robot_equals_the_single_env():
    n, steps = 6, 25
    rng = np.random.default_rng(3)
    envs = NavigateVectorEnv(n, autoreset_mode="disabled", robot={"model": "rear_bicycle"})
    start, goal = envs.task.sample(n, rng)
    obs, _ = envs.reset(seed=0, options={"start": start, "goal": goal})
    actions = rng.uniform(-1, 1, (steps, n, 2)).astype(np.float32)
    batch = [obs]
    rewards, flags = [], []
    for k in range(steps):
        obs, reward, terminated, truncated, _ = envs.step(actions[k])
        batch.append(obs)
        rewards.append(reward)
        flags.append(terminated | truncated)
    for i in range(n):
        env = NavigateEnv(robot={"model": "rear_bicycle"})
        obs, _ = env.reset(options={"start": start[i], "goal": goal[i]})
        np.testing.assert_array_equal(obs, batch[0][i])
        for k in range(steps):
            obs, reward, terminated, truncated, _ = env.step(actions[k, i])
            np.testing.assert_allclose(obs, batch[k + 1][i], rtol=0, atol=1e-6)
            assert reward == pytest.approx(rewards[k][i], abs=1e-9)
            assert (terminated or truncated) == flags[k][i]
            if terminated or truncated:
                break


def test_next_step_autoreset():
    envs = NavigateVectorEnv(2, max_episode_steps=50)
    start = np.array([[9.65, 5.0, 0.0], [3.0, 3.0, 0.0]])
    goal = np.array([[5.0, 5.0, 0.0], [7.0, 7.0, 0.0]])
    envs.reset(seed=0, options={"start": start, "goal": goal})
    forward = np.array([[1.0, 0.0], [0.0, 0.0]], np.float32)
    _, _, terminated, truncated, _ = envs.step(forward)
    assert terminated.tolist() == [True, False] and not truncated.any()
    assert envs.task.state.pose[0, 0] == pytest.approx(9.75)  # the terminal pose is kept
    # Next call: robot 0's action is ignored, it starts anew with reward 0 and no flags.
    _obs, reward, terminated, truncated, infos = envs.step(forward)
    assert reward[0] == 0.0 and not terminated[0] and not truncated[0]
    assert envs.task.elapsed.tolist() == [0, 2]
    assert not np.allclose(envs.task.goal[0], goal[0])
    np.testing.assert_array_equal(envs.task.goal[1], goal[1])
    assert infos["distance"][0] == pytest.approx(
        np.hypot(*(envs.task.goal[0, :2] - envs.task.state.pose[0, :2]))
    )


def test_same_step_autoreset_keeps_the_final_observation():
    envs = NavigateVectorEnv(2, autoreset_mode="same_step")
    start = np.array([[9.65, 5.0, 0.0], [3.0, 3.0, 0.0]])
    goal = np.array([[5.0, 5.0, 0.0], [7.0, 7.0, 0.0]])
    envs.reset(seed=0, options={"start": start, "goal": goal})
    forward = np.array([[1.0, 0.0], [0.0, 0.0]], np.float32)
    obs, _, terminated, _, infos = envs.step(forward)
    assert terminated.tolist() == [True, False]
    assert infos["_final_obs"].tolist() == [True, False]
    final = infos["final_obs"][0]
    assert final[BEAMS + 3] == pytest.approx(1.0)  # it was moving at full speed
    assert obs[0, BEAMS + 3] == 0.0 and envs.task.elapsed[0] == 0  # a new episode, at rest
    assert infos["final_info"][0]["is_success"] is False


def test_make_vec_uses_the_native_vector_env_and_spaces_agree():
    envs = gymnasium.make_vec(
        "wheelbase/Navigate-v0", num_envs=4, vectorization_mode="vector_entry_point"
    )
    assert isinstance(envs.unwrapped, NavigateVectorEnv)
    obs, _ = envs.reset(seed=2)
    assert obs in envs.observation_space and obs.shape == (4, BEAMS + 5)
    for _ in range(30):
        obs, reward, terminated, truncated, _infos = envs.step(envs.action_space.sample())
        assert obs in envs.observation_space
        assert reward.shape == terminated.shape == truncated.shape == (4,)
    assert envs.metadata["autoreset_mode"] == gymnasium.vector.AutoresetMode.NEXT_STEP


def test_render_rgb_array():
    env = NavigateEnv(render_mode="rgb_array")
    env.reset(seed=0)
    frame = env.render()
    assert frame.shape == (500, 500, 3) and frame.dtype == np.uint8
    assert len(np.unique(frame.reshape(-1, 3), axis=0)) > 3  # map, robot, rays, goal
    vector = NavigateVectorEnv(3, render_mode="rgb_array")
    vector.reset(seed=0)
    assert vector.render().shape == (500, 500, 3)


def test_render_human_redraws_a_window_per_step(monkeypatch):
    # Headless (Agg): the window is a figure; each reset and step redraws every robot's
    # footprint, and close() closes it. The pause is skipped to keep the test quick.
    import matplotlib.pyplot as plt

    monkeypatch.setattr(plt, "pause", lambda interval: None)
    for env, robots in ((NavigateEnv(render_mode="human"), 1),
                        (NavigateVectorEnv(3, render_mode="human"), 3)):  # fmt: skip
        env.reset(seed=0)
        figure = env._figure
        assert figure is not None and figure.number in plt.get_fignums()
        single = isinstance(env, NavigateEnv)
        env.step(np.zeros(2) if single else np.zeros((robots, 2)))
        (ax,) = figure.axes  # redrawn, not stacked
        footprints = [line for line in ax.lines if line.get_color() == "tab:blue"]
        poses = env.task.state.pose[:, :2]
        assert len(footprints) == robots
        for line, pose in zip(footprints, poses, strict=True):  # drawn where the robots are
            assert np.allclose(np.mean(line.get_xydata()[:-1], axis=0), pose, atol=0.5)
        assert env.render() is None
        env.close()
        assert figure.number not in plt.get_fignums()
    assert "human" in NavigateVectorEnv(1).metadata["render_modes"]


def test_bad_input_is_a_clear_error():
    env = NavigateEnv()
    with pytest.raises(gymnasium.error.ResetNeeded):
        env.step(np.zeros(2, np.float32))
    env.reset(seed=0)
    with pytest.raises(InputError, match="finite"):
        env.step(np.array([np.nan, 0.0]))
    with pytest.raises(InputError, match="ClipAction"):
        env.step(np.array([1.5, 0.0]))
    with pytest.raises(InputError, match=r"shape \(2,\)"):
        env.step(np.zeros(3))
    with pytest.raises(InputError, match="collision"):
        env.reset(options={"start": [0.0, 0.0, 0.0]})
    walls = OccupancyGrid.from_array(np.ones((20, 20), bool), 0.05)
    with pytest.raises(MapError, match="no free cell"):
        NavigateEnv(map=walls)
    with pytest.raises(ConfigError, match=r"robot\.model"):
        NavigateEnv(robot={"model": "tank"})
    with pytest.raises(ConfigError, match="render_mode"):
        NavigateEnv(render_mode="ascii")
    with pytest.raises(ConfigError, match="autoreset_mode"):
        NavigateVectorEnv(2, autoreset_mode="sometimes")
    envs = NavigateVectorEnv(2)
    with pytest.raises(gymnasium.error.ResetNeeded):
        envs.step(np.zeros((2, 2)))
    envs.reset(seed=0)
    with pytest.raises(InputError, match=r"shape \(2, 2\)"):
        envs.step(np.zeros(2))
    with pytest.raises(InputError, match="reset_mask"):
        envs.reset(options={"reset_mask": np.ones(3, bool)})


def test_missing_gymnasium_names_the_extra(monkeypatch):
    for name in [name for name in sys.modules if name.startswith("wheelbase.gym")]:
        monkeypatch.delitem(sys.modules, name)
    monkeypatch.setitem(sys.modules, "gymnasium", None)
    with pytest.raises(DependencyError, match=r"wheelbase\[gym\]"):
        importlib.import_module("wheelbase.gym")


def test_benchmark_quick_prints_the_figures():
    import json
    import subprocess
    from pathlib import Path

    script = Path(__file__).resolve().parents[1] / "benchmarks" / "gym.py"
    done = subprocess.run([sys.executable, str(script), "--quick"], capture_output=True,
                          text=True, timeout=300, check=False)  # fmt: skip
    assert done.returncode == 0, done.stderr
    report = json.loads(done.stdout)
    for key in ("vector_env_steps_per_s", "sync_vector_env_steps_per_s", "ratio"):
        assert report[key] > 0
    assert report["config"]["beams"] == BEAMS
    parts = report["vector_step_breakdown_us"]
    assert parts["total"] == pytest.approx(sum(v for k, v in parts.items() if k != "total"))


def test_a_world_of_walkers_is_seen_and_touched_in_the_environment():
    from wheelbase.gym import NavigateVectorEnv

    world = {
        "obstacles": [{"box": [5.0, 5.0, 1.0, 1.0, 0.0]}],
        "agents": [{"count": 6, "radius": 0.3, "behaviour": "wander", "region": [2, 2, 8, 8]}],
    }
    plain = NavigateVectorEnv(num_envs=3)
    crowded = NavigateVectorEnv(num_envs=3, world=world)
    options = {"start": np.tile([1.0, 5.0, 0.0], (3, 1)), "goal": np.tile([9.0, 5.0, 0.0], (3, 1))}
    seen_plain, _ = plain.reset(seed=0, options=options)
    seen, _ = crowded.reset(seed=0, options=options)
    beams = plain.task.lidar.beams
    # facing the box at 3.5 m (and walkers in the way): every reading is no longer than the map's
    assert np.all(seen[:, :beams] <= seen_plain[:, :beams] + 1e-9)
    assert seen[0, beams // 2] * 5.0 <= 3.5 + 1e-6  # the beam straight ahead stops at the box
    # the walkers move with the steps: the world state advances, the scans change
    before = crowded.task.world_state.position.copy()
    for _ in range(5):
        crowded.step(np.zeros((3, 2), dtype=np.float32))
    assert not np.allclose(crowded.task.world_state.position, before)
    # driving straight into the box ends the episode as a collision
    terminated = np.zeros(3, bool)
    for _ in range(60):
        _, _, term, _, _ = crowded.step(np.tile([1.0, 0.0], (3, 1)).astype(np.float32))
        terminated |= term
        if terminated.all():
            break
    assert terminated.all()
