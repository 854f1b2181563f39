"""Read and write occupancy grids: plain images and ROS ``map_server`` YAML + PGM/PNG pairs.

The grid convention (row 0 = lowest y) is described in :mod:`wheelbase.planning.occupancy`;
image formats store the top row first and are flipped here. Moving AI ``.map`` files are read by
:mod:`wheelbase.planning.movingai`.
"""

from __future__ import annotations

import re
import warnings
from pathlib import Path as FilePath

import numpy as np
import yaml
from numpy.typing import ArrayLike

from wheelbase._validate import check_choice, finite, read_text
from wheelbase.errors import ConfigError, DataError, MapError
from wheelbase.limits import MAX_MAP_CELLS
from wheelbase.planning.occupancy import OccupancyGrid

__all__ = ["read_image", "read_ros_yaml", "write_ros_yaml"]

_ROS_MODES = ("trinary", "scale", "raw")


def read_image(
    path: str | FilePath,
    resolution: float,
    origin: ArrayLike = (0.0, 0.0),
    *,
    threshold: float = 0.5,
    max_cells: int = MAX_MAP_CELLS,
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
        A pixel is occupied when its darkness ``1 − gray/255`` exceeds this value, in
        [0, 1).
    max_cells : int
        Most pixels accepted, checked before decoding (default
        :data:`wheelbase.limits.MAX_MAP_CELLS` = 1e8); PIL itself refuses more than
        ``2 × PIL.Image.MAX_IMAGE_PIXELS`` (1.8e8).

    Returns
    -------
    OccupancyGrid
    """
    threshold = finite("threshold", threshold)
    if not 0.0 <= threshold < 1.0:
        raise ConfigError(f"threshold must be in [0, 1) (got {threshold:g})")
    gray = _read_gray(FilePath(path), max_cells)
    darkness = 1.0 - gray / 255.0
    return OccupancyGrid(np.flipud(darkness > threshold), resolution, tuple(np.ravel(origin)[:2]))


def read_ros_yaml(
    path: str | FilePath, *, unknown_as_occupied: bool = True, max_cells: int = MAX_MAP_CELLS
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
    max_cells : int
        Most pixels accepted (see :func:`read_image`).

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
    text = read_text(path, "map YAML")
    try:
        meta = yaml.safe_load(text)
    except (yaml.YAMLError, ValueError, RecursionError) as exc:
        # ValueError: an integer of more than 4300 digits; RecursionError: lists nested deep
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
    for name, value in (("occupied_thresh", occ_t), ("free_thresh", free_t)):
        if not 0.0 <= value <= 1.0:
            raise MapError(f"{path}: {name} must be in [0, 1] (got {value:g})")
    if free_t > occ_t:
        raise MapError(
            f"{path}: free_thresh must be <= occupied_thresh (got {free_t:g} > {occ_t:g})"
        )
    negate = meta.get("negate", 0)
    if negate not in (0, 1):  # YAML's true/false are 1/0 too, as map_server reads them
        raise MapError(f"{path}: negate must be 0 or 1 (got {negate!r})")
    resolution = finite("resolution", meta["resolution"], "m/cell", error=MapError)
    if resolution <= 0:
        raise MapError(f"{path}: resolution must be > 0 m/cell (got {resolution})")
    origin = meta["origin"]
    try:
        origin_xy = np.asarray(origin[:2], dtype=np.float64)
    except (TypeError, ValueError, KeyError):
        origin_xy = np.zeros(0)
    if not isinstance(origin, list | tuple) or origin_xy.shape != (2,):
        raise MapError(f"{path}: origin must be [x, y, yaw] in m, m, rad (got {origin!r})")
    if not np.all(np.isfinite(origin_xy)):
        raise MapError(f"{path}: origin must be finite (got {origin!r})")
    gray = _read_gray(image, max_cells)
    if mode == "raw":
        unknown = gray > 100
        occ = (gray / 100.0 > occ_t) & ~unknown
    else:
        p = gray / 255.0 if negate else (255.0 - gray) / 255.0
        occ = p > occ_t
        unknown = ~occ & (p >= free_t) if mode == "trinary" else np.zeros_like(occ)
    if unknown_as_occupied:
        occ = occ | unknown
    return OccupancyGrid(np.flipud(occ), resolution, tuple(origin_xy), np.flipud(unknown))


def write_ros_yaml(
    grid: OccupancyGrid, path: str | FilePath, *, image: str | None = None
) -> FilePath:
    """Write the grid as a ROS ``map_server`` YAML + binary PGM pair (trinary mode).

    Occupied cells are written 0, free 254 and unknown free cells 205, as ``map_saver``
    does, so that :func:`read_ros_yaml` reads back the same grid.

    Parameters
    ----------
    grid : OccupancyGrid
        The grid to write.
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
    pixels = np.full(grid.shape, 254, np.uint8)
    if grid.unknown is not None:
        pixels[grid.unknown] = 205
    pixels[grid.occupied & (grid.unknown is None or ~grid.unknown)] = 0
    pixels = np.ascontiguousarray(np.flipud(pixels))
    if image_path.suffix.lower() == ".png":
        from PIL import Image

        Image.fromarray(pixels, mode="L").save(image_path, optimize=True)
    else:
        header = f"P5\n{grid.shape[1]} {grid.shape[0]}\n255\n".encode()
        image_path.write_bytes(header + pixels.tobytes())
    meta = {
        "image": image_path.name,
        "mode": "trinary",
        "resolution": grid.resolution,
        "origin": [grid.origin[0], grid.origin[1], 0.0],
        "negate": 0,
        "occupied_thresh": 0.65,
        "free_thresh": 0.196,
    }
    path.write_text(yaml.safe_dump(meta, sort_keys=False))
    return image_path


def _read_gray(path: FilePath, max_cells: int = MAX_MAP_CELLS) -> np.ndarray:
    """Gray levels 0..255 of an image, its size checked against ``max_cells`` before decoding."""
    from PIL import Image, UnidentifiedImageError

    def too_big(pixels: str) -> MapError:
        return MapError(
            f"map image {path} has {pixels} pixels: more than max_cells = {max_cells}; use a "
            "coarser image or raise max_cells (scenarios: resources.max_map_cells)"
        )

    try:
        with warnings.catch_warnings():
            # PIL warns above 8.9e7 pixels and refuses twice that: the size is checked here
            warnings.simplefilter("ignore", Image.DecompressionBombWarning)
            with Image.open(path) as img:
                width, height = img.size
                if width * height > max_cells:
                    raise too_big(f"{width} × {height} = {width * height:.3g}")
                if img.mode in ("LA", "RGBA", "PA"):
                    img = img.convert("RGBA").convert("RGB")
                gray = np.asarray(img.convert("L") if img.mode != "L" else img, dtype=np.float64)
    except MapError:
        raise
    except Image.DecompressionBombError as exc:
        # PIL refuses before the size can be read here; its message has it
        found = re.search(r"\((\d+) pixels\)", str(exc))
        raise too_big(f"{int(found[1]):.3g}" if found else "too many") from None
    except (OSError, UnidentifiedImageError, ValueError, SyntaxError, EOFError) as exc:
        raise DataError(f"cannot read map image {path}: {exc}") from None
    if gray.ndim != 2 or gray.size == 0:
        raise MapError(f"map image {path} is empty")
    return gray
