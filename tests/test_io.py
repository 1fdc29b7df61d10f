"""Tests for the phase 0 input edge: image, text and ROS maps, and scenario YAML."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest
from numpy.typing import NDArray
from PIL import Image

from mresim_phys.errors import MapError, ScenarioError
from mresim_phys.scenario.readers import (
    LoadedMap,
    load_image_map,
    load_map,
    load_ros_map,
    load_text_map,
    read_yaml_mapping,
)

PATTERN = np.array(
    [
        [0, 255, 255, 0],
        [255, 0, 255, 255],
        [255, 255, 255, 0],
    ],
    dtype=np.uint8,
)


def write_image(path: Path, pixels: NDArray[np.uint8], mode: str | None = None) -> Path:
    image = Image.fromarray(pixels)
    (image.convert(mode) if mode else image).save(path)
    return path


# --- image maps -------------------------------------------------------------------------


@pytest.mark.parametrize("suffix", [".png", ".bmp", ".gif"])
def test_image_round_trip_keeps_rows_and_columns(tmp_path: Path, suffix: str) -> None:
    path = write_image(tmp_path / f"map{suffix}", PATTERN)
    loaded = load_image_map(path)
    np.testing.assert_array_equal(loaded.occupied, PATTERN == 0)
    assert loaded.occupied.dtype == np.bool_
    assert loaded.resolution is None and loaded.origin is None and loaded.source == path


def test_rgb_image_uses_luminance(tmp_path: Path) -> None:
    colours = np.array([[[255, 0, 0], [255, 255, 0], [0, 0, 128], [200, 200, 200]]], np.uint8)
    loaded = load_image_map(write_image(tmp_path / "rgb.bmp", colours))
    assert loaded.occupied.tolist() == [[True, False, True, False]]  # red L=76, yellow L=226


def test_threshold_and_negate(tmp_path: Path) -> None:
    path = write_image(tmp_path / "grey.png", np.array([[0, 100, 200, 255]], np.uint8))
    assert load_image_map(path).occupied.tolist() == [[True, True, False, False]]
    assert load_image_map(path, threshold=0.3).occupied.tolist() == [[True, False, False, False]]
    assert load_image_map(path, threshold=1.0).occupied.tolist() == [[True, True, True, False]]
    negated = load_image_map(path, negate=True).occupied.tolist()
    assert negated == [[False, False, True, True]]


@pytest.mark.parametrize("threshold", [0.0, -0.2, 1.01, float("nan")])
def test_threshold_out_of_range_is_a_map_error(tmp_path: Path, threshold: float) -> None:
    path = write_image(tmp_path / "grey.png", PATTERN)
    with pytest.raises(MapError, match=r"grey\.png.*\(0, 1\]"):
        load_image_map(path, threshold=threshold)


def test_palette_png_uses_the_palette_colours_not_the_indices(tmp_path: Path) -> None:
    image = Image.new("P", (4, 1))
    image.putpalette([255, 255, 255, 0, 0, 0] + [0, 0, 0] * 254)  # index 0 white, 1 black
    image.putdata([0, 1, 1, 0])
    image.save(tmp_path / "palette.png")
    loaded = load_image_map(tmp_path / "palette.png")
    assert loaded.occupied.tolist() == [[False, True, True, False]]


def test_transparent_pixels_are_composited_on_white(tmp_path: Path) -> None:
    rgba = np.zeros((1, 3, 4), np.uint8)  # black everywhere
    rgba[0, :, 3] = [255, 0, 100]  # opaque, transparent, mostly transparent
    loaded = load_image_map(write_image(tmp_path / "alpha.png", rgba))
    assert loaded.occupied.tolist() == [[True, False, False]]


def test_sixteen_bit_greyscale_png(tmp_path: Path) -> None:
    path = tmp_path / "deep.png"
    Image.fromarray(np.array([[0, 30000, 40000, 65535]], np.uint16)).save(path)
    assert load_image_map(path).occupied.tolist() == [[True, True, False, False]]


def test_jpeg_blocks_survive_compression(tmp_path: Path) -> None:
    pixels = np.kron(PATTERN, np.ones((16, 16), np.uint8))
    Image.fromarray(pixels).save(tmp_path / "map.jpg", quality=90)
    occupied = load_image_map(tmp_path / "map.jpg").occupied
    np.testing.assert_array_equal(occupied[8::16, 8::16], PATTERN == 0)


@pytest.mark.parametrize("value", [0, 255])
def test_all_obstacle_or_all_free_images_are_allowed(tmp_path: Path, value: int) -> None:
    path = write_image(tmp_path / "plain.png", np.full((3, 5), value, np.uint8))
    assert load_image_map(path).occupied.tolist() == [[value == 0] * 5] * 3


def test_any_image_size_is_accepted(tmp_path: Path) -> None:
    path = write_image(tmp_path / "big.png", np.full((7, 1234), 255, np.uint8))
    assert load_image_map(path).occupied.shape == (7, 1234)


@pytest.mark.parametrize(
    ("name", "content", "message"),
    [
        ("missing.png", None, "does not exist"),
        ("notes.png", b"this is not an image", "not a readable image"),
        ("cut.png", "truncated", "not a readable image"),
    ],
)
def test_bad_image_files_are_map_errors_naming_the_file(
    tmp_path: Path, name: str, content: bytes | str | None, message: str
) -> None:
    path = tmp_path / name
    if content == "truncated":
        write_image(path, np.kron(PATTERN, np.ones((50, 50), np.uint8)))
        path.write_bytes(path.read_bytes()[:60])
    elif isinstance(content, bytes):
        path.write_bytes(content)
    with pytest.raises(MapError, match=message) as info:
        load_image_map(path)
    assert name in str(info.value)


def test_directory_instead_of_image_is_a_map_error(tmp_path: Path) -> None:
    with pytest.raises(MapError, match="not a regular file"):
        load_image_map(tmp_path)


# --- text maps ------------------------------------------------------------------------


def write_text(path: Path, text: str, newline: str = "\n") -> Path:
    path.write_bytes(text.replace("\n", newline).encode())
    return path


@pytest.mark.parametrize("newline", ["\n", "\r\n"])
def test_text_map_round_trip(tmp_path: Path, newline: str) -> None:
    path = write_text(tmp_path / "map.txt", "3\n4\n1001\n0100\n0001\n\n\n", newline)
    loaded = load_text_map(path)
    np.testing.assert_array_equal(loaded.occupied, PATTERN == 0)
    assert loaded.resolution is None and loaded.source == path


def test_text_map_of_any_size(tmp_path: Path) -> None:
    grid = np.random.default_rng(5).random((37, 211)) < 0.4
    rows = "\n".join("".join("1" if v else "0" for v in row) for row in grid)
    loaded = load_text_map(write_text(tmp_path / "big.txt", f"37\n211\n{rows}\n"))
    np.testing.assert_array_equal(loaded.occupied, grid)


@pytest.mark.parametrize(
    ("text", "line", "expected"),
    [
        ("", 1, "number of rows"),
        ("three\n4\n", 1, "number of rows"),
        ("0\n4\n", 1, "number of rows"),
        ("3\n-4\n1001\n", 2, "number of columns"),
        ("3\n4\n1001\n0100\n", 5, "row 3 of 3"),
        ("3\n4\n1001\n0100\n0001\n1111\n", 6, "end of the file"),
        ("3\n4\n1001\n010\n0001\n", 4, "4 characters"),
        ("3\n4\n1001\n\n0001\n", 4, "4 characters"),
        ("3\n4\n1001\n0100\n00x1\n", 5, "column 3"),
        ("3\n4\n1001\n0100\n0 01\n", 5, "column 2"),
    ],
)
def test_malformed_text_maps_name_file_and_line(
    tmp_path: Path, text: str, line: int, expected: str
) -> None:
    path = write_text(tmp_path / "broken.txt", text, "\r\n")
    with pytest.raises(MapError) as info:
        load_text_map(path)
    message = str(info.value)
    assert "broken.txt" in message and f"line {line}:" in message and expected in message


def test_missing_or_binary_text_map(tmp_path: Path) -> None:
    with pytest.raises(MapError, match="does not exist"):
        load_text_map(tmp_path / "nope.txt")
    (tmp_path / "binary.txt").write_bytes(b"\xff\xfe\x00\x81")
    with pytest.raises(MapError, match=r"binary\.txt"):
        load_text_map(tmp_path / "binary.txt")


# --- ROS maps -------------------------------------------------------------------------

ROS_PIXELS = np.array([[254, 0, 205, 254], [254, 100, 160, 255]], np.uint8)


def write_ros(tmp_path: Path, extra: str = "", image: str = "warehouse.pgm") -> Path:
    Image.fromarray(ROS_PIXELS).save(tmp_path / "warehouse.pgm")
    yaml_path = tmp_path / "warehouse.yaml"
    yaml_path.write_text(
        f"image: {image}\nresolution: 0.05\norigin: [-7.5, -5.0, 0.0]\n"
        "occupied_thresh: 0.65\nfree_thresh: 0.196\n" + extra
    )
    return yaml_path


def test_ros_map_trinary_with_unknown_as_obstacle(tmp_path: Path) -> None:
    loaded = load_ros_map(write_ros(tmp_path, "negate: 0\n"))
    # p = (255 - v) / 255: 254 free, 0 occupied, 205 unknown, 100 unknown, 160 unknown.
    assert loaded.occupied.tolist() == [[False, True, True, False], [False, True, True, False]]
    assert loaded.resolution == 0.05
    assert loaded.origin == (-7.5, -5.0, 0.0)
    assert loaded.source == tmp_path / "warehouse.yaml"


def test_ros_map_negate_flips_darkness(tmp_path: Path) -> None:
    loaded = load_ros_map(write_ros(tmp_path, "negate: 1\n"))
    # p = v / 255: only the black pixel (0) is free, 100 -> 0.39 unknown.
    assert loaded.occupied.tolist() == [[True, False, True, True], [True, True, True, True]]


def test_ros_map_free_threshold_decides_what_is_free(tmp_path: Path) -> None:
    yaml_path = write_ros(tmp_path)
    yaml_path.write_text(yaml_path.read_text().replace("free_thresh: 0.196", "free_thresh: 0.4"))
    loaded = load_ros_map(yaml_path)
    assert loaded.occupied.tolist() == [[False, True, False, False], [False, True, False, False]]


def test_ros_map_scale_mode_treats_transparent_pixels_as_unknown(tmp_path: Path) -> None:
    rgba = np.full((1, 2, 4), 254, np.uint8)
    rgba[0, :, 3] = [255, 0]
    Image.fromarray(rgba).save(tmp_path / "alpha.png")
    (tmp_path / "m.yaml").write_text("image: alpha.png\nresolution: 1\nmode: scale\n")
    assert load_ros_map(tmp_path / "m.yaml").occupied.tolist() == [[False, True]]
    (tmp_path / "m.yaml").write_text("image: alpha.png\nresolution: 1\nmode: trinary\n")
    assert load_ros_map(tmp_path / "m.yaml").occupied.tolist() == [[False, False]]


def test_ros_map_raw_mode_reads_values_as_percent(tmp_path: Path) -> None:
    Image.fromarray(np.array([[0, 10, 50, 100, 255]], np.uint8)).save(tmp_path / "raw.pgm")
    (tmp_path / "raw.yaml").write_text("image: raw.pgm\nresolution: 0.1\nmode: raw\n")
    loaded = load_ros_map(tmp_path / "raw.yaml")
    assert loaded.occupied.tolist() == [[False, False, True, True, True]]
    assert loaded.origin is None


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        ("negate: 2\n", "'negate' must be 0 or 1"),
        ("mode: fuzzy\n", "'mode' must be one of"),
        ("free_thresh: 0.9\n", "free_thresh <= occupied_thresh"),
    ],
)
def test_ros_map_bad_settings(tmp_path: Path, extra: str, message: str) -> None:
    yaml_path = write_ros(tmp_path)
    text = yaml_path.read_text().replace("free_thresh: 0.196\n", "")
    yaml_path.write_text(text + extra)
    with pytest.raises(MapError, match=message):
        load_ros_map(yaml_path)


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("image: w.pgm\norigin: [0, 0, 0]\n", "no 'resolution' key"),
        ("image: w.pgm\nresolution: fine\n", "'resolution' must be a number"),
        ("image: w.pgm\nresolution: -1\n", "metres per cell from"),
        ("image: w.pgm\nresolution: 1\norigin: [0]\n", "'origin' must be a list"),
        ("resolution: 1\n", "needs an 'image' key"),
        ("image: [w.pgm\n", "not valid YAML at line"),
        ("- image\n", "not a mapping"),
    ],
)
def test_ros_map_bad_yaml(tmp_path: Path, text: str, message: str) -> None:
    Image.fromarray(ROS_PIXELS).save(tmp_path / "w.pgm")
    (tmp_path / "w.yaml").write_text(text)
    with pytest.raises(MapError, match=message) as info:
        load_ros_map(tmp_path / "w.yaml")
    assert "w.yaml" in str(info.value)


def test_ros_map_missing_image_names_both_files(tmp_path: Path) -> None:
    yaml_path = write_ros(tmp_path, image="gone.pgm")
    with pytest.raises(MapError, match=r"warehouse\.yaml.*gone\.pgm"):
        load_ros_map(yaml_path)
    with pytest.raises(MapError, match="does not exist"):
        load_ros_map(tmp_path / "absent.yaml")


def test_ros_image_is_resolved_relative_to_the_yaml(tmp_path: Path, monkeypatch) -> None:
    (tmp_path / "sub").mkdir()
    yaml_path = write_ros(tmp_path / "sub")
    monkeypatch.chdir(tmp_path)
    assert load_ros_map(Path("sub/warehouse.yaml")).occupied.shape == ROS_PIXELS.shape
    assert load_ros_map(yaml_path).occupied.shape == ROS_PIXELS.shape


# --- dispatch, value type and scenario YAML ------------------------------------------------


def test_load_map_dispatches_on_suffix(tmp_path: Path) -> None:
    text = load_map(write_text(tmp_path / "m.txt", "1\n2\n01\n"))
    assert text.occupied.tolist() == [[False, True]]
    assert load_map(write_ros(tmp_path)).resolution == 0.05
    image = load_map(write_image(tmp_path / "m.png", PATTERN), threshold=0.9, negate=True)
    np.testing.assert_array_equal(image.occupied, PATTERN == 255)


def test_loaded_map_is_frozen(tmp_path: Path) -> None:
    loaded = load_text_map(write_text(tmp_path / "m.txt", "1\n1\n0\n"))
    assert isinstance(loaded, LoadedMap)
    with pytest.raises(dataclasses.FrozenInstanceError):
        loaded.resolution = 1.0  # type: ignore[misc]


def test_read_yaml_mapping_returns_the_mapping(tmp_path: Path) -> None:
    path = tmp_path / "scenario.yaml"
    path.write_text("name: demo\nrobots:\n  count: 3\n")
    assert read_yaml_mapping(path) == {"name": "demo", "robots": {"count": 3}}


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("name: demo\n  robots: 3\n", r"not valid YAML at line 2, column \d+"),
        ("robots: [1, 2\n", "not valid YAML at line"),
        ("", "is empty"),
        ("- a\n- b\n", "a list, not a mapping"),
        ("just text\n", "a str, not a mapping"),
    ],
)
def test_read_yaml_mapping_errors(tmp_path: Path, text: str, message: str) -> None:
    path = tmp_path / "scenario.yaml"
    path.write_text(text)
    with pytest.raises(ScenarioError, match=message) as info:
        read_yaml_mapping(path)
    assert "scenario.yaml" in str(info.value)


def test_read_yaml_mapping_missing_or_not_a_file(tmp_path: Path) -> None:
    with pytest.raises(ScenarioError, match=r"absent\.yaml does not exist"):
        read_yaml_mapping(tmp_path / "absent.yaml")
    with pytest.raises(ScenarioError, match="not a regular file"):
        read_yaml_mapping(tmp_path)
    (tmp_path / "latin.yaml").write_bytes(b"name: caf\xe9\n")
    with pytest.raises(ScenarioError, match="UTF-8"):
        read_yaml_mapping(tmp_path / "latin.yaml")
