"""TKCLoader (tuckercodec/web/three/) on files with attributes and face sets (format 1.5), in node
with the three.js the viewer vendors: every triangle corner shows its face corner's UV, colour
and position (a vertex is split where its corners' values differ, and each copy follows its
vertex frame by frame), authored normals are shown on a single frame and keep their hard
edges when recomputed, and each material's faces are one group (tests/js/loader_attributes.mjs).
"""

from __future__ import annotations

import base64
import functools
import json
import subprocess
from pathlib import Path
from typing import Any

import numpy as np

import tuckercodec
from tests.support.js_decoder import JS, RUN_TIMEOUT, node
from tests.support.sequences import wave_sequence
from tuckercodec import Attribute, FaceSet, MeshSequence
from tuckercodec.model.attributes import corner_faces, corner_vertices, face_corner_starts

GRID = 7


def _sheet() -> np.ndarray:
    """A sheet of quads and triangles, rows padded with -1."""
    rows = []
    for y in range(GRID - 1):
        for x in range(GRID - 1):
            a, b = y * GRID + x, y * GRID + x + 1
            c, d = (y + 1) * GRID + x + 1, (y + 1) * GRID + x
            rows += [[a, b, c, -1], [a, c, d, -1]] if (x + y) % 3 == 0 else [[a, b, c, d]]
    return np.array(rows, dtype=np.int64)


def _sequence(frames: int) -> MeshSequence:
    """The sheet with UVs per corner (a seam down the middle), normals per corner with a hard
    edge along the same column, a colour per face, and two materials that leave faces unbound."""
    faces = _sheet()
    positions = wave_sequence(frames=frames, grid=GRID)
    corners = corner_vertices(faces)
    face_of = corner_faces(faces)
    column = corners % GRID
    # the faces left of column 3 use a second UV (and normal) row for the vertices on it
    face_left = np.array([max(v % GRID for v in row if v >= 0) <= 3 for row in faces])
    seam = (column == 3) & face_left[face_of]
    uv_rows = np.concatenate([positions[0, :, :2], positions[0, 3::GRID, :2] + 0.5])
    uv_rows = uv_rows.astype(np.float32)
    uv_index = np.where(seam, GRID * GRID + corners // GRID, corners)
    normal_rows = np.concatenate(
        [np.tile([[0.0, 0.0, 1.0]], (GRID * GRID, 1)), np.tile([[1.0, 0.0, 0.0]], (GRID, 1))]
    ).astype(np.float32)
    rng = np.random.default_rng(3)
    count = faces.shape[0]
    return MeshSequence(
        positions,
        faces,
        attributes=[
            Attribute("st", "corner", uv_rows, uv_index, "uv"),
            Attribute("N", "corner", normal_rows, uv_index, "normal"),
            Attribute("Cd", "face", rng.random((count, 3)).astype(np.float32), None, "color"),
        ],
        face_sets=[
            FaceSet("wood", np.arange(0, count // 3), "materialBind"),
            FaceSet("part", np.arange(0, count, 2), "group"),
            FaceSet("steel", np.arange(count // 2, count), "materialBind"),
        ],
    )


@functools.cache
def _file(frames: int) -> bytes:
    return tuckercodec.encode(_sequence(frames), target_kg=0.1)


def _load(tmp_path: Path, data: bytes, frame: int) -> dict[str, Any]:
    path = tmp_path / "in.tkc"
    path.write_bytes(data)
    done = subprocess.run(
        [
            node(),
            "--import",
            "./three_from_vendor.mjs",
            "loader_attributes.mjs",
            str(path),
            str(frame),
        ],
        cwd=JS,
        capture_output=True,
        text=True,
        timeout=RUN_TIMEOUT,
        check=False,
    )
    assert done.returncode == 0, f"loader_attributes.mjs failed:\n{done.stderr[-3000:]}"
    return json.loads(done.stdout)


def _array(text: str, dtype: str, width: int = 1) -> np.ndarray:
    values = np.frombuffer(base64.b64decode(text), dtype)
    return values.reshape(-1, width) if width > 1 else values


def _expected_corners(decoder: tuckercodec.Decoder) -> tuple[np.ndarray, list[int]]:
    """The corner (in corner order) of every triangle corner TKCLoader draws: the faces fanned,
    the faces of each materialBind set in turn, then the faces of none; and each group's size
    in triangles."""
    faces = decoder.faces
    starts = face_corner_starts(faces)
    materials = [s for s in decoder.face_sets if s.family == "materialBind"]
    material = np.full(faces.shape[0], len(materials))
    for number in reversed(range(len(materials))):
        material[materials[number].faces] = number
    corners, sizes = [], []
    for number in range(len(materials) + 1):
        chosen = np.flatnonzero(material == number)
        for face in chosen:
            first = int(starts[face])
            for j in range(first + 1, int(starts[face + 1]) - 1):
                corners += [first, j, j + 1]
        sizes.append(int(sum(starts[f + 1] - starts[f] - 2 for f in chosen)))
    return np.array(corners), sizes


def test_every_corner_shows_its_values(tmp_path):
    data = _file(6)
    decoder = tuckercodec.Decoder(data)
    got = _load(tmp_path, data, 4)
    index = _array(got["index"], "<u4")
    corners, sizes = _expected_corners(decoder)
    assert index.size == corners.size
    vertex_of = _array(got["vertexOf"], "<u4")
    faces = decoder.faces
    assert np.array_equal(vertex_of[index], corner_vertices(faces)[corners])
    uv = {a.name: a for a in decoder.attributes}["st"]
    drawn_uv = _array(got["attributes"]["uv"]["array"], "<f4", 2)
    assert drawn_uv.tobytes() != b"" and vertex_of.size > decoder.info.vertices  # split
    assert uv.indices is not None
    assert np.array_equal(drawn_uv[index], uv.values[uv.indices[corners]])
    colour = {a.name: a for a in decoder.attributes}["Cd"]
    drawn_colour = _array(got["attributes"]["color"]["array"], "<f4", 3)
    assert np.array_equal(drawn_colour[index], colour.values[corner_faces(faces)[corners]])
    assert got["vertexColors"] is True
    # each drawn vertex at its file vertex's position in the frame, which is the Python one's
    frame = _array(got["frame"], "<f4", 3)
    positions = _array(got["attributes"]["position"]["array"], "<f4", 3)
    assert np.array_equal(positions, frame[vertex_of])
    assert np.abs(frame - decoder.frame(4)).max() <= 1e-6 * np.abs(decoder.frame(4)).max()
    # a group per material, then the faces of none
    assert got["materialNames"] == ["wood", "steel", None]
    starts = np.cumsum([0, *sizes])
    expected = [
        {"start": 3 * int(starts[m]), "count": 3 * sizes[m], "materialIndex": m}
        for m in range(3)
        if sizes[m]
    ]
    assert got["groups"] == expected


def test_recomputed_normals_keep_the_hard_edges(tmp_path):
    data = _file(6)
    decoder = tuckercodec.Decoder(data)
    got = _load(tmp_path, data, 2)
    assert got["updateNormals"] is True
    index = _array(got["index"], "<u4")
    corners, _ = _expected_corners(decoder)
    normals = _array(got["attributes"]["normal"]["array"], "<f4", 3)
    assert np.allclose(np.linalg.norm(normals, axis=1), 1, atol=1e-5)
    authored = {a.name: a for a in decoder.attributes}["N"]
    assert authored.indices is not None
    rows = authored.indices[corners]
    vertices = corner_vertices(decoder.faces)[corners]
    # two corners of one vertex share a normal exactly when their authored rows are the same
    drawn = normals[index]
    for vertex in np.unique(vertices):
        at = np.flatnonzero(vertices == vertex)
        for other in at[1:]:
            same_row = rows[other] == rows[at[0]]
            assert np.array_equal(drawn[other], drawn[at[0]]) == same_row, vertex


def test_a_single_frame_shows_the_authored_normals(tmp_path):
    data = _file(1)
    decoder = tuckercodec.Decoder(data)
    got = _load(tmp_path, data, 0)
    assert got["updateNormals"] is False
    index = _array(got["index"], "<u4")
    corners, _ = _expected_corners(decoder)
    authored = {a.name: a for a in decoder.attributes}["N"]
    normals = _array(got["attributes"]["normal"]["array"], "<f4", 3)
    assert authored.indices is not None
    assert np.array_equal(normals[index], authored.values[authored.indices[corners]])


def test_a_file_without_attributes_draws_its_own_vertices(tmp_path):
    sequence = _sequence(4)
    plain = MeshSequence(sequence.vertices, sequence.faces)
    data = tuckercodec.encode(plain, target_kg=0.1)
    got = _load(tmp_path, data, 1)
    assert set(got["attributes"]) == {"position", "normal"}
    assert got["groups"] == [] and got["materialNames"] == []
    vertex_of = _array(got["vertexOf"], "<u4")
    assert np.array_equal(vertex_of, np.arange(sequence.vertex_count))
