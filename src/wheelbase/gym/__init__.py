"""Gymnasium environments on the wheelbase engine: ``wheelbase/Navigate-v0``, single and
vectorised.

Importing this package registers ``wheelbase/Navigate-v0`` (entry point
:class:`NavigateEnv`; vector entry point :class:`NavigateVectorEnv`)::

    import gymnasium
    import wheelbase.gym

    env = gymnasium.make("wheelbase/Navigate-v0", robot={"model": "bicycle"}, map="maze")
    envs = gymnasium.make_vec("wheelbase/Navigate-v0", num_envs=256,
                              vectorization_mode="vector_entry_point")

Episodes end after ``max_episode_steps`` (300 unless ``gymnasium.make(...,
max_episode_steps=N)`` or ``make_vec(..., max_episode_steps=N)`` says otherwise). The task
(observation, action, reward, termination) is documented in
:mod:`wheelbase.gym.task`. Needs the optional extra ``wheelbase[gym]`` (Gymnasium).
"""

from wheelbase.errors import DependencyError

try:
    import gymnasium
except ImportError as _error:
    raise DependencyError(
        f"wheelbase.gym needs Gymnasium: pip install 'wheelbase[gym]' ({_error})"
    ) from None

from wheelbase.gym.env import NavigateEnv
from wheelbase.gym.task import EPISODE_STEPS, NavigateTask, RewardWeights
from wheelbase.gym.vector import NavigateVectorEnv

__all__ = ["ENV_ID", "NavigateEnv", "NavigateTask", "NavigateVectorEnv", "RewardWeights"]

ENV_ID = "wheelbase/Navigate-v0"
"""The id under which :class:`NavigateEnv` is registered with Gymnasium."""

if ENV_ID not in gymnasium.registry:
    gymnasium.register(
        id=ENV_ID,
        entry_point="wheelbase.gym.env:NavigateEnv",
        vector_entry_point="wheelbase.gym.vector:NavigateVectorEnv",
        max_episode_steps=EPISODE_STEPS,  # make's TimeLimit; make(..., max_episode_steps=N)
    )
