"""The world beyond the map: static obstacles and moving agents that only the sensors see.

:class:`World` (parameters) and :class:`WorldState` (B worlds of agents, advanced by the
pure :meth:`World.step`) hold the truth a scenario's ``world`` section describes: static
obstacles that are not on the map (:class:`Obstacles`), moving agents in groups
(:class:`AgentGroup`) with behaviours (straight, wander, waypoints, the social force model,
ORCA), the exact lidar ranges that see all of it (:meth:`World.cast`) and exact contacts and
distances for the metrics. :func:`world_from_spec` reads the ``world`` section from plain
data. Controllers, planners, estimators and perception never import this package.
"""

from typing import TYPE_CHECKING

from wheelbase._lazy import attach

if TYPE_CHECKING:  # the names, for type checkers and IDEs; imported on first use
    from wheelbase.world.agents import BEHAVIOURS, ORCA, AgentGroup, SocialForce
    from wheelbase.world.obstacles import Obstacles, box_polygon
    from wheelbase.world.orca import orca_half_plane, solve_velocity_lp
    from wheelbase.world.social_force import social_force_acceleration
    from wheelbase.world.spec import agent_groups_from_spec, obstacles_from_spec, world_from_spec
    from wheelbase.world.state import Distances, RobotBodies, WorldState
    from wheelbase.world.world import World

_EXPORTS = {
    "BEHAVIOURS": "wheelbase.world.agents",
    "ORCA": "wheelbase.world.agents",
    "AgentGroup": "wheelbase.world.agents",
    "SocialForce": "wheelbase.world.agents",
    "Obstacles": "wheelbase.world.obstacles",
    "box_polygon": "wheelbase.world.obstacles",
    "orca_half_plane": "wheelbase.world.orca",
    "solve_velocity_lp": "wheelbase.world.orca",
    "social_force_acceleration": "wheelbase.world.social_force",
    "agent_groups_from_spec": "wheelbase.world.spec",
    "obstacles_from_spec": "wheelbase.world.spec",
    "world_from_spec": "wheelbase.world.spec",
    "Distances": "wheelbase.world.state",
    "RobotBodies": "wheelbase.world.state",
    "WorldState": "wheelbase.world.state",
    "World": "wheelbase.world.world",
}
__getattr__, __dir__ = attach(__name__, _EXPORTS)

__all__ = [
    "BEHAVIOURS",
    "ORCA",
    "AgentGroup",
    "Distances",
    "Obstacles",
    "RobotBodies",
    "SocialForce",
    "World",
    "WorldState",
    "agent_groups_from_spec",
    "box_polygon",
    "obstacles_from_spec",
    "orca_half_plane",
    "social_force_acceleration",
    "solve_velocity_lp",
    "world_from_spec",
]
