"""Map IO in ROS map_server format: round trips, pixel interpretation, bad files."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from mrcomm.errors import InputError
from mrcomm.world import mapio
from mrcomm.world.mapio import load_map, save_map
from mrcomm.world.occupancy import OccupancyGrid


def _asymmetric_grid() -> OccupancyGrid:
    """A grid with no symmetry, so any flip or transpose shows."""
    occ = np.zeros((7, 11), dtype=np.bool_)
    occ[0, :] = True  # bottom row
    occ[:, 0] = True  # left column
    occ[4, 6] = True
    occ[5, 2:4] = True
    return OccupancyGrid(occ, 0.1, (-1.25, 3.5))


def _write_map(tmp_path: Path, pixels: np.ndarray, **keys: object) -> Path:
    """Write ``pixels`` (image row order) as map.png plus a YAML with ``keys``."""
    image = keys.pop("image", "map.png")
    Image.fromarray(pixels).save(tmp_path / str(image))
    entries = {"image": image, "resolution": 0.5, "origin": [0.0, 0.0, 0.0], **keys}
    lines = [f"{k}: {v}" for k, v in entries.items()]
    yaml_path = tmp_path / "map.yaml"
    yaml_path.write_text("\n".join(lines) + "\n")
    return yaml_path


@pytest.mark.parametrize("image_name", [None, "floor.png"])
def test_round_trip_keeps_cells_resolution_and_origin(
    tmp_path: Path, image_name: str | None
) -> None:
    grid = _asymmetric_grid()
    save_map(grid, tmp_path / "m.yaml", image_name=image_name)
    loaded = load_map(tmp_path / "m.yaml")
    np.testing.assert_array_equal(loaded.occupied, grid.occupied)
    assert loaded.resolution == grid.resolution
    assert loaded.origin == grid.origin
    image = tmp_path / (image_name or "m.pgm")
    assert image.exists()
    if image_name is None:
        assert image.read_bytes().startswith(b"P5")


def test_image_top_row_is_grid_last_row(tmp_path: Path) -> None:
    grid = _asymmetric_grid()
    save_map(grid, tmp_path / "m.yaml")
    pixels = np.asarray(Image.open(tmp_path / "m.pgm"))
    # Grid row 0 (bottom, all occupied) is the image's last row.
    assert (pixels[-1, :] == mapio.OCCUPIED_PIXEL).all()
    assert pixels[0, 5] == mapio.FREE_PIXEL
    # A cell's world position survives: (4, 6) is occupied at its world coordinates.
    loaded = load_map(tmp_path / "m.yaml")
    x, y = grid.cell_to_world(4, 6)
    assert not loaded.is_free(x, y)
    assert loaded.is_free(*grid.cell_to_world(4, 5))


def test_save_writes_ros_keys_and_comment(tmp_path: Path) -> None:
    save_map(_asymmetric_grid(), tmp_path / "m.yaml", comment="made by a test")
    text = (tmp_path / "m.yaml").read_text()
    assert text.startswith("# made by a test\n")
    for key in mapio.MAP_KEYS:
        assert f"\n{key}: " in text
    assert "origin: [-1.25, 3.5, 0.0]" in text


def test_save_is_atomic_on_failure(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    save_map(_asymmetric_grid(), tmp_path / "m.yaml")
    before = {p.name: p.read_bytes() for p in tmp_path.iterdir()}

    def broken_write_text(self: Path, *args: object, **kwargs: object) -> int:
        raise OSError("disk full")

    monkeypatch.setattr(Path, "write_text", broken_write_text)
    empty = OccupancyGrid(np.zeros((3, 3), dtype=np.bool_), 0.1)
    with pytest.raises(OSError, match="disk full"):
        save_map(empty, tmp_path / "m.yaml")
    after = {p.name: p.read_bytes() for p in tmp_path.iterdir()}
    assert after == before  # old map untouched, no temporary files left


def test_trinary_thresholds_and_unknown_is_occupied(tmp_path: Path) -> None:
    # p = (255 - v) / 255: 255 -> 0 (free), 205 -> 0.196 (unknown), 0 -> 1 (occupied).
    pixels = np.array([[255, 230, 205, 100, 0]], dtype=np.uint8)
    grid = load_map(_write_map(tmp_path, pixels, occupied_thresh=0.65, free_thresh=0.196))
    assert grid.occupied[0].tolist() == [False, False, True, True, True]
    grid = load_map(_write_map(tmp_path, pixels, occupied_thresh=0.65, free_thresh=0.5))
    assert grid.occupied[0].tolist() == [False, False, False, True, True]


def test_negate_inverts_pixels(tmp_path: Path) -> None:
    pixels = np.array([[255, 0]], dtype=np.uint8)
    assert load_map(_write_map(tmp_path, pixels, negate=0)).occupied[0].tolist() == [False, True]
    assert load_map(_write_map(tmp_path, pixels, negate=1)).occupied[0].tolist() == [True, False]


def test_raw_mode_reads_percent(tmp_path: Path) -> None:
    pixels = np.array([[0, 10, 50, 100, 255]], dtype=np.uint8)
    grid = load_map(_write_map(tmp_path, pixels, mode="raw", free_thresh=0.2))
    assert grid.occupied[0].tolist() == [False, False, True, True, True]


def test_scale_mode_transparent_is_unknown(tmp_path: Path) -> None:
    rgba = np.zeros((1, 3, 4), dtype=np.uint8)
    rgba[0, :, :3] = 255
    rgba[0, :, 3] = [255, 0, 255]
    rgba[0, 2, :3] = 0
    yaml_path = _write_map(tmp_path, rgba, mode="scale")
    assert load_map(yaml_path).occupied[0].tolist() == [False, True, True]
    # trinary ignores alpha, as map_server does
    yaml_path = _write_map(tmp_path, rgba, mode="trinary")
    assert load_map(yaml_path).occupied[0].tolist() == [False, False, True]


def test_colour_channels_are_averaged(tmp_path: Path) -> None:
    # (255, 255, 0) averages to 170 -> p = 0.33: neither free nor occupied -> occupied;
    # with free_thresh 0.4 it is free. A luminance weighting would give a different p.
    rgb = np.array([[[255, 255, 0], [255, 255, 255]]], dtype=np.uint8)
    assert load_map(_write_map(tmp_path, rgb)).occupied[0].tolist() == [True, False]
    grid = load_map(_write_map(tmp_path, rgb, free_thresh=0.4))
    assert grid.occupied[0].tolist() == [False, False]


def test_plain_and_16_bit_pgm(tmp_path: Path) -> None:
    (tmp_path / "p2.pgm").write_bytes(b"P2\n# a comment\n3 2\n15\n15 0 15\n0 15 0\n")
    (tmp_path / "p2.yaml").write_text("image: p2.pgm\nresolution: 1\norigin: [0, 0, 0]\n")
    grid = load_map(tmp_path / "p2.yaml")
    # image top row (15 0 15) is grid row 1
    assert grid.occupied.tolist() == [[True, False, True], [False, True, False]]
    data = np.array([[65535, 0]], dtype=">u2").tobytes()
    (tmp_path / "p16.pgm").write_bytes(b"P5 2 1 65535\n" + data)
    (tmp_path / "p16.yaml").write_text("image: p16.pgm\nresolution: 1\norigin: [0, 0, 0]\n")
    assert load_map(tmp_path / "p16.yaml").occupied.tolist() == [[False, True]]


def test_image_path_is_relative_to_yaml(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    (tmp_path / "maps").mkdir()
    save_map(_asymmetric_grid(), tmp_path / "maps" / "m.yaml")
    monkeypatch.chdir(tmp_path)
    assert load_map(Path("maps/m.yaml")).width == 11


def _bad(tmp_path: Path, text: str, image: bytes | None = b"ok") -> InputError:
    if image == b"ok":
        Image.fromarray(np.full((2, 2), 255, dtype=np.uint8)).save(tmp_path / "m.pgm")
    elif image is not None:
        (tmp_path / "m.pgm").write_bytes(image)
    (tmp_path / "m.yaml").write_text(text)
    with pytest.raises(InputError) as info:
        load_map(tmp_path / "m.yaml")
    return info.value


GOOD = "image: m.pgm\nresolution: 0.05\norigin: [0, 0, 0]\n"


@pytest.mark.parametrize(
    ("text", "field", "words"),
    [
        (GOOD + "resolutoin: 1\n", "resolutoin", "did you mean 'resolution'"),
        ("resolution: 0.05\norigin: [0, 0, 0]\n", "image", "missing"),
        ("image: m.pgm\norigin: [0, 0, 0]\n", "resolution", "missing"),
        ("image: m.pgm\nresolution: fine\norigin: [0, 0, 0]\n", "resolution", "number"),
        ("image: m.pgm\nresolution: -1\norigin: [0, 0, 0]\n", "resolution", "positive"),
        ("image: m.pgm\nresolution: 0.05\norigin: [0, 0]\n", "origin", "[x, y, yaw]"),
        ("image: m.pgm\nresolution: 0.05\norigin: [0, 0, 0.5]\n", "origin", "yaw"),
        (GOOD + "mode: trinery\n", "mode", "did you mean 'trinary'"),
        (GOOD + "negate: 2\n", "negate", "0 or 1"),
        (GOOD + "occupied_thresh: 1.5\n", "occupied_thresh", "between 0 and 1"),
        (GOOD + "free_thresh: 0.9\n", "free_thresh", "below occupied_thresh"),
        ("image: nothere.pgm\nresolution: 0.05\norigin: [0, 0, 0]\n", "image", "not found"),
    ],
)
def test_bad_map_yaml_names_file_and_field(
    tmp_path: Path, text: str, field: str, words: str
) -> None:
    err = _bad(tmp_path, text)
    assert err.file is not None and err.file.endswith("m.yaml")
    assert err.field == field
    assert words in err.one_line()
    assert "\n" not in err.one_line()


def test_missing_yaml_file(tmp_path: Path) -> None:
    with pytest.raises(InputError, match="file not found"):
        load_map(tmp_path / "absent.yaml")


def test_malformed_yaml_and_duplicate_keys(tmp_path: Path) -> None:
    assert "not valid YAML" in _bad(tmp_path, "image: [unclosed\n").one_line()
    assert "given twice" in _bad(tmp_path, GOOD + "image: m.pgm\n").one_line()
    assert "mapping" in _bad(tmp_path, "- just\n- a list\n").one_line()


def test_unreadable_image(tmp_path: Path) -> None:
    err = _bad(tmp_path, GOOD, image=b"this is not an image")
    assert err.field == "image"
    assert "cannot read image" in err.one_line()
