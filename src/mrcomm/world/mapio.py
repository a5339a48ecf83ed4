"""Maps in the ROS map_server format: a YAML file plus an image (PGM or PNG).

YAML keys (as ROS): ``image`` (path relative to the YAML file), ``resolution`` (m per
cell), ``origin`` ``[x, y, yaw]`` (pose of the lower-left pixel; only yaw 0 is
supported), ``negate`` (0/1), ``occupied_thresh``, ``free_thresh`` and ``mode``
(``trinary`` | ``scale`` | ``raw``). Only ``image``, ``resolution`` and ``origin`` are
required; the others default to ROS map_saver's values.

Pixel interpretation follows map_server: the channel average ``v`` (0..255; inverted
when ``negate``) gives an occupancy probability ``p = (255 - v) / 255``; a cell is free
when ``p < free_thresh``. In ``raw`` mode ``v`` itself is the occupancy in percent
(0..100; anything above is unknown) and a cell is free when ``v / 100 < free_thresh``.
Occupied and unknown cells both become occupied: a robot never plans through space
nobody has seen. In ``scale`` mode a transparent pixel is unknown.

Image row 0 is the top of the map; the grid's row 0 is the bottom, so rows are flipped.
"""

from __future__ import annotations

import math
import warnings
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray
from PIL import Image, UnidentifiedImageError

from mrcomm.errors import InputError, did_you_mean
from mrcomm.fileio import commit, stage
from mrcomm.world.occupancy import OccupancyGrid
from mrcomm.world.yamlfile import read_yaml

#: Largest coordinate accepted anywhere on a map (m): far beyond any map, small enough
#: that no grid arithmetic on it overflows.
MAX_COORDINATE = 1e6
#: Most cells a map image may have (a 500 m square at 5 cm): checked from its header,
#: before any pixel is decoded.
MAX_MAP_CELLS = 100_000_000
MAP_KEYS = ("image", "resolution", "origin", "negate", "occupied_thresh", "free_thresh", "mode")
MODES = ("trinary", "scale", "raw")
#: map_saver's defaults (ROS 1), used when a key is absent and when saving.
DEFAULT_OCCUPIED_THRESH = 0.65
DEFAULT_FREE_THRESH = 0.196
#: Pixel values written by :func:`save_map` (map_saver's: free 254, occupied 0).
FREE_PIXEL = 254
OCCUPIED_PIXEL = 0


def _number(raw: dict[str, Any], key: str, file: Path, default: float | None = None) -> float:
    if key not in raw:
        if default is None:
            raise InputError("required key is missing", file=file, field=key)
        return default
    value = raw[key]
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise InputError(f"must be a number, got {value!r}", file=file, field=key)
    return float(value)


def _read_image(
    path: Path, yaml_file: Path, mode: str
) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
    """Channel-average grey level (0..255, image row order) and a transparency mask."""
    if path.exists() and not path.is_file():
        raise InputError(f"not a regular file: {path}", file=yaml_file, field="image")
    try:
        with warnings.catch_warnings():
            # Pillow warns of big images; the size is judged here, against our limit.
            warnings.simplefilter("ignore", Image.DecompressionBombWarning)
            img = Image.open(path)  # reads the header only
        with img:
            if img.width * img.height > MAX_MAP_CELLS:
                raise InputError(
                    f"image {path} is {img.width} x {img.height} pixels: more than "
                    f"{MAX_MAP_CELLS:,} cells",
                    file=yaml_file,
                    field="image",
                )
            img.load()
            image = img.copy()
    except FileNotFoundError:
        raise InputError(f"image file not found: {path}", file=yaml_file, field="image") from None
    except Image.DecompressionBombError as err:
        message = f"cannot read image {path}: {err}"
        raise InputError(message, file=yaml_file, field="image") from None
    except (UnidentifiedImageError, OSError, ValueError, SyntaxError) as err:
        # Pillow reports a malformed header as SyntaxError/ValueError.
        raise InputError(
            f"cannot read image {path}: {err}", file=yaml_file, field="image"
        ) from None
    transparent = np.zeros((image.height, image.width), dtype=np.bool_)
    if image.mode in ("I", "I;16", "I;16B", "I;16L"):
        # 16-bit PGM: Pillow scales samples to 0..65535.
        grey = np.asarray(image, dtype=np.float64) * (255.0 / 65535.0)
    elif image.mode == "F":
        raise InputError(
            f"unsupported image mode {image.mode!r} in {path}", file=yaml_file, field="image"
        )
    else:
        if image.mode == "P":
            image = image.convert("RGBA")
        has_alpha = image.mode in ("LA", "RGBA", "PA")
        if has_alpha:
            alpha = np.asarray(image.getchannel("A"), dtype=np.uint8)
            if mode == "scale":
                transparent = alpha < 255
            image = image.convert("RGB" if image.mode == "RGBA" else "L")
        if image.mode not in ("L", "RGB"):
            image = image.convert("L")
        pixels = np.asarray(image, dtype=np.float64)
        # map_server averages the colour channels (not a luminance weighting).
        grey = pixels.mean(axis=2) if pixels.ndim == 3 else pixels
    return grey, transparent


def load_map(yaml_path: str | Path) -> OccupancyGrid:
    """Load a ROS map_server map; any problem is an InputError naming file and field."""
    file = Path(yaml_path)
    raw = read_yaml(file)
    if not isinstance(raw, dict):
        raise InputError("must be a mapping of map_server keys (image, resolution, ...)", file=file)
    for key in raw:
        if key not in MAP_KEYS:
            raise InputError(
                f"unknown key '{key}'{did_you_mean(str(key), MAP_KEYS)}", file=file, field=str(key)
            )
    image_name = raw.get("image")
    if image_name is None:
        raise InputError("required key is missing", file=file, field="image")
    if not isinstance(image_name, str) or not image_name:
        raise InputError(f"must be a file name, got {image_name!r}", file=file, field="image")
    resolution = _number(raw, "resolution", file)
    if not 0 < resolution <= 1000.0:
        raise InputError(
            f"must be positive and at most 1000 m per cell, got {resolution}",
            file=file,
            field="resolution",
        )
    origin = raw.get("origin")
    if origin is None:
        raise InputError("required key is missing", file=file, field="origin")
    if (
        not isinstance(origin, list)
        or len(origin) != 3
        or any(isinstance(v, bool) or not isinstance(v, int | float) for v in origin)
        or not all(math.isfinite(v) and abs(v) <= MAX_COORDINATE for v in origin)
    ):
        raise InputError(
            f"must be [x, y, yaw] (numbers), got {origin!r}", file=file, field="origin"
        )
    if abs(origin[2]) > 1e-9:
        raise InputError(
            f"non-zero yaw ({origin[2]}) is not supported: rotate the image instead",
            file=file,
            field="origin",
        )
    negate = raw.get("negate", 0)
    if negate not in (0, 1) or (isinstance(negate, float)):
        raise InputError(f"must be 0 or 1, got {negate!r}", file=file, field="negate")
    occupied_thresh = _number(raw, "occupied_thresh", file, DEFAULT_OCCUPIED_THRESH)
    free_thresh = _number(raw, "free_thresh", file, DEFAULT_FREE_THRESH)
    for key, value in (("occupied_thresh", occupied_thresh), ("free_thresh", free_thresh)):
        if not 0.0 <= value <= 1.0:
            raise InputError(f"must be between 0 and 1, got {value}", file=file, field=key)
    if free_thresh >= occupied_thresh:
        raise InputError(
            f"must be below occupied_thresh ({occupied_thresh}), got {free_thresh}",
            file=file,
            field="free_thresh",
        )
    mode = raw.get("mode", "trinary")
    if mode not in MODES:
        raise InputError(
            f"must be one of {', '.join(MODES)}, got {mode!r}{did_you_mean(str(mode), MODES)}",
            file=file,
            field="mode",
        )
    image_path = Path(image_name)
    if not image_path.is_absolute():
        image_path = file.parent / image_path
    grey, transparent = _read_image(image_path, file, mode)
    if grey.size == 0:
        raise InputError(f"image {image_path} is empty", file=file, field="image")
    if bool(negate):
        grey = 255.0 - grey
    # raw: the pixel is the occupancy in percent; otherwise map_server's probability.
    occupancy = grey / 100.0 if mode == "raw" else (255.0 - grey) / 255.0
    free = occupancy < free_thresh
    free &= ~transparent
    occupied = np.flipud(~free).copy()
    return OccupancyGrid(occupied, resolution, (float(origin[0]), float(origin[1])))


def save_map(
    grid: OccupancyGrid,
    yaml_path: str | Path,
    *,
    image_name: str | None = None,
    comment: str | None = None,
) -> None:
    """Write ``grid`` as a trinary map_server map: ``<stem>.pgm`` (or ``image_name``,
    whose suffix ``.png`` selects PNG) next to ``yaml_path``.

    Both files are written to temporary files first and renamed into place only when
    both are complete, so an error never leaves a half-written map. ``comment`` is put
    at the top of the YAML file (e.g. which script generated it).
    """
    yaml_file = Path(yaml_path)
    name = image_name or f"{yaml_file.stem}.pgm"
    image_file = yaml_file.parent / name
    suffix = image_file.suffix.lower()
    formats = {".pgm": "PPM", ".png": "PNG"}
    if suffix not in formats:
        raise ValueError(f"image must end in .pgm or .png, got {name!r}")
    pixels = np.where(np.flipud(grid.occupied), OCCUPIED_PIXEL, FREE_PIXEL).astype(np.uint8)
    ox, oy = grid.origin
    lines = [f"# {line}".rstrip() for line in (comment or "").splitlines()]
    lines += [
        f"image: {name}",
        "mode: trinary",
        f"resolution: {float(grid.resolution)!r}",
        f"origin: [{float(ox)!r}, {float(oy)!r}, 0.0]",
        "negate: 0",
        f"occupied_thresh: {DEFAULT_OCCUPIED_THRESH}",
        f"free_thresh: {DEFAULT_FREE_THRESH}",
    ]
    text = "\n".join(lines) + "\n"

    def write_image(tmp: Path) -> None:
        Image.fromarray(pixels).save(tmp, format=formats[suffix])

    def write_yaml(tmp: Path) -> None:
        tmp.write_text(text, encoding="utf-8")

    tmp_image = stage(image_file, write_image)
    try:
        tmp_yaml = stage(yaml_file, write_yaml)
    except BaseException:
        tmp_image.unlink(missing_ok=True)
        raise
    # The image goes first so the YAML never points at a missing or partial image.
    commit(tmp_image, image_file)
    commit(tmp_yaml, yaml_file)


__all__ = ["MAP_KEYS", "MODES", "load_map", "save_map"]
