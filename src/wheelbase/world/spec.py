"""A scenario's ``world`` section, from plain data (what YAML gives) to a :class:`World`.

The section::

    world:
      obstacles:                              # static, not on the map
        - {box: [6.0, 3.0, 0.6, 0.6, 30]}     # x, y, length, width [m], yaw [deg] (default 0)
        - {disc: [9.0, 2.5, 0.3]}             # x, y, radius [m]
        - {polygon: [[0, 0], [1, 0], [0, 1]]} # vertices [m]
      agents:                                 # moving obstacles, group by group
        - count: 20
          radius: 0.3                         # [m]
          speed: 0.5                          # preferred speed [m/s]
          behaviour: straight                 # straight | wander | waypoints | social_force | orca
          region: [3, 3, 17, 17]              # x0, y0, x1, y1 [m]; default the map
          reacts_to_robot: false
          waypoints: [[x, y], ...]            # for behaviour waypoints (a loop)
      social_force: {relaxation_time: 0.5}    # optional: SocialForce's fields
      orca: {time_horizon: 5.0}               # optional: ORCA's fields

Every error is a :class:`~wheelbase.errors.ScenarioError` whose message starts with the key's
path (``world.agents[0].speed must be > 0 m/s (got -1)``,
``world.obstacles[2].box: ...``). The agents' and obstacles' overlap with the robots' starts
and goals is checked when the world starts (:meth:`World.start`), which knows them.
"""

from __future__ import annotations

import math
from dataclasses import fields
from typing import Any

import numpy as np

from wheelbase.errors import ConfigError, MapError, ScenarioError
from wheelbase.world.agents import ORCA, AgentGroup, SocialForce
from wheelbase.world.obstacles import MAX_OBSTACLES, Obstacles, box_polygon
from wheelbase.world.world import World

__all__ = ["agent_groups_from_spec", "obstacles_from_spec", "world_from_spec"]

WORLD_KEYS = ("obstacles", "agents", "social_force", "orca")
"""Keys of the ``world`` section."""
OBSTACLE_KINDS = ("box", "disc", "polygon")
"""Kinds of static obstacle; each entry has exactly one of them."""
AGENT_KEYS = tuple(f.name for f in fields(AgentGroup))
"""Keys of an ``agents`` entry (the fields of :class:`AgentGroup`)."""


def _mapping(value: Any, path: str) -> dict:
    if not isinstance(value, dict):
        raise ScenarioError(f"{path} must be a mapping of keys to values (got {value!r})"[:300])
    for key in value:
        if not isinstance(key, str):
            raise ScenarioError(f"{path}: keys must be strings (got {key!r})"[:300])
    return value


def _unknown(value: dict, allowed: tuple[str, ...], path: str) -> None:
    extra = sorted(set(value) - set(allowed))
    if extra:
        raise ScenarioError(f"{path}: unknown key {extra[0]!r}; allowed: {', '.join(allowed)}")


def _list(value: Any, path: str, limit: int) -> list:
    if not isinstance(value, (list, tuple)):
        raise ScenarioError(f"{path} must be a list (got {value!r})"[:300])
    if len(value) > limit:
        raise ScenarioError(f"{path}: {len(value)} entries, more than {limit}")
    return list(value)


def _real(value: Any, path: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise ScenarioError(f"{path} must be a number (got {value!r})"[:300])
    number = float(value) if abs(value) < 1e308 or isinstance(value, float) else math.inf
    if not math.isfinite(number):
        raise ScenarioError(f"{path} must be finite (got {value!r})"[:300])
    return number


def _reals(value: Any, path: str, sizes: tuple[int, ...], what: str) -> list[float]:
    items = _list(value, path, max(sizes))
    if len(items) not in sizes:
        raise ScenarioError(f"{path} must be {what} (got {value!r})"[:300])
    return [_real(item, f"{path}[{i}]") for i, item in enumerate(items)]


def _points(value: Any, path: str, limit: int = 100_000) -> np.ndarray:
    items = _list(value, path, limit)
    return np.array([_reals(p, f"{path}[{i}]", (2,), "[x, y] [m]") for i, p in enumerate(items)],
                    dtype=float).reshape(-1, 2)  # fmt: skip


def obstacles_from_spec(spec: Any, path: str = "world.obstacles") -> Obstacles:
    """The static obstacles of a ``world.obstacles`` list (module docstring).

    Parameters
    ----------
    spec : list or None
        Entries ``{box: [x, y, length, width, yaw_deg]}``, ``{disc: [x, y, radius]}`` or
        ``{polygon: [[x, y], ...]}``.
    path : str
        The key path, for messages.

    Returns
    -------
    Obstacles
        The polygons (boxes as 4-gons) in the order given, then the discs, each named by its
        entry (``world.obstacles[2] (box)``) for the messages of :class:`World`.

    Raises
    ------
    ScenarioError
        The message names the entry (``world.obstacles[2].box: ...``).

    Examples
    --------
    >>> obs = obstacles_from_spec([{"box": [6, 3, 0.6, 0.6, 30]}, {"disc": [9, 2.5, 0.3]}])
    >>> len(obs.polygons), obs.discs.tolist()
    (1, [[9.0, 2.5, 0.3]])
    """
    if spec is None:
        return Obstacles()
    polygons, discs, where, disc_where = [], [], [], []
    for i, entry in enumerate(_list(spec, path, MAX_OBSTACLES)):
        here = f"{path}[{i}]"
        entry = _mapping(entry, here)
        present = [k for k in OBSTACLE_KINDS if k in entry]
        _unknown(entry, OBSTACLE_KINDS, here)
        if len(present) != 1:
            raise ScenarioError(f"{here} must have exactly one of {', '.join(OBSTACLE_KINDS)} "
                                f"(got {sorted(entry) or 'none'})")  # fmt: skip
        kind = present[0]
        key = f"{here}.{kind}"
        if kind == "box":
            numbers = _reals(entry[kind], key, (4, 5),
                             "[x, y, length, width] [m] and an optional yaw [deg]")  # fmt: skip
            x, y, length, width = numbers[:4]
            if length <= 0 or width <= 0:
                raise ScenarioError(f"{key}: length and width must be > 0 m (got {length:g}, "
                                    f"{width:g})")  # fmt: skip
            yaw = math.radians(numbers[4]) if len(numbers) == 5 else 0.0
            polygons.append(box_polygon(x, y, length, width, yaw))
            where.append(f"{here} (box)")
        elif kind == "disc":
            x, y, r = _reals(entry[kind], key, (3,), "[x, y, radius] [m]")
            if r <= 0:
                raise ScenarioError(f"{key}: radius must be > 0 m (got {r:g})")
            discs.append((x, y, r))
            disc_where.append(f"{here} (disc)")
        else:
            polygons.append(_points(entry[kind], key))
            where.append(f"{here} (polygon)")
    try:
        return Obstacles(tuple(polygons), np.array(discs, float).reshape(-1, 3),
                         (*where, *disc_where))  # fmt: skip
    except MapError as error:
        text = str(error)
        if text.startswith("polygon "):
            index = int(text.split()[1])
            raise ScenarioError(f"{where[index]}: {text.split(' ', 2)[2]}") from None
        raise ScenarioError(f"{path}: {text}") from None


def agent_groups_from_spec(spec: Any, path: str = "world.agents") -> tuple[AgentGroup, ...]:
    """The agent groups of a ``world.agents`` list (module docstring).

    Parameters
    ----------
    spec : list or None
        Mappings of :data:`AGENT_KEYS`.
    path : str
        The key path, for messages.

    Returns
    -------
    tuple of AgentGroup

    Raises
    ------
    ScenarioError
        The message starts with the key (``world.agents[0].speed must be > 0 m/s``).

    Examples
    --------
    >>> agent_groups_from_spec([{"count": 3, "behaviour": "wander"}])[0].count
    3
    """
    if spec is None:
        return ()
    groups = []
    for i, entry in enumerate(_list(spec, path, 10_000)):
        here = f"{path}[{i}]"
        entry = _mapping(entry, here)
        _unknown(entry, AGENT_KEYS, here)
        options = dict(entry)
        for key in ("radius", "speed"):
            if key in options:
                options[key] = _real(options[key], f"{here}.{key}")
        if "region" in options and options["region"] is not None:
            options["region"] = tuple(_reals(options["region"], f"{here}.region", (4,),
                                             "[x0, y0, x1, y1] [m]"))  # fmt: skip
        if "waypoints" in options and options["waypoints"] is not None:
            options["waypoints"] = _points(options["waypoints"], f"{here}.waypoints")
        try:
            groups.append(AgentGroup(**options))
        except ConfigError as error:
            raise ScenarioError(f"{here}.{error}") from None
    return tuple(groups)


def _parameters(cls: type, spec: Any, path: str) -> Any:
    if spec is None:
        return cls()
    spec = _mapping(spec, path)
    names = tuple(f.name for f in fields(cls))
    _unknown(spec, names, path)
    options = {}
    for key, value in spec.items():
        if key == "max_neighbours":
            options[key] = value
        else:
            options[key] = _real(value, f"{path}.{key}")
    try:
        return cls(**options)
    except ConfigError as error:
        raise ScenarioError(f"{path}.{error}") from None


def world_from_spec(spec: Any, grid: Any) -> World:
    """The :class:`World` of a scenario's ``world`` section on its map.

    Parameters
    ----------
    spec : dict or None
        The section (module docstring); None or empty: a world with nothing beyond the map.
    grid : OccupancyGrid or PolygonWorld
        The scenario's map.

    Returns
    -------
    World

    Raises
    ------
    ScenarioError
        The message starts with the key's path (``world.agents[0].speed ...``).

    Examples
    --------
    >>> from wheelbase.planning import OccupancyGrid
    >>> room = OccupancyGrid(np.zeros((100, 100), bool), 0.1)
    >>> world = world_from_spec({"agents": [{"count": 4, "behaviour": "wander"}]}, room)
    >>> world.agent_count
    4
    """
    if spec is None:
        spec = {}
    spec = _mapping(spec, "world")
    _unknown(spec, WORLD_KEYS, "world")
    return World(
        grid,
        obstacles_from_spec(spec.get("obstacles"), "world.obstacles"),
        agent_groups_from_spec(spec.get("agents"), "world.agents"),
        _parameters(SocialForce, spec.get("social_force"), "world.social_force"),
        _parameters(ORCA, spec.get("orca"), "world.orca"),
    )
