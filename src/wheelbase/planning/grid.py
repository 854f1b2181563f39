"""Occupancy grids: loaders, writer, inflation, distance field and footprint collision checks.

The planning problem of document 000 ("path planning of a wheeled mobile robot in a static
environment", §1.1) and of document 002 (Hybrid A*) is posed on a 2-D occupancy grid. Here a
grid is a boolean array ``occupied[row, col]`` with **row 0 at the lowest y and column 0 at the
lowest x** (so ``occupied[i, j]`` covers the square ``[x0 + j·r, x0 + (j+1)·r) × [y0 + i·r,
y0 + (i+1)·r)`` for resolution ``r`` and origin ``(x0, y0)``). Image formats (ROS ``map_server``
PGM/PNG, Moving AI ``.map``) store the top row first and are flipped on load.

Cells outside the map are occupied. Unknown cells are occupied unless a loader is told
otherwise (``unknown_as_occupied=False``).

Collision semantics ("exact to the cell resolution"): a robot footprint (a convex polygon in the
body frame) at a pose collides iff the polygon intersects the closed square of an occupied cell,
or leaves the map. The fast path uses the Euclidean distance field and circles covering the
footprint; poses that are neither clearly free nor clearly in collision fall back to an exact
separating-axis test against every occupied cell under the footprint's bounding box.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path as FilePath

import numba
import numpy as np
import yaml
from numpy.typing import ArrayLike
from scipy import ndimage

from wheelbase._validate import as_float_array, check_choice, finite, nonnegative, positive
from wheelbase.errors import ConfigError, DataError, InputError, MapError

__all__ = [
    "Footprint",
    "MovingAIScenario",
    "OccupancyGrid",
    "read_movingai_scenarios",
]

_MOVINGAI_PASSABLE = frozenset(".GS")
_ROS_MODES = ("trinary", "scale", "raw")


@dataclass(frozen=True, eq=False)
class OccupancyGrid:
    """A 2-D occupancy grid in world coordinates.

    Parameters
    ----------
    occupied : numpy.ndarray
        Boolean array of shape ``(rows, cols)``; ``True`` = blocked. Row 0 is the lowest y,
        column 0 the lowest x.
    resolution : float
        Cell side [m/cell], > 0.
    origin : tuple of float
        World position ``(x0, y0)`` [m] of the lower-left corner of cell ``(0, 0)``.
    unknown : numpy.ndarray or None
        Optional boolean mask of cells whose state was unknown in the source map (already
        merged into ``occupied`` or not, as the loader was told).

    Examples
    --------
    >>> grid = OccupancyGrid.from_array(np.zeros((30, 40), bool), 0.5)
    >>> grid.width_m, grid.height_m
    (20.0, 15.0)
    """

    occupied: np.ndarray
    resolution: float
    origin: tuple[float, float] = (0.0, 0.0)
    unknown: np.ndarray | None = field(default=None, repr=False)

    def __post_init__(self) -> None:
        occ = np.asarray(self.occupied)
        if occ.ndim != 2 or occ.size == 0:
            raise MapError(f"occupied must be a non-empty 2-D array (got shape {occ.shape})")
        occ = np.ascontiguousarray(occ.astype(bool))
        occ.setflags(write=False)
        object.__setattr__(self, "occupied", occ)
        object.__setattr__(self, "resolution", positive("resolution", self.resolution, "m/cell"))
        origin = as_float_array("origin", self.origin, max_ndim=1)
        if origin.shape not in ((2,), (3,)):
            raise InputError(f"origin must be (x0, y0) [m] (got shape {origin.shape})")
        object.__setattr__(self, "origin", (float(origin[0]), float(origin[1])))
        if self.unknown is not None:
            unknown = np.asarray(self.unknown, dtype=bool)
            if unknown.shape != occ.shape:
                raise MapError(f"unknown mask shape {unknown.shape} != map shape {occ.shape}")
            object.__setattr__(self, "unknown", unknown)

    # ------------------------------------------------------------------ constructors
    @classmethod
    def from_array(
        cls,
        occupied: ArrayLike,
        resolution: float,
        origin: ArrayLike = (0.0, 0.0),
        *,
        occupied_thresh: float = 0.5,
    ) -> OccupancyGrid:
        """Build a grid from an array (row 0 = lowest y, column 0 = lowest x).

        Parameters
        ----------
        occupied : array_like
            Boolean array (``True`` = occupied) or numeric occupancy probabilities in [0, 1];
            a numeric cell is occupied when its value is >= ``occupied_thresh``, and NaN or
            negative values (ROS's −1) are unknown, hence occupied.
        resolution : float
            Cell side [m/cell].
        origin : array_like
            ``(x0, y0)`` [m] of the lower-left corner of cell (0, 0).
        occupied_thresh : float
            Threshold for numeric arrays.

        Returns
        -------
        OccupancyGrid
        """
        array = np.asarray(occupied)
        if array.dtype == bool:
            return cls(array, resolution, tuple(np.ravel(origin)[:2]))
        if not np.issubdtype(array.dtype, np.number):
            raise MapError(f"occupied must be a bool or numeric array (got dtype {array.dtype})")
        values = array.astype(np.float64)
        unknown = ~np.isfinite(values) | (values < 0)
        with np.errstate(invalid="ignore"):
            occ = (values >= occupied_thresh) | unknown
        return cls(occ, resolution, tuple(np.ravel(origin)[:2]), unknown)

    @classmethod
    def from_image(
        cls,
        path: str | FilePath,
        resolution: float,
        origin: ArrayLike = (0.0, 0.0),
        *,
        threshold: float = 0.5,
    ) -> OccupancyGrid:
        """Load a plain image (PNG, PGM, BMP…): dark pixels are occupied.

        Parameters
        ----------
        path : str or pathlib.Path
            Image file; its top row is the highest y.
        resolution : float
            Cell side [m/pixel].
        origin : array_like
            ``(x0, y0)`` [m] of the lower-left corner of the image.
        threshold : float
            A pixel is occupied when its darkness ``1 − gray/255`` exceeds this value.

        Returns
        -------
        OccupancyGrid
        """
        gray = _read_gray(FilePath(path))
        darkness = 1.0 - gray / 255.0
        return cls(np.flipud(darkness > threshold), resolution, tuple(np.ravel(origin)[:2]))

    @classmethod
    def from_ros_yaml(
        cls, path: str | FilePath, *, unknown_as_occupied: bool = True
    ) -> OccupancyGrid:
        """Load a ROS ``map_server`` map: a YAML file naming a PGM/PNG image.

        Follows the ``map_server`` rules: ``p = (255 − v)/255`` (or ``v/255`` when
        ``negate: 1``); in ``trinary`` and ``scale`` modes a pixel with ``p > occupied_thresh``
        is occupied, ``p < free_thresh`` free and anything else unknown (trinary) or a partial
        cost that is treated as free (scale); in ``raw`` mode the value is the occupancy in
        percent and values above 100 are unknown. The origin yaw is ignored, as Nav2's costmap
        does.

        Parameters
        ----------
        path : str or pathlib.Path
            The YAML file.
        unknown_as_occupied : bool
            Treat unknown cells as occupied (default) or as free.

        Returns
        -------
        OccupancyGrid

        Raises
        ------
        MapError
            If the YAML is missing a field or has an invalid value.
        DataError
            If a file cannot be read.
        """
        path = FilePath(path)
        try:
            meta = yaml.safe_load(path.read_text())
        except OSError as exc:
            raise DataError(f"cannot read map YAML {path}: {exc}") from None
        except yaml.YAMLError as exc:
            raise MapError(f"{path}: invalid YAML: {exc}") from None
        if not isinstance(meta, dict):
            raise MapError(f"{path}: expected a mapping with image, resolution, origin")
        for key in ("image", "resolution", "origin"):
            if key not in meta:
                raise MapError(f"{path}: missing field {key!r}")
        image = FilePath(str(meta["image"]))
        if not image.is_absolute():
            image = path.parent / image
        if not image.exists():
            alternatives = [path.with_suffix(s) for s in (".pgm", ".png")]
            found = [p for p in alternatives if p.exists()]
            if not found:
                raise DataError(f"{path}: image {str(meta['image'])!r} not found")
            warnings.warn(
                f"{path}: image {str(meta['image'])!r} not found; using {found[0].name}",
                stacklevel=2,
            )
            image = found[0]
        mode = check_choice("mode", str(meta.get("mode", "trinary")), _ROS_MODES)
        occ_t = finite("occupied_thresh", meta.get("occupied_thresh", 0.65), error=MapError)
        free_t = finite("free_thresh", meta.get("free_thresh", 0.196), error=MapError)
        negate = bool(int(meta.get("negate", 0)))
        resolution = finite("resolution", meta["resolution"], "m/cell", error=MapError)
        if resolution <= 0:
            raise MapError(f"{path}: resolution must be > 0 m/cell (got {resolution})")
        origin = meta["origin"]
        if not isinstance(origin, list | tuple) or len(origin) < 2:
            raise MapError(f"{path}: origin must be [x, y, yaw] (got {origin!r})")
        gray = _read_gray(image)
        if mode == "raw":
            unknown = gray > 100
            occ = (gray / 100.0 > occ_t) & ~unknown
        else:
            p = gray / 255.0 if negate else (255.0 - gray) / 255.0
            occ = p > occ_t
            unknown = ~occ & (p >= free_t) if mode == "trinary" else np.zeros_like(occ)
        if unknown_as_occupied:
            occ = occ | unknown
        origin_xy = (float(origin[0]), float(origin[1]))
        return cls(np.flipud(occ), resolution, origin_xy, np.flipud(unknown))

    @classmethod
    def from_movingai(
        cls, path: str | FilePath, resolution: float = 1.0, origin: ArrayLike = (0.0, 0.0)
    ) -> OccupancyGrid:
        """Load a Moving AI benchmark ``.map`` file (Sturtevant 2012).

        ``.``, ``G`` and ``S`` are passable; every other terrain (``@``, ``O``, ``T``, ``W``) is
        blocked. The file's first row (Moving AI y = 0) becomes the highest grid row, so Moving
        AI cell ``(x, y)`` is grid cell ``(height − 1 − y, x)``: see :meth:`movingai_cell`.

        Parameters
        ----------
        path : str or pathlib.Path
            The ``.map`` file. Text after the ``height`` map rows (e.g. a BibTeX entry) is
            ignored.
        resolution : float
            Cell side [m/cell].
        origin : array_like
            ``(x0, y0)`` [m] of the lower-left corner.

        Returns
        -------
        OccupancyGrid
        """
        path = FilePath(path)
        try:
            lines = path.read_text().splitlines()
        except OSError as exc:
            raise DataError(f"cannot read Moving AI map {path}: {exc}") from None
        header: dict[str, str] = {}
        row0 = None
        for i, line in enumerate(lines):
            parts = line.split()
            if parts and parts[0] == "map":
                row0 = i + 1
                break
            if len(parts) == 2:
                header[parts[0]] = parts[1]
        if row0 is None or "height" not in header or "width" not in header:
            raise MapError(f"{path}: not a Moving AI map (needs height, width and map lines)")
        height, width = int(header["height"]), int(header["width"])
        rows = lines[row0 : row0 + height]
        if len(rows) < height or any(len(r) < width for r in rows):
            raise MapError(f"{path}: expected {height} rows of {width} characters")
        chars = np.array([list(r[:width]) for r in rows])
        blocked = ~np.isin(chars, list(_MOVINGAI_PASSABLE))
        return cls(np.flipud(blocked), resolution, tuple(np.ravel(origin)[:2]))

    # ------------------------------------------------------------------ writer
    def to_ros_yaml(self, path: str | FilePath, *, image: str | None = None) -> FilePath:
        """Write the grid as a ROS ``map_server`` YAML + binary PGM pair (trinary mode).

        Occupied cells are written 0, free 254 and unknown free cells 205, as ``map_saver``
        does, so that :meth:`from_ros_yaml` reads back the same grid.

        Parameters
        ----------
        path : str or pathlib.Path
            The YAML file to write; the image goes beside it.
        image : str or None
            Image file name (``.pgm`` or ``.png``); default: the YAML's stem + ``.pgm``.

        Returns
        -------
        pathlib.Path
            The image path.
        """
        path = FilePath(path)
        image_path = path.parent / (image or path.with_suffix(".pgm").name)
        pixels = np.full(self.shape, 254, np.uint8)
        if self.unknown is not None:
            pixels[self.unknown] = 205
        pixels[self.occupied & (self.unknown is None or ~self.unknown)] = 0
        pixels = np.ascontiguousarray(np.flipud(pixels))
        if image_path.suffix.lower() == ".png":
            from PIL import Image

            Image.fromarray(pixels, mode="L").save(image_path, optimize=True)
        else:
            header = f"P5\n{self.shape[1]} {self.shape[0]}\n255\n".encode()
            image_path.write_bytes(header + pixels.tobytes())
        meta = {
            "image": image_path.name,
            "mode": "trinary",
            "resolution": self.resolution,
            "origin": [self.origin[0], self.origin[1], 0.0],
            "negate": 0,
            "occupied_thresh": 0.65,
            "free_thresh": 0.196,
        }
        path.write_text(yaml.safe_dump(meta, sort_keys=False))
        return image_path

    # ------------------------------------------------------------------ geometry
    @property
    def shape(self) -> tuple[int, int]:
        """``(rows, cols)`` of the grid."""
        return self.occupied.shape  # type: ignore[return-value]

    @property
    def width_m(self) -> float:
        """Extent along x [m]."""
        return self.shape[1] * self.resolution

    @property
    def height_m(self) -> float:
        """Extent along y [m]."""
        return self.shape[0] * self.resolution

    @property
    def extent(self) -> tuple[float, float, float, float]:
        """``(x_min, x_max, y_min, y_max)`` [m], e.g. for ``imshow(..., origin="lower")``."""
        x0, y0 = self.origin
        return (x0, x0 + self.width_m, y0, y0 + self.height_m)

    def world_to_cell(self, xy: ArrayLike) -> np.ndarray:
        """Cells ``(row, col)`` (int64, shape ``(..., 2)``) containing world points ``(x, y)``.

        Parameters
        ----------
        xy : array_like
            Points ``(..., 2)`` or poses ``(..., 3)`` [m]; only x and y are used.

        Returns
        -------
        numpy.ndarray
            Indices; points outside the map give indices outside ``[0, rows) × [0, cols)``.
        """
        xy = as_float_array("xy", xy, min_ndim=1)
        if xy.shape[-1] not in (2, 3):
            raise InputError(f"xy must have shape (..., 2) or (..., 3) (got {xy.shape})")
        col = np.floor((xy[..., 0] - self.origin[0]) / self.resolution).astype(np.int64)
        row = np.floor((xy[..., 1] - self.origin[1]) / self.resolution).astype(np.int64)
        return np.stack([row, col], -1)

    def cell_to_world(self, cells: ArrayLike) -> np.ndarray:
        """World coordinates ``(x, y)`` [m] of the centres of cells ``(row, col)``.

        Parameters
        ----------
        cells : array_like
            Integer or fractional cell indices ``(..., 2)`` as ``(row, col)``.

        Returns
        -------
        numpy.ndarray
            Shape ``(..., 2)``.
        """
        cells = as_float_array("cells", cells, 2)
        x = self.origin[0] + (cells[..., 1] + 0.5) * self.resolution
        y = self.origin[1] + (cells[..., 0] + 0.5) * self.resolution
        return np.stack([x, y], -1)

    def contains(self, xy: ArrayLike) -> np.ndarray:
        """Whether world points ``(..., 2)`` lie inside the map rectangle.

        Parameters
        ----------
        xy : array_like
            Points or poses [m].

        Returns
        -------
        numpy.ndarray
            Boolean array of shape ``xy.shape[:-1]``.
        """
        cells = self.world_to_cell(xy)
        rows, cols = self.shape
        return (
            (cells[..., 0] >= 0)
            & (cells[..., 0] < rows)
            & (cells[..., 1] >= 0)
            & (cells[..., 1] < cols)
        )

    def is_occupied(self, xy: ArrayLike) -> np.ndarray:
        """Whether the cells under world points are occupied (outside the map: ``True``).

        Parameters
        ----------
        xy : array_like
            Points or poses [m].

        Returns
        -------
        numpy.ndarray
            Boolean array of shape ``xy.shape[:-1]``.
        """
        cells = self.world_to_cell(xy)
        inside = self.contains(xy)
        rows = np.clip(cells[..., 0], 0, self.shape[0] - 1)
        cols = np.clip(cells[..., 1], 0, self.shape[1] - 1)
        return ~inside | self.occupied[rows, cols]

    # ------------------------------------------------------------------ derived maps
    @cached_property
    def distance_field(self) -> np.ndarray:
        """Euclidean distance [m] from each cell centre to the nearest occupied cell centre.

        Computed once with ``scipy.ndimage.distance_transform_edt``; 0 on occupied cells and
        ``inf`` everywhere when the map has no occupied cell. The map border is not an
        obstacle here (leaving the map is checked separately).
        """
        if not self.occupied.any():
            out = np.full(self.shape, np.inf)
        else:
            out = ndimage.distance_transform_edt(~self.occupied) * self.resolution
        out.setflags(write=False)
        return out

    @cached_property
    def occupancy_prefix(self) -> np.ndarray:
        """Per-row prefix counts of occupied cells, shape ``(rows, cols + 1)`` (int32): the
        number of occupied cells in row ``i`` and columns ``j0..j1`` is
        ``prefix[i, j1 + 1] − prefix[i, j0]``."""
        out = np.zeros((self.shape[0], self.shape[1] + 1), np.int32)
        np.cumsum(self.occupied, axis=1, out=out[:, 1:])
        out.setflags(write=False)
        return out

    def clearance(self, xy: ArrayLike) -> np.ndarray:
        """Distance [m] from world points to the nearest occupied cell (its square).

        A lower bound good to one cell: the distance field at the point's cell minus the
        largest offset between a point and a cell centre in the two cells involved (√2·r).
        Outside the map: 0.

        Parameters
        ----------
        xy : array_like
            Points or poses [m].

        Returns
        -------
        numpy.ndarray
            Shape ``xy.shape[:-1]`` [m], >= 0.
        """
        cells = self.world_to_cell(xy)
        inside = self.contains(xy)
        rows = np.clip(cells[..., 0], 0, self.shape[0] - 1)
        cols = np.clip(cells[..., 1], 0, self.shape[1] - 1)
        d = self.distance_field[rows, cols] - math.sqrt(2.0) * self.resolution
        return np.where(inside, np.maximum(d, 0.0), 0.0)

    def inflate(self, radius: float) -> OccupancyGrid:
        """A new grid where every cell whose centre is within ``radius`` of an occupied cell
        centre is occupied (a disk-shaped robot of that radius reduced to a point).

        Parameters
        ----------
        radius : float
            Inflation radius [m], >= 0.

        Returns
        -------
        OccupancyGrid
        """
        radius = nonnegative("radius", radius, "m")
        occ = self.occupied | (self.distance_field <= radius)
        return OccupancyGrid(occ, self.resolution, self.origin, self.unknown)

    # ------------------------------------------------------------------ collision
    def in_collision(
        self, footprint: Footprint, poses: ArrayLike, *, margin: float = 0.0
    ) -> np.ndarray:
        """Footprint collision check at one pose ``(3,)`` or a batch ``(N, 3)``.

        A pose collides iff the footprint polygon (grown by ``margin`` along every edge
        normal) intersects an occupied cell's square or leaves the map. Exact to the cell
        resolution: the distance field and covering circles decide clear cases, an exact
        separating-axis test decides the rest.

        Parameters
        ----------
        footprint : Footprint
            Robot outline in the body frame of the reference point.
        poses : array_like
            Reference-point poses ``(x, y, θ)`` [m, m, rad], shape ``(3,)`` or ``(N, 3)``.
        margin : float
            Extra clearance [m], >= 0.

        Returns
        -------
        numpy.ndarray
            Boolean, shape ``poses.shape[:-1]``.
        """
        poses = as_float_array("poses", poses, 3, min_ndim=1, max_ndim=2)
        margin = nonnegative("margin", margin, "m")
        fp = footprint.inflated(margin) if margin > 0 else footprint
        flat = poses.reshape(-1, 3)
        out = _collides_batch(
            self.occupied.view(np.uint8),
            self.occupancy_prefix,
            np.asarray(self.distance_field),
            self.resolution,
            self.origin[0],
            self.origin[1],
            fp.polygon,
            fp.circles,
            fp.circle_radius,
            flat,
        )
        return out.reshape(poses.shape[:-1])

    def lattice_collisions(
        self, footprint: Footprint, poses: ArrayLike, spacing: float = 0.02
    ) -> np.ndarray:
        """Brute-force reference check: whether each pose's footprint, sampled as a lattice of
        points ``spacing`` apart, has a point on an occupied cell (or off the map).

        Slow and independent of :meth:`in_collision` (no distance field, no covering circles,
        no cell rasterisation): tests and benchmarks use it to verify the fast path and planned
        paths. A gap narrower than ``spacing`` between lattice points can be missed.

        Parameters
        ----------
        footprint : Footprint
            Robot outline.
        poses : array_like, shape (N, 3)
            Poses [m, m, rad].
        spacing : float
            Lattice spacing [m], > 0.

        Returns
        -------
        numpy.ndarray
            Boolean array of shape (N,).
        """
        spacing = positive("spacing", spacing, "m")
        poses = as_float_array("poses", poses, 3, min_ndim=2, max_ndim=2)
        poly = footprint.polygon
        lo, hi = poly.min(0), poly.max(0)
        xs = np.linspace(lo[0], hi[0], math.ceil((hi[0] - lo[0]) / spacing) + 1)
        ys = np.linspace(lo[1], hi[1], math.ceil((hi[1] - lo[1]) / spacing) + 1)
        points = np.stack(np.meshgrid(xs, ys), -1).reshape(-1, 2)
        # keep the lattice points inside the (convex, counter-clockwise) polygon
        edges = np.roll(poly, -1, 0) - poly
        cross = edges[:, 0] * (points[:, None, 1] - poly[:, 1]) - edges[:, 1] * (
            points[:, None, 0] - poly[:, 0]
        )
        points = points[np.all(cross >= -1e-12, axis=1)]
        hits = np.zeros(len(poses), bool)
        for rows in np.array_split(np.arange(len(poses)), max(1, len(poses) // 500)):
            chunk = poses[rows]
            c, s = np.cos(chunk[:, 2]), np.sin(chunk[:, 2])
            wx = chunk[:, None, 0] + c[:, None] * points[:, 0] - s[:, None] * points[:, 1]
            wy = chunk[:, None, 1] + s[:, None] * points[:, 0] + c[:, None] * points[:, 1]
            hits[rows] = np.any(self.is_occupied(np.stack([wx, wy], -1)), axis=1)
        return hits

    def footprint_clearance(self, footprint: Footprint, poses: ArrayLike) -> np.ndarray:
        """Distance [m] from the footprint polygon at each pose to the nearest occupied cell.

        Exact polygon-to-square distance over occupied cells near the footprint (searched
        within the distance-field bound); 0 when in collision.

        Parameters
        ----------
        footprint : Footprint
            Robot outline.
        poses : array_like
            Poses ``(N, 3)`` or ``(3,)``.

        Returns
        -------
        numpy.ndarray
            Clearances [m], shape ``poses.shape[:-1]``.
        """
        poses = as_float_array("poses", poses, 3, min_ndim=1, max_ndim=2)
        flat = poses.reshape(-1, 3)
        out = _clearance_batch(
            self.occupied.view(np.uint8),
            self.occupancy_prefix,
            np.asarray(self.distance_field),
            self.resolution,
            self.origin[0],
            self.origin[1],
            footprint.polygon,
            footprint.circles,
            footprint.circle_radius,
            flat,
        )
        return out.reshape(poses.shape[:-1])


@dataclass(frozen=True, eq=False)
class Footprint:
    """A convex robot outline in the body frame of its reference point.

    The reference point is the origin of the body frame: the rear-axle centre for car-like
    robots, the wheel-axle centre for differential drive. Planners report poses of it.

    Parameters
    ----------
    polygon : numpy.ndarray
        Convex polygon vertices ``(M, 2)`` [m] in the body frame (x forward, y left), in
        counter-clockwise or clockwise order.

    Examples
    --------
    >>> fp = Footprint.rectangle(4.5, 1.8, rear_axle_to_center=1.35)
    >>> [round(float(v), 3) for v in (fp.polygon[:, 0].min(), fp.polygon[:, 0].max())]
    [-0.9, 3.6]
    """

    polygon: np.ndarray

    def __post_init__(self) -> None:
        poly = as_float_array("polygon", self.polygon, 2, min_ndim=2, max_ndim=2)
        if len(poly) < 3:
            raise ConfigError(f"polygon needs >= 3 vertices (got {len(poly)})")
        area2 = np.sum(poly[:, 0] * np.roll(poly[:, 1], -1) - np.roll(poly[:, 0], -1) * poly[:, 1])
        if abs(area2) < 1e-12:
            raise ConfigError("polygon must have a non-zero area")
        if area2 < 0:
            poly = poly[::-1]
        edges = np.roll(poly, -1, axis=0) - poly
        nxt = np.roll(edges, -1, axis=0)
        if np.any(edges[:, 0] * nxt[:, 1] - edges[:, 1] * nxt[:, 0] < -1e-12):
            raise ConfigError("polygon must be convex")
        poly = np.ascontiguousarray(poly)
        poly.setflags(write=False)
        object.__setattr__(self, "polygon", poly)

    @classmethod
    def rectangle(cls, length: float, width: float, rear_axle_to_center: float = 0.0) -> Footprint:
        """A ``length × width`` rectangle whose centre is ``rear_axle_to_center`` ahead of the
        reference point.

        Parameters
        ----------
        length : float
            Extent along the body x axis [m], > 0.
        width : float
            Extent along the body y axis [m], > 0.
        rear_axle_to_center : float
            Distance [m] from the reference point (rear-axle centre) forward to the
            rectangle's centre; 0 for a robot whose reference point is its centre.

        Returns
        -------
        Footprint
        """
        length = positive("length", length, "m")
        width = positive("width", width, "m")
        c = finite("rear_axle_to_center", rear_axle_to_center, "m")
        hl, hw = length / 2.0, width / 2.0
        return cls(np.array([[c - hl, -hw], [c + hl, -hw], [c + hl, hw], [c - hl, hw]]))

    @cached_property
    def circles(self) -> np.ndarray:
        """Centres ``(K, 2)`` [m] of circles that together cover the polygon's bounding box."""
        (xmin, ymin), (xmax, ymax) = self.polygon.min(0), self.polygon.max(0)
        length, width = xmax - xmin, ymax - ymin
        along_x = length >= width
        long_side, short_side = (length, width) if along_x else (width, length)
        n = max(1, math.ceil(2.0 * long_side / short_side))
        t = (np.arange(n) + 0.5) / n
        if along_x:
            return np.stack([xmin + t * length, np.full(n, (ymin + ymax) / 2)], -1)
        return np.stack([np.full(n, (xmin + xmax) / 2), ymin + t * width], -1)

    @cached_property
    def circle_radius(self) -> float:
        """Radius [m] of each covering circle."""
        (xmin, ymin), (xmax, ymax) = self.polygon.min(0), self.polygon.max(0)
        length, width = xmax - xmin, ymax - ymin
        n = len(self.circles)
        long_side, short_side = max(length, width), min(length, width)
        return float(math.hypot(long_side / (2 * n), short_side / 2))

    @property
    def circle_overshoot(self) -> float:
        """How far [m] the covering :attr:`circles` reach beyond the polygon at most (at the
        ends of a long outline: 0.56 m for a 4.5 × 1.8 m car)."""
        return float(self.outline_distance(self.circles, np.full(len(self.circles),
                                                                 self.circle_radius)))  # fmt: skip

    def outline_distance(self, centres: np.ndarray, radii: np.ndarray) -> float:
        """Largest distance [m] from the polygon to a point of the disks ``(centres, radii)``.

        The farthest point of a disk from a convex polygon lies on its rim; 64 rim points per
        disk bound it to 0.1 % of the radius.

        Parameters
        ----------
        centres : numpy.ndarray, shape (K, 2)
            Disk centres [m] in the body frame.
        radii : numpy.ndarray, shape (K,)
            Disk radii [m].

        Returns
        -------
        float
            0 when every disk lies inside the polygon.
        """
        angle = np.linspace(0.0, 2.0 * math.pi, 64, endpoint=False)
        rim = np.stack([np.cos(angle), np.sin(angle)], -1)
        points = (centres[:, None, :] + radii[:, None, None] * rim).reshape(-1, 2)
        return float(np.max(_polygon_distance(self.polygon, points), initial=0.0))

    def outline_circles(self, spacing: float) -> np.ndarray:
        """Disks ``(K, 3)`` = (x [m], y [m], radius [m]) that follow the outline closely.

        Disks of radius ``spacing / 2`` centred on the edges every ``spacing`` at most (the
        vertices included) cover a band along the outline and reach at most ``spacing / 2``
        beyond it; disks inscribed in the polygon along its long axis (every half its width)
        fill the middle. Unlike :attr:`circles`, which reach 0.56 m past the ends of a car, this
        lets a critic see a wall close behind a reversing car; a point obstacle can only get
        into the uncovered pockets at the corners by crossing the band, which a step shorter
        than ``spacing`` does not skip.

        Parameters
        ----------
        spacing : float
            Largest gap [m] between neighbouring edge disks, > 0.

        Returns
        -------
        numpy.ndarray
        """
        spacing = positive("spacing", spacing, "m")
        poly = self.polygon
        rows = []
        for start, end in zip(poly, np.roll(poly, -1, axis=0), strict=True):
            count = max(1, math.ceil(float(np.hypot(*(end - start))) / spacing - 1e-9))
            frac = np.arange(count)[:, None] / count
            rows.append(start + frac * (end - start))
        edge = np.concatenate(rows)
        (xmin, ymin), (xmax, ymax) = poly.min(0), poly.max(0)
        along_x = xmax - xmin >= ymax - ymin
        short = min(xmax - xmin, ymax - ymin)
        lo, hi = (xmin, xmax) if along_x else (ymin, ymax)
        first, last = lo + short / 2.0, hi - short / 2.0
        count = max(1, math.ceil((last - first) / (short / 2.0) - 1e-9))
        t = first + (last - first) * np.arange(count + 1) / count
        mid = (ymin + ymax) / 2.0 if along_x else (xmin + xmax) / 2.0
        inner = np.stack([t, np.full_like(t, mid)], -1) if along_x else np.stack(
            [np.full_like(t, mid), t], -1)  # fmt: skip
        inner_radius = np.maximum(-_polygon_distance(poly, inner), 0.0)
        keep = inner_radius > 0.0
        return np.ascontiguousarray(
            np.concatenate(
                [
                    np.column_stack([edge, np.full(len(edge), spacing / 2.0)]),
                    np.column_stack([inner[keep], inner_radius[keep]]),
                ]
            )
        )

    @cached_property
    def max_radius(self) -> float:
        """Largest distance [m] from the reference point to a vertex."""
        return float(np.max(np.hypot(self.polygon[:, 0], self.polygon[:, 1])))

    @cached_property
    def inscribed_radius(self) -> float:
        """Distance [m] from the reference point to the nearest edge (0 if it is outside)."""
        poly = self.polygon
        edges = np.roll(poly, -1, axis=0) - poly
        normals = np.stack([edges[:, 1], -edges[:, 0]], -1)
        normals /= np.linalg.norm(normals, axis=1, keepdims=True)
        d = -np.sum(normals * poly, axis=1)  # signed distance of the origin, <0 inside
        return float(max(0.0, -d.max()))

    def inflated(self, margin: float) -> Footprint:
        """The polygon with every edge moved outward by ``margin`` (contains the Minkowski sum
        with a disk of that radius).

        Parameters
        ----------
        margin : float
            Offset [m], >= 0.

        Returns
        -------
        Footprint
        """
        margin = nonnegative("margin", margin, "m")
        if margin == 0:
            return self
        poly = self.polygon
        m = len(poly)
        edges = np.roll(poly, -1, axis=0) - poly
        normals = np.stack([edges[:, 1], -edges[:, 0]], -1)
        normals /= np.linalg.norm(normals, axis=1, keepdims=True)
        offset = np.sum(normals * poly, axis=1) + margin
        out = np.empty_like(poly)
        for i in range(m):
            j = (i - 1) % m  # edges j and i meet at vertex i
            a = np.array([normals[j], normals[i]])
            out[i] = np.linalg.solve(a, [offset[j], offset[i]])
        return Footprint(out)


def _polygon_distance(poly: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Signed distance [m] from ``points (P, 2)`` to a convex counter-clockwise polygon
    (negative inside)."""
    edges = np.roll(poly, -1, axis=0) - poly
    normals = np.stack([edges[:, 1], -edges[:, 0]], -1)
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    # outside: the distance to the nearest edge segment; inside: minus the nearest edge line
    rel = points[:, None, :] - poly[None]
    t = np.clip(np.sum(rel * edges, -1) / np.sum(edges * edges, -1), 0.0, 1.0)
    gap = np.linalg.norm(rel - t[..., None] * edges, axis=-1).min(1)
    side = np.max(np.sum(rel * normals, -1), axis=1)
    return np.where(side > 0.0, gap, side)


# ---------------------------------------------------------------------- Numba kernels
@numba.njit(cache=True)
def _world_polygon(poly, x, y, th):
    c, s = math.cos(th), math.sin(th)
    out = np.empty_like(poly)
    for k in range(poly.shape[0]):
        out[k, 0] = x + c * poly[k, 0] - s * poly[k, 1]
        out[k, 1] = y + s * poly[k, 0] + c * poly[k, 1]
    return out


@numba.njit(cache=True)
def _point_in_polygon(wp, px, py):
    m = wp.shape[0]
    for i in range(m):
        j = (i + 1) % m
        cross = (wp[j, 0] - wp[i, 0]) * (py - wp[i, 1]) - (wp[j, 1] - wp[i, 1]) * (px - wp[i, 0])
        if cross < 0.0:
            return False
    return True


@numba.njit(cache=True)
def _poly_square_separated(wp, sx0, sy0, side, gap):
    """True if convex polygon ``wp`` and square [sx0, sx0+side]² are more than ``gap`` apart
    along some separating axis (SAT; gap = 0 tests intersection of closed sets)."""
    m = wp.shape[0]
    pxmin = wp[:, 0].min()
    pxmax = wp[:, 0].max()
    pymin = wp[:, 1].min()
    pymax = wp[:, 1].max()
    if pxmax < sx0 - gap or pxmin > sx0 + side + gap:
        return True
    if pymax < sy0 - gap or pymin > sy0 + side + gap:
        return True
    for i in range(m):
        j = (i + 1) % m
        ex = wp[j, 0] - wp[i, 0]
        ey = wp[j, 1] - wp[i, 1]
        norm = math.sqrt(ex * ex + ey * ey)
        nx = ey / norm
        ny = -ex / norm
        # polygon lies on the side n·p <= n·wp[i] (CCW); square's min projection
        pmax = nx * wp[i, 0] + ny * wp[i, 1]
        smin = min(nx * sx0, nx * (sx0 + side)) + min(ny * sy0, ny * (sy0 + side))
        if smin > pmax + gap:
            return True
    return False


@numba.njit(cache=True)
def _collides_one(occ, prefix, dist, res, x0, y0, poly, circles, radius, x, y, th):
    rows, cols = occ.shape
    wp = _world_polygon(poly, x, y, th)
    xmax_map = x0 + cols * res
    ymax_map = y0 + rows * res
    for k in range(wp.shape[0]):
        if wp[k, 0] < x0 or wp[k, 0] >= xmax_map or wp[k, 1] < y0 or wp[k, 1] >= ymax_map:
            return True
    c, s = math.cos(th), math.sin(th)
    slack = math.sqrt(2.0) * res
    all_clear = True
    for k in range(circles.shape[0]):
        cx = x + c * circles[k, 0] - s * circles[k, 1]
        cy = y + s * circles[k, 0] + c * circles[k, 1]
        j = math.floor((cx - x0) / res)
        i = math.floor((cy - y0) / res)
        if i < 0 or i >= rows or j < 0 or j >= cols:
            all_clear = False
            continue
        if occ[i, j] and _point_in_polygon(wp, cx, cy):
            return True
        if dist[i, j] - slack <= radius:
            all_clear = False
    if all_clear:
        return False
    return _polygon_hits_cells(prefix, res, x0, y0, wp)


@numba.njit(cache=True)
def _polygon_hits_cells(prefix, res, x0, y0, wp):
    """Exact test: does convex polygon ``wp`` meet any occupied (closed) cell square?

    Row band by row band: the polygon's x-extent inside the band [y_i, y_i + r] is an interval
    (convexity), and a square of that row meets the polygon iff its x-range meets that interval;
    per-row prefix sums of occupancy answer "any occupied cell in columns j0..j1" in O(1).
    """
    rows = prefix.shape[0]
    cols = prefix.shape[1] - 1
    m = wp.shape[0]
    ymin = wp[:, 1].min()
    ymax = wp[:, 1].max()
    i0 = max(0, math.ceil((ymin - y0) / res) - 1)
    i1 = min(rows - 1, math.floor((ymax - y0) / res))
    for i in range(i0, i1 + 1):
        yb0 = y0 + i * res
        yb1 = yb0 + res
        lo = np.inf
        hi = -np.inf
        for k in range(m):
            vx = wp[k, 0]
            vy = wp[k, 1]
            if yb0 <= vy <= yb1:
                lo = min(lo, vx)
                hi = max(hi, vx)
            ax, ay = vx, vy
            bx = wp[(k + 1) % m, 0]
            by = wp[(k + 1) % m, 1]
            if ay != by:
                for yl in (yb0, yb1):
                    if (ay - yl) * (by - yl) <= 0.0:
                        xl = ax + (yl - ay) * (bx - ax) / (by - ay)
                        lo = min(lo, xl)
                        hi = max(hi, xl)
        if lo > hi:
            continue
        j0 = max(0, math.ceil((lo - x0) / res) - 1)
        j1 = min(cols - 1, math.floor((hi - x0) / res))
        if j1 >= j0 and prefix[i, j1 + 1] - prefix[i, j0] > 0:
            return True
    return False


@numba.njit(cache=True)
def _collides_batch(occ, prefix, dist, res, x0, y0, poly, circles, radius, poses):
    out = np.empty(poses.shape[0], dtype=np.bool_)
    for n in range(poses.shape[0]):
        out[n] = _collides_one(
            occ,
            prefix,
            dist,
            res,
            x0,
            y0,
            poly,
            circles,
            radius,
            poses[n, 0],
            poses[n, 1],
            poses[n, 2],
        )
    return out


@numba.njit(cache=True)
def _seg_seg_dist2(ax, ay, bx, by, cx, cy, dx, dy):
    best = np.inf
    for px, py, qx, qy, rx, ry in (
        (ax, ay, cx, cy, dx, dy),
        (bx, by, cx, cy, dx, dy),
        (cx, cy, ax, ay, bx, by),
        (dx, dy, ax, ay, bx, by),
    ):
        ux, uy = rx - qx, ry - qy
        ll = ux * ux + uy * uy
        t = 0.0 if ll == 0 else max(0.0, min(1.0, ((px - qx) * ux + (py - qy) * uy) / ll))
        ex, ey = qx + t * ux - px, qy + t * uy - py
        best = min(best, ex * ex + ey * ey)
    return best


@numba.njit(cache=True)
def _poly_square_distance(wp, sx, sy, side):
    if not _poly_square_separated(wp, sx, sy, side, 0.0):
        return 0.0
    sq = np.array([[sx, sy], [sx + side, sy], [sx + side, sy + side], [sx, sy + side]])
    best = np.inf
    m = wp.shape[0]
    for i in range(m):
        a = wp[i]
        b = wp[(i + 1) % m]
        for k in range(4):
            c = sq[k]
            d = sq[(k + 1) % 4]
            best = min(best, _seg_seg_dist2(a[0], a[1], b[0], b[1], c[0], c[1], d[0], d[1]))
    return math.sqrt(best)


@numba.njit(cache=True)
def _clearance_batch(occ, prefix, dist, res, x0, y0, poly, circles, radius, poses):
    rows, cols = occ.shape
    out = np.empty(poses.shape[0])
    slack = math.sqrt(2.0) * res
    for n in range(poses.shape[0]):
        x, y, th = poses[n, 0], poses[n, 1], poses[n, 2]
        if _collides_one(occ, prefix, dist, res, x0, y0, poly, circles, radius, x, y, th):
            out[n] = 0.0
            continue
        wp = _world_polygon(poly, x, y, th)
        # search radius: an upper bound on the clearance from points of the polygon (its first
        # vertex and the covering-circle centres that lie inside it)
        j = min(cols - 1, max(0, math.floor((wp[0, 0] - x0) / res)))
        i = min(rows - 1, max(0, math.floor((wp[0, 1] - y0) / res)))
        reach = dist[i, j] + slack
        c, s = math.cos(th), math.sin(th)
        for k in range(circles.shape[0]):
            cx = x + c * circles[k, 0] - s * circles[k, 1]
            cy = y + s * circles[k, 0] + c * circles[k, 1]
            if _point_in_polygon(wp, cx, cy):
                j = min(cols - 1, max(0, math.floor((cx - x0) / res)))
                i = min(rows - 1, max(0, math.floor((cy - y0) / res)))
                reach = min(reach, dist[i, j] + slack)
        if not np.isfinite(reach):
            out[n] = np.inf
            continue
        j0 = max(0, math.floor((wp[:, 0].min() - reach - x0) / res))
        j1 = min(cols - 1, math.floor((wp[:, 0].max() + reach - x0) / res))
        i0 = max(0, math.floor((wp[:, 1].min() - reach - y0) / res))
        i1 = min(rows - 1, math.floor((wp[:, 1].max() + reach - y0) / res))
        best = np.inf
        for a in range(i0, i1 + 1):
            for b in range(j0, j1 + 1):
                if occ[a, b]:
                    d = _poly_square_distance(wp, x0 + b * res, y0 + a * res, res)
                    best = min(best, d)
        out[n] = best
    return out


# ---------------------------------------------------------------------- helpers
def _read_gray(path: FilePath) -> np.ndarray:
    from PIL import Image, UnidentifiedImageError

    try:
        with Image.open(path) as img:
            if img.mode in ("LA", "RGBA", "PA"):
                img = img.convert("RGBA").convert("RGB")
            gray = np.asarray(img.convert("L") if img.mode != "L" else img, dtype=np.float64)
    except (OSError, UnidentifiedImageError) as exc:
        raise DataError(f"cannot read map image {path}: {exc}") from None
    if gray.ndim != 2 or gray.size == 0:
        raise MapError(f"map image {path} is empty")
    return gray


@dataclass(frozen=True)
class MovingAIScenario:
    """One row of a Moving AI ``.scen`` file.

    Parameters
    ----------
    bucket : int
        Difficulty bucket.
    map_name : str
        Map file name.
    width, height : int
        Map size [cells].
    start, goal : tuple of int
        Moving AI cells ``(x, y)`` (x = column, y = row from the top).
    optimal_length : float
        Optimal octile length [cells] (no corner cutting).
    """

    bucket: int
    map_name: str
    width: int
    height: int
    start: tuple[int, int]
    goal: tuple[int, int]
    optimal_length: float

    def grid_cells(self) -> tuple[tuple[int, int], tuple[int, int]]:
        """Start and goal as grid cells ``(row, col)`` of :meth:`OccupancyGrid.from_movingai`.

        Returns
        -------
        tuple
            ``((row, col), (row, col))``.
        """
        h = self.height
        return (h - 1 - self.start[1], self.start[0]), (h - 1 - self.goal[1], self.goal[0])


def read_movingai_scenarios(path: str | FilePath) -> list[MovingAIScenario]:
    """Read a Moving AI ``.scen`` file (version 1).

    Parameters
    ----------
    path : str or pathlib.Path
        The scenario file; lines that are not 9 tab- or space-separated fields after the
        version line (e.g. an appended BibTeX entry) end the table.

    Returns
    -------
    list of MovingAIScenario
    """
    path = FilePath(path)
    try:
        lines = path.read_text().splitlines()
    except OSError as exc:
        raise DataError(f"cannot read scenario file {path}: {exc}") from None
    out = []
    for line in lines[1:]:
        parts = line.split()
        if len(parts) != 9:
            break
        try:
            b, name, w, h, sx, sy, gx, gy, opt = parts
            out.append(
                MovingAIScenario(
                    int(b),
                    name,
                    int(w),
                    int(h),
                    (int(sx), int(sy)),
                    (int(gx), int(gy)),
                    float(opt),
                )
            )
        except ValueError:
            break
    if not out:
        raise DataError(f"{path}: no scenarios found")
    return out
