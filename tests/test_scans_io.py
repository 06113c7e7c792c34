"""Reading scans: PLY (ascii, binary both byte orders), text x y z, STL (ascii, binary); messages name the place."""

import struct

import numpy as np
import pytest

from hoseline.io import scans
from hoseline.io.scans import ScanFileError, read_scan, write_ply

POINTS = np.random.default_rng(1).normal(size=(30, 3)) * 50.0


def test_binary_ply_round_trip(tmp_path):
    path = write_ply(tmp_path / "scan.ply", POINTS)
    np.testing.assert_array_equal(read_scan(path), POINTS)


def test_ascii_and_big_endian_ply_with_extra_properties(tmp_path):
    header = "ply\nformat {}\nelement vertex 30\nproperty float x\nproperty float y\nproperty float z\n" \
             "property uchar red\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n"
    lines = "".join(f"{x} {y} {z} 7\n" for x, y, z in POINTS)
    (tmp_path / "a.ply").write_text(header.format("ascii 1.0") + lines)
    np.testing.assert_allclose(read_scan(tmp_path / "a.ply"), POINTS, rtol=1e-6)
    record = np.dtype([("x", ">f4"), ("y", ">f4"), ("z", ">f4"), ("red", "u1")])
    table = np.zeros(30, dtype=record)
    table["x"], table["y"], table["z"] = POINTS.T
    (tmp_path / "b.ply").write_bytes(header.format("binary_big_endian 1.0").encode() + table.tobytes())
    np.testing.assert_allclose(read_scan(tmp_path / "b.ply"), POINTS, rtol=1e-6)


def test_text_with_header_commas_and_comments(tmp_path):
    text = "x,y,z\n# exported from the scanner\n" + "".join(f"{x},{y},{z}\n" for x, y, z in POINTS)
    (tmp_path / "scan.csv").write_text(text)
    np.testing.assert_allclose(read_scan(tmp_path / "scan.csv"), POINTS)


def test_stl_vertices_ascii_and_binary_are_merged(tmp_path):
    triangles = POINTS[:30].reshape(10, 3, 3)
    facets = "".join("facet normal 0 0 1\nouter loop\n" + "".join(f"vertex {x} {y} {z}\n" for x, y, z in t)
                     + "endloop\nendfacet\n" for t in np.concatenate([triangles, triangles]))
    (tmp_path / "a.stl").write_text(f"solid hose\n{facets}endsolid hose\n")
    assert read_scan(tmp_path / "a.stl").shape == (30, 3)  # every vertex twice in the file, once in the cloud
    body = b"".join(struct.pack("<12fH", 0, 0, 1, *t.ravel(), 0) for t in triangles.astype(np.float32))
    (tmp_path / "b.stl").write_bytes(b"\0" * 80 + struct.pack("<I", 10) + body)
    np.testing.assert_allclose(np.sort(read_scan(tmp_path / "b.stl"), axis=0), np.sort(POINTS, axis=0), rtol=1e-6)


@pytest.mark.parametrize("name, content, fragments", [
    ("scan.xyz", "1 2 3\n" * 25 + "4 five 6\n", ["line 26", "not three numbers"]),
    ("scan.xyz", "1 2\n", ["line 1", "has 2 numbers"]),
    ("scan.txt", "1 2 3\n", ["only 1 points"]),
    ("scan.xyz", "1 2 3\n" * 25 + "1e308 0 0\n", ["point 25", "beyond +-100000 mm", "in mm"]),
    ("scan.obj", "v 1 2 3\n", ["unknown scan format '.obj'", ".ply"]),
    ("scan.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float u\nend_header\n1\n", ["no x, y, z"]),
    ("scan.ply", "ply\nformat binary_little_endian 1.0\nelement vertex 99\nproperty float x\nproperty float y\n"
                 "property float z\nend_header\n", ["99 vertices", "too short"]),
    ("scan.ply", "ply\nformat ascii 1.0\nelement vertex many\nend_header\n", ["header line 3", "whole number"]),
    ("scan.ply", "ply\nformat\nelement vertex 1\nend_header\n", ["header line 2", "incomplete"]),
    ("scan.ply", "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\n"
                 "end_header\n1 2 3\n4 5\n", ["line 9", "'4 5' is not 3 numbers"]),
    ("scan.ply", "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\n"
                 "end_header", ["2 vertices", "fewer lines"]),
])
def test_bad_scans_are_refused_with_the_place_and_the_fix(tmp_path, name, content, fragments):
    (tmp_path / name).write_text(content)
    with pytest.raises(ScanFileError) as error:
        read_scan(tmp_path / name)
    for fragment in fragments:
        assert fragment in str(error.value)


def _no_line_by_line(*args):
    raise AssertionError("read line by line: the fast reader refused a well-formed file")


@pytest.mark.parametrize("name, content, expected", [
    ("a.csv", "\ufeffx;y;z\r\n# units: mm\r\n1;2;3\r\n\r\n4;5;6;7 # with a fourth column\r\n", [[1, 2, 3], [4, 5, 6]]),
    ("b.xyz", "x y z\nmm mm mm\n1\t2\t3\n  -4e1  5.5   6\n", [[1, 2, 3], [-40, 5.5, 6]]),
    ("c.txt", "1, 2, 3\n4,5 ,6\n", [[1, 2, 3], [4, 5, 6]]),
])
def test_well_formed_text_is_read_without_the_line_by_line_reader(tmp_path, monkeypatch, name, content, expected):
    monkeypatch.setattr(scans, "_read_text_lines", _no_line_by_line)
    (tmp_path / name).write_bytes(content.encode())
    np.testing.assert_array_equal(read_scan(tmp_path / name, min_points=1), expected)


def test_text_is_read_exactly_and_mixed_separators_line_by_line(tmp_path, monkeypatch):
    (tmp_path / "mixed.xyz").write_text("1 2 3\n4,5;6\n" * 15)
    np.testing.assert_array_equal(read_scan(tmp_path / "mixed.xyz"), [[1, 2, 3], [4, 5, 6]] * 15)
    monkeypatch.setattr(scans, "_read_text_lines", _no_line_by_line)
    (tmp_path / "exact.xyz").write_text("".join(f"{x!r} {y!r} {z!r}\n" for x, y, z in POINTS.tolist()))
    np.testing.assert_array_equal(read_scan(tmp_path / "exact.xyz"), POINTS)  # every digit, as Python reads it


def test_large_binary_and_ascii_ply_with_faces_after_the_vertices(tmp_path, monkeypatch):
    points = np.random.default_rng(2).normal(size=(100_000, 3)).astype(np.float32) * 100.0
    header = ("ply\nformat {}\ncomment scanner export\nelement vertex 100000\nproperty float x\nproperty float y\n"
              "property float z\nproperty uchar intensity\nelement face 2\nproperty list uchar int vertex_indices\n"
              "end_header\n")
    record = np.dtype([("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("intensity", "u1")])
    table = np.zeros(100_000, dtype=record)
    table["x"], table["y"], table["z"] = points.T
    faces = bytes([3]) + np.array([0, 1, 2], "<i4").tobytes()
    (tmp_path / "b.ply").write_bytes(header.format("binary_little_endian 1.0").encode() + table.tobytes() + faces * 2)
    np.testing.assert_array_equal(read_scan(tmp_path / "b.ply"), points)
    monkeypatch.setattr(scans, "_read_ply_ascii_lines", _no_line_by_line)
    body = "".join(f"{x!r} {y!r} {z!r} 7\r\n" for x, y, z in points.tolist()) + "3 0 1 2\r\n" * 2
    (tmp_path / "a.ply").write_bytes(header.format("ascii 1.0").replace("\n", "\r\n").encode() + body.encode())
    np.testing.assert_array_equal(read_scan(tmp_path / "a.ply"), points)
