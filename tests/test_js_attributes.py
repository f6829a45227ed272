"""The JavaScript decoder (tuckercodec/web/tkc/) on format 1.5's sections, against the Python
decoder, in node: the faces in their given order (ORDER), every attribute (ATTR.n) bit for bit
(float32 UVs indexed per corner, float64 and int32 values with their extremes, NaN payloads and
signed zeros, colours per face, normals per vertex) with its indices, and every face set (FSET),
on the cloth of ../shared/data and a polygon mesh; and the same rule, file for file, on files
whose 1.5 sections are damaged (tests/js/attached.mjs)."""

from __future__ import annotations

import functools
from pathlib import Path
from typing import Any

import numpy as np

import tuckercodec
from tests.support.compressed import Parts
from tests.support.js_decoder import compare_verdicts, python_verdict, run_node
from tests.support.sequences import load_shared_npz, wave_sequence
from tuckercodec import Attribute, FaceSet, MeshSequence
from tuckercodec.format import streams
from tuckercodec.model.attributes import corner_vertices

FRAMES = 8  # enough frames for a real file, few enough for a quick encode


def _special_float64(rng: np.random.Generator, shape: tuple[int, int]) -> np.ndarray:
    """Random float64 values with every kind of bit pattern a value can have: signed zeros,
    infinities, NaNs with payloads and signs, subnormals, the extremes."""
    values = rng.standard_normal(shape) * 10.0 ** rng.integers(-300, 300, size=shape)
    specials = np.array(
        [
            0.0,
            -0.0,
            np.inf,
            -np.inf,
            5e-324,
            -5e-324,
            1.7976931348623157e308,
            -2.2250738585072014e-308,
        ],
        dtype=np.float64,
    )
    flat = values.reshape(-1)
    flat[: specials.size] = specials
    bits = flat.view(np.uint64)
    bits[specials.size : specials.size + 4] = [
        0x7FF8000000000001,
        0xFFF0000000000ABC,
        0x7FF4000000000000,
        0xFFFFFFFFFFFFFFFF,
    ]
    return values


def _special_float32(rng: np.random.Generator, shape: tuple[int, int]) -> np.ndarray:
    values = rng.random(shape).astype(np.float32)
    flat = values.reshape(-1)
    flat.view(np.uint32)[:6] = [
        0x80000000,
        0x7F800001,
        0xFFC00123,
        0x00000001,
        0xFF800000,
        0x7F7FFFFF,
    ]
    return values


def _attributes(
    faces: np.ndarray, vertex_count: int, rng: np.random.Generator, positions: np.ndarray
) -> list[Attribute]:
    """One attribute of each kind, on this mesh."""
    corners = corner_vertices(faces)
    face_count = faces.shape[0]
    # UVs: a row per vertex, projected from the first frame, and a second row for the vertices
    # of a seam, which the corners of every seventh face use: rows in order of first use
    uv_vertex = (positions[:, :2] - positions[:, :2].min(0)).astype(np.float32)
    seam = np.unique(corners[: corners.size // 5 : 3])
    seam_row = np.full(vertex_count, -1)
    seam_row[seam] = vertex_count + np.arange(seam.size)
    uv_table = np.concatenate([uv_vertex, uv_vertex[seam] + np.float32(0.5)])
    corner_face = np.repeat(np.arange(face_count), (faces >= 0).sum(axis=1))
    uv_index = np.where(
        (corner_face % 7 == 0) & (seam_row[corners] >= 0), seam_row[corners], corners
    )
    used, first_use = np.unique(uv_index, return_index=True)
    renumber = np.empty(uv_table.shape[0], dtype=np.int64)
    renumber[used[np.argsort(first_use)]] = np.arange(used.size)
    uv_values = np.empty((used.size, 2), dtype=np.float32)
    uv_values[renumber[used]] = uv_table[used]
    normals = rng.standard_normal((vertex_count, 3)).astype(np.float32)
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    extremes = np.array([[-(2**31)], [2**31 - 1], [0], [-1]], dtype=np.int32)
    ids = rng.integers(-(2**31), 2**31, size=(face_count, 1), dtype=np.int64).astype(np.int32)
    ids[: extremes.shape[0]] = extremes
    palette = _special_float32(rng, (5, 4))
    return [
        Attribute("st", "corner", uv_values, renumber[uv_index], "uv"),
        Attribute("N", "vertex", normals, None, "normal"),
        Attribute("Cd", "face", rng.random((face_count, 3)).astype(np.float32), None, "color"),
        Attribute("rest", "vertex", _special_float64(rng, (vertex_count, 3)), None, "generic"),
        Attribute("id", "face", ids, None, "generic"),
        Attribute(
            "paint", "face", palette, np.asarray(rng.integers(0, 5, size=face_count)), "color"
        ),
        Attribute("weight", "corner", _special_float64(rng, (corners.size, 1)), None, "generic"),
        Attribute(
            "bone", "vertex", extremes.repeat(2, axis=1), rng.integers(0, 4, size=vertex_count)
        ),
        Attribute("crease", "corner", rng.random((3, 2)), rng.integers(0, 3, size=corners.size)),
    ]


def _face_sets(face_count: int, rng: np.random.Generator) -> list[FaceSet]:
    cut = sorted(rng.choice(np.arange(1, face_count), size=2, replace=False))
    return [
        FaceSet("cloth", np.arange(0, cut[0]), "materialBind"),
        FaceSet("trim", np.arange(cut[0], face_count), "materialBind"),
        FaceSet("pinned", np.sort(rng.choice(face_count, face_count // 9, replace=False)), "group"),
        FaceSet("nothing", np.zeros(0, dtype=np.int64), ""),
    ]


@functools.cache
def cloth_with_attributes() -> bytes:
    """The cloth of ../shared/data (or skip), its faces shuffled so that the walk reorders
    them, with an attribute of each kind and face sets, at KG 0.1."""
    vertices, faces = load_shared_npz("cloth-vellum.npz")
    rng = np.random.default_rng(5)
    faces = faces[rng.permutation(faces.shape[0])].astype(np.int64)
    positions = vertices[:FRAMES].astype(np.float64)
    sequence = MeshSequence(
        positions,
        faces,
        attributes=_attributes(faces, positions.shape[1], rng, positions[0]),
        face_sets=_face_sets(faces.shape[0], rng),
    )
    return tuckercodec.encode(sequence, target_kg=0.1)


@functools.cache
def polygons_with_attributes() -> bytes:
    """A sheet of quads and triangles (rows padded with -1), with attributes and face sets."""
    grid = 9
    positions = wave_sequence(frames=FRAMES, grid=grid)
    rows = []
    for y in range(grid - 1):
        for x in range(grid - 1):
            a, b, c, d = y * grid + x, y * grid + x + 1, (y + 1) * grid + x + 1, (y + 1) * grid + x
            rows += [[a, b, c, -1], [a, c, d, -1]] if (x + y) % 3 == 0 else [[a, b, c, d]]
    faces = np.array(rows, dtype=np.int64)
    rng = np.random.default_rng(8)
    sequence = MeshSequence(
        positions,
        faces,
        attributes=_attributes(faces, positions.shape[1], rng, positions[0]),
        face_sets=_face_sets(faces.shape[0], rng),
    )
    return tuckercodec.encode(sequence, target_kg=0.1)


def _js_attached(data: bytes, tmp_path: Path, name: str = "in") -> tuple[dict[str, Any], bytes]:
    source, output = tmp_path / f"{name}.tkc", tmp_path / f"{name}.bin"
    source.write_bytes(data)
    result = run_node("attached.mjs", source, output)
    assert not result.get("crashed"), result["message"]
    return result, output.read_bytes() if result["accepted"] else b""


TYPES: dict[str, np.dtype[Any]] = {
    "f32": np.dtype("<f4"),
    "f64": np.dtype("<f8"),
    "i32": np.dtype("<i4"),
}


def _check_same_as_python(data: bytes, tmp_path: Path) -> None:
    facts, raw = _js_attached(data, tmp_path)
    assert facts["accepted"], facts["message"]
    expected = tuckercodec.Decoder(data)
    width = facts["face_width"]
    faces = np.frombuffer(raw[: facts["faces"] * width * 4], "<i4").reshape(-1, width)
    assert np.array_equal(faces, expected.faces)  # the given order, row for row
    assert len(facts["attributes"]) == len(expected.attributes)
    for got, want in zip(facts["attributes"], expected.attributes, strict=True):
        assert (got["name"], got["domain"], got["role"]) == (want.name, want.domain, want.role)
        values = np.frombuffer(
            raw, TYPES[got["type"]], got["rows"] * got["components"], got["values_at"]
        )
        assert values.dtype == want.values.dtype.newbyteorder("<")
        assert values.tobytes() == want.values.tobytes(), f"{want.name}: values differ"
        assert values.size == want.values.size and got["components"] == want.components
        if want.indices is None:
            assert got["indices_at"] is None
        else:
            indices = np.frombuffer(raw, "<u4", got["indices"], got["indices_at"])
            assert np.array_equal(indices, want.indices), f"{want.name}: indices differ"
    assert len(facts["face_sets"]) == len(expected.face_sets)
    for got, face_set in zip(facts["face_sets"], expected.face_sets, strict=True):
        assert (got["name"], got["family"]) == (face_set.name, face_set.family)
        numbers = np.frombuffer(raw, "<u4", got["faces"], got["faces_at"])
        assert np.array_equal(numbers, face_set.faces)


def test_cloth_attributes_bit_for_bit(tmp_path):
    data = cloth_with_attributes()
    container_ids = [s.id for s in tuckercodec.format.container.parse_container(data).sections]
    assert "ORDER" in container_ids  # the walk reordered the shuffled faces: ORDER is tested
    _check_same_as_python(data, tmp_path)


def test_polygon_attributes_bit_for_bit(tmp_path):
    _check_same_as_python(polygons_with_attributes(), tmp_path)


# ------------------------------------------------------------------------------------------
# crafted streams: values no encoder writes, which both decoders must read the same way


def _with_attribute(
    data: bytes, number: int, params: dict[str, Any], streams_: list[np.ndarray]
) -> bytes:
    """The file with ATTR.number's streams replaced by ``streams_`` (int64 values as they are
    coded: the value stream, then the index residuals) and ``params`` changed."""
    parts = Parts(data)
    at = parts.index(f"ATTR.{number}")
    entry, _ = parts.sections[at]
    table, payload = [], b""
    for stream in streams_:
        unsigned = streams.zigzag(stream)
        planes = streams.planes_needed(unsigned)
        packed = streams.compress(streams.to_planes(unsigned, planes))
        table.append([int(stream.size), planes, len(packed)])
        payload += packed
    if len(table) == 1:
        table.append([0, 1, 0])
    parts.sections[at] = ({**entry, **params, "streams": table}, payload)
    return parts.pack()


def test_crafted_streams_same_bits(tmp_path):
    """Stream values beyond the type's width (a 32-bit type keeps the low half, its sign that of
    the whole 64-bit value), running sums that wrap, and index residuals far from prediction."""
    data = polygons_with_attributes()
    rng = np.random.default_rng(21)
    wide = rng.integers(-(2**63), 2**63 - 1, size=255 * 3, dtype=np.int64, endpoint=True)
    wide[:6] = [2**32 - 1, -(2**32), 2**31, -(2**31) - 1, -(2**63), 2**63 - 1]
    cases = []
    shapes = {"f32": (2, 85, 3), "i32": (4, 85, 1), "f64": (3, 81, 3)}
    cases = [
        _with_attribute(
            data, number, {"type": type_name, "predict": predict}, [wide[: rows * cols]]
        )
        for type_name, (number, rows, cols) in shapes.items()
        for predict in (0, 1)
    ]
    # a face-domain index stream whose running sum wraps at 64 bits back into range
    residuals = np.zeros(85, dtype=np.int64)
    residuals[:3] = [2**62, 2**62, -(2**63)]
    palette = rng.integers(-100, 100, 20, dtype=np.int64)
    cases.append(_with_attribute(data, 5, {}, [palette, residuals]))
    for n, case in enumerate(cases):
        python = python_verdict(case)
        if python["accepted"]:
            _check_same_as_python(case, tmp_path)
        else:
            facts, _ = _js_attached(case, tmp_path, f"case{n}")
            assert (facts.get("rule"), facts.get("kind")) == (python["rule"], python["kind"])
    assert sum(python_verdict(c)["accepted"] for c in cases) >= 6  # the values cases decode


# ------------------------------------------------------------------------------------------
# damaged files: the same verdict from both decoders

ATTACHED = ("ORDER", "FSET", "ATTR.")
CASES = 240


def _damaged_value(value: Any, rng: np.random.Generator) -> Any:
    """``value`` changed in type or a little in value, lists at any depth."""
    if isinstance(value, bool):
        return [not value, 1, None][int(rng.integers(3))]
    if isinstance(value, int):
        return [value + 1, value - 1, -1, 0, 9, 2**33, 2**64 - 1, 1.0, True, "1"][
            int(rng.integers(10))
        ]
    if isinstance(value, str):
        return ["", "vertex", "corner", "face", "f64", "i32", "uv", "x" * 300, 7][
            int(rng.integers(9))
        ]
    if isinstance(value, list):
        value = list(value)
        if not value or rng.random() < 0.2:
            return [None, [], [*value, 0], value[:-1]][int(rng.integers(4))]
        at = int(rng.integers(len(value)))
        value[at] = _damaged_value(value[at], rng)
        return value
    return 0


def _damaged(data: bytes, rng: np.random.Generator) -> bytes:
    parts = Parts(data)
    chosen = [n for n, (e, _) in enumerate(parts.sections) if e["id"].startswith(ATTACHED)]
    at = int(rng.choice(chosen))
    entry, payload = parts.sections[at]
    entry = dict(entry)
    kind = int(rng.integers(10))
    if kind < 2 and payload:  # bits of the payload
        damaged = bytearray(payload)
        for _ in range(int(rng.integers(1, 4))):
            damaged[int(rng.integers(len(damaged)))] ^= 1 << int(rng.integers(8))
        payload = bytes(damaged)
    elif kind == 2:  # the table's rules: criticality, codec, numbering
        change = int(rng.integers(4))
        if change == 0:
            entry["critical"] = True
        elif change == 1:
            entry["codec"] = "qmat"
        elif change == 2:
            entry["id"] = "ATTR.12"
        else:  # a field's section without the field before it
            extra = ["FLD.0.U1", "FLD.1", "FLD.0.MEAN"][int(rng.integers(3))]
            parts.sections.append(({"id": extra, "critical": False, "codec": "qmat"}, b""))
            if extra == "FLD.1":
                parts.sections[-1][0]["codec"] = "field"
    else:  # a parameter
        keys = sorted(k for k in entry if k not in ("id", "critical", "codec"))
        key = str(rng.choice(keys))
        if rng.random() < 0.1:
            del entry[key]
        else:
            entry[key] = _damaged_value(entry[key], rng)
    parts.sections[at] = (entry, payload)
    return parts.pack()


def test_damaged_sections_same_verdict(tmp_path):
    rng = np.random.default_rng(31)
    bases = [polygons_with_attributes(), cloth_with_attributes()]
    files = [_damaged(bases[n % 2], rng) for n in range(CASES)]
    differ, zstd_only, verdicts = compare_verdicts(files, tmp_path, _zstd_strictness)
    rules = {verdict.get("rule") for verdict in verdicts}
    assert not differ, f"{len(differ)} of {len(files)} verdicts differ: {differ[:5]}"
    assert len(zstd_only) <= len(files) // 25, f"zstd disagrees too often: {zstd_only}"
    # the damage reaches every rule of the 1.5 sections
    assert {"R42-face-order", "R43-attribute", "R44-face-sets", "R45-field"} <= rules, rules


def _zstd_strictness(python: dict[str, Any], javascript: dict[str, Any]) -> bool:
    """A corrupt Zstandard frame that libzstd takes and fzstd refuses (R29), or the reverse
    (spec/FORMAT.md §6.1 allows both): the decoder that took it may then refuse the integers it
    got, by the section's own rule. Any other difference is a bug."""
    verdicts = [python, javascript]
    refused = [v for v in verdicts if v.get("rule") == "R29-zstd-content-size"]
    others = [v for v in verdicts if v.get("rule") != "R29-zstd-content-size"]
    later = {"R42-face-order", "R43-attribute", "R44-face-sets"}
    return len(refused) == 1 and (others[0]["accepted"] or others[0].get("rule") in later)
