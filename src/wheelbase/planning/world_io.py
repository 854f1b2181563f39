"""World files: polygon worlds from YAML or GeoJSON (:func:`~wheelbase.planning.load_world` loads
any kind of world).

**YAML** (schema: ``wheelbase/data/schemas/world.schema.json``; lengths in metres)::

    bounds: [0.0, 60.0, 0.0, 60.0]   # x_min, x_max, y_min, y_max: the map rectangle
    resolution: 0.1                  # raster cell for the distance field and plots (optional)
    grid: parking_lot                # optional: a bundled map or a ROS/Moving AI/image map file
    polygons:                        # optional: each an exterior ring, or exterior + holes
      - [[19.9, 0.0], [20.1, 0.0], [20.1, 39.0], [19.9, 39.0]]
      - exterior: [[30, 30], [36, 30], [36, 36], [30, 36]]
        holes: [[[32, 32], [34, 32], [34, 34], [32, 34]]]
    discs:                           # optional: [x, y, radius]
      - [10.0, 40.0, 1.5]

**GeoJSON** (RFC 7946 syntax, but planar coordinates in metres, not longitude/latitude): a
``FeatureCollection`` (or one ``Feature``/geometry) of ``Polygon`` and ``MultiPolygon``
geometries (first ring the exterior, the others holes) and ``Point`` features with a
``radius`` property [m] (discs). The standard ``bbox`` member ``[x_min, y_min, x_max, y_max]``
gives the bounds; the foreign members ``resolution`` and ``grid`` mean what they mean in YAML.

A ``grid`` path in a file is relative to that file.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path as FilePath
from typing import Any

import yaml
from pydantic import BaseModel, ConfigDict, Field, ValidationError

from wheelbase._validate import read_text
from wheelbase.errors import MapError
from wheelbase.limits import MAX_MAP_CELLS
from wheelbase.planning.map_io import read_ros_yaml
from wheelbase.planning.occupancy import OccupancyGrid
from wheelbase.planning.world import PolygonWorld

__all__ = [
    "WorldFile",
    "is_world_mapping",
    "read_world_file",
    "world_from_mapping",
    "world_schema",
]

_WORLD_KEYS = frozenset({"bounds", "resolution", "grid", "polygons", "discs"})
Point = tuple[float, float]
Ring = list[Point]


class PolygonSpec(BaseModel):
    """A polygon with holes."""

    model_config = ConfigDict(extra="forbid")
    exterior: Ring = Field(description="Exterior ring [[x, y], ...] [m], >= 3 vertices.")
    holes: list[Ring] = Field(default_factory=list, description="Hole rings [m].")


class WorldFile(BaseModel):
    """A polygon world file (YAML form); the JSON Schema is :func:`world_schema`."""

    model_config = ConfigDict(extra="forbid", title="wheelbase world")
    bounds: tuple[float, float, float, float] | None = Field(
        None, description="Map rectangle [x_min, x_max, y_min, y_max] [m]; default: the grid's "
        "extent, else the obstacles' bounding box."
    )  # fmt: skip
    resolution: float | None = Field(
        None, gt=0, description="Raster cell [m] (distance field, heuristic, plots); default 0.1."
    )
    grid: str | None = Field(
        None, description="A bundled map name or a map file (relative to this file)."
    )
    polygons: list[Ring | PolygonSpec] = Field(
        default_factory=list, description="Obstacle polygons: a ring, or exterior and holes."
    )
    discs: list[tuple[float, float, float]] = Field(
        default_factory=list, description="Disc obstacles [x, y, radius] [m]."
    )


def world_schema() -> dict[str, Any]:
    """The JSON Schema of the YAML world format (as shipped in ``data/schemas``).

    Returns
    -------
    dict
    """
    schema = WorldFile.model_json_schema()
    schema["$schema"] = "https://json-schema.org/draft/2020-12/schema"
    return schema


def is_world_mapping(data: object) -> bool:
    """Whether a parsed YAML/JSON document is a world (rather than, e.g., a ROS map).

    Parameters
    ----------
    data : object
        The parsed document.

    Returns
    -------
    bool
    """
    if not isinstance(data, dict):
        return False
    if data.get("type") in ("FeatureCollection", "Feature", "Polygon", "MultiPolygon"):
        return True
    return bool(data) and set(data) <= _WORLD_KEYS and "image" not in data


def read_world_file(
    path: str | FilePath,
    *,
    max_cells: int = MAX_MAP_CELLS,
    load_grid: Callable[..., OccupancyGrid | PolygonWorld] | None = None,
) -> OccupancyGrid | PolygonWorld:
    """Read a ``.geojson``/``.json`` world, or a ``.yaml``/``.yml`` file that holds either a
    world or a ROS ``map_server`` map (one that names an ``image``).

    Parameters
    ----------
    path : str or pathlib.Path
        The file.
    max_cells : int
        Most cells of a grid map (pixels, checked before decoding) or of a polygon world's
        raster (default :data:`wheelbase.limits.MAX_MAP_CELLS` = 1e8).
    load_grid : callable or None
        ``load_grid(name_or_path, max_cells=...)`` loads the map a world's ``grid`` names (a
        bundled map or a map file): :func:`~wheelbase.planning.load_map`, which reads world
        files through this function and passes itself. Without one, a world that names a
        grid is refused (this module reads files; the names and kinds of maps live above it).

    Returns
    -------
    OccupancyGrid or PolygonWorld

    Raises
    ------
    MapError
        Invalid YAML/JSON or a malformed world.
    DataError
        A file that cannot be read or is not UTF-8.
    """
    path = FilePath(path)
    suffix = path.suffix.lower()
    text = read_text(path, "world file")
    try:
        data = json.loads(text) if suffix in (".geojson", ".json") else yaml.safe_load(text)
    except (json.JSONDecodeError, yaml.YAMLError, ValueError, RecursionError) as exc:
        # ValueError: an integer of more than 4300 digits; RecursionError: lists nested deep
        raise MapError(f"{path}: not valid {suffix[1:].upper()}: {exc}") from None
    if is_world_mapping(data):
        return world_from_mapping(data, path.parent, str(path), max_cells, load_grid)
    if suffix in (".geojson", ".json"):
        raise MapError(f"{path}: expected a GeoJSON FeatureCollection, Feature or Polygon")
    return read_ros_yaml(path, max_cells=max_cells)


def world_from_mapping(
    data: dict,
    base: FilePath,
    label: str,
    max_cells: int = MAX_MAP_CELLS,
    load_grid: Callable[..., OccupancyGrid | PolygonWorld] | None = None,
) -> PolygonWorld:
    """A polygon world from a parsed world mapping (YAML or GeoJSON, see the module docstring).

    Parameters
    ----------
    data : dict
        The mapping.
    base : pathlib.Path
        Folder that a relative ``grid`` path is relative to.
    label : str
        What the mapping is, for messages (a file name).
    max_cells : int
        Most cells of the grid map or of the world's raster.
    load_grid : callable or None
        Loads the map ``grid`` names (see :func:`read_world_file`).

    Returns
    -------
    PolygonWorld

    Raises
    ------
    MapError
        A malformed world (the message names the field or polygon).
    """
    if data.get("type") is not None:
        data = _from_geojson(data, label)
    try:
        spec = WorldFile.model_validate(data)
    except ValidationError as exc:
        first = exc.errors()[0]
        where = ".".join(str(p) for p in first["loc"])
        raise MapError(f"{label}: {where}: {first['msg']}") from None
    grid = None
    if spec.grid is not None:
        if load_grid is None:
            raise MapError(
                f"{label}: grid {spec.grid!r} names a map; read the world with "
                "wheelbase.planning.load_map, which loads it"
            )
        target = FilePath(spec.grid)
        if target.suffix and not target.is_absolute():
            target = base / target
        grid = load_grid(target if target.suffix else spec.grid, max_cells=max_cells)
        if not isinstance(grid, OccupancyGrid):
            raise MapError(f"{label}: grid must name a grid map (got a polygon world)")
    polygons = [(p.exterior, p.holes) if isinstance(p, PolygonSpec) else p for p in spec.polygons]
    try:
        return PolygonWorld(
            polygons, spec.discs, spec.bounds, spec.resolution, grid, max_cells=max_cells
        )
    except MapError as exc:
        raise MapError(f"{label}: {exc}") from None


def _from_geojson(data: dict, label: str) -> dict:
    kind = data.get("type")
    if kind == "FeatureCollection":
        features = data.get("features")
        if not isinstance(features, list):
            raise MapError(f"{label}: a FeatureCollection needs a 'features' list")
    elif kind == "Feature":
        features = [data]
    else:
        features = [{"type": "Feature", "geometry": data, "properties": {}}]
    polygons: list = []
    discs: list = []
    for i, feature in enumerate(features):
        geometry = feature.get("geometry") if isinstance(feature, dict) else None
        if not isinstance(geometry, dict):
            raise MapError(f"{label}: feature {i} has no geometry")
        gtype, coords = geometry.get("type"), geometry.get("coordinates")
        props = feature.get("properties") or {}
        if gtype == "Polygon":
            groups = [coords]
        elif gtype == "MultiPolygon":
            groups = coords
        elif gtype == "Point":
            if "radius" not in props:
                raise MapError(f"{label}: feature {i} (Point) needs a 'radius' property [m]")
            if not isinstance(coords, list) or len(coords) < 2:
                raise MapError(f"{label}: feature {i} (Point) needs coordinates [x, y]")
            discs.append([*coords[:2], props["radius"]])
            continue
        else:
            raise MapError(
                f"{label}: feature {i}: geometry {gtype!r} is not Polygon, MultiPolygon or Point"
            )
        for rings in groups:
            if not isinstance(rings, list) or not rings:
                raise MapError(f"{label}: feature {i}: a polygon needs at least one ring")
            polygons.append({"exterior": rings[0], "holes": rings[1:]})
    out: dict = {"polygons": polygons, "discs": discs}
    if "bbox" in data:
        box = data["bbox"]
        if not isinstance(box, list) or len(box) != 4:
            raise MapError(f"{label}: bbox must be [x_min, y_min, x_max, y_max] (got {box!r})")
        out["bounds"] = [box[0], box[2], box[1], box[3]]
    for key in ("resolution", "grid"):
        if key in data:
            out[key] = data[key]
    return out
