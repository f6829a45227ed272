"""§6.8 Codec faces-traverse: every face table of §6.4 round-trips (faces, corners, orientation
and vertex order kept; face order the walk's), and every broken stream is R39-traversal."""

from __future__ import annotations

import tracemalloc
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tests.support.properties import HYPOTHESIS_SETTINGS
from tests.support.work import lines_run
from tools.bench.faces import closed_fan
from tuckercodec import FormatError, LimitError, load_sequence
from tuckercodec.format import traversal
from tuckercodec.format.faces import decode_faces, encode_face_section, encode_faces
from tuckercodec.format.limits import Limits
from tuckercodec.format.sections import FACES_TRAVERSE
from tuckercodec.model.topology import mesh_edges, mesh_parents

DATA = Path(__file__).resolve().parents[2] / "shared" / "data"


def grid(n: int, quads: bool = False) -> np.ndarray:
    index = np.arange(n * n).reshape(n, n)
    a, b, c, d = index[:-1, :-1], index[1:, :-1], index[1:, 1:], index[:-1, 1:]
    if quads:
        return np.stack([a, b, c, d], -1).reshape(-1, 4)
    return np.concatenate([np.stack([a, b, c], -1), np.stack([a, c, d], -1)]).reshape(-1, 3)


def scrambled(faces: np.ndarray, vertex_count: int, seed: int) -> np.ndarray:
    """The same mesh with its vertices renumbered, its faces shuffled and each face's corners
    rotated (orientation kept): what an arbitrary exporter writes."""
    rng = np.random.default_rng(seed)
    relabel = np.append(rng.permutation(vertex_count), -1)
    out = relabel[faces][rng.permutation(len(faces))]
    for row in out:
        n = int((row >= 0).sum())
        row[:n] = np.roll(row[:n], int(rng.integers(n)))
    return out


def pad(rows: list[list[int]]) -> np.ndarray:
    width = max(len(row) for row in rows)
    return np.array([row + [-1] * (width - len(row)) for row in rows], dtype=np.int64)


def sorted_rows(faces: np.ndarray) -> list[tuple[int, ...]]:
    return sorted(tuple(int(v) for v in row) for row in faces)


def round_trip(faces: np.ndarray, vertex_count: int) -> np.ndarray:
    params, payload, walked = traversal.encode_traversal(faces, vertex_count)
    decoded = traversal.decode_traversal(payload, params, vertex_count, "section FACE")
    assert np.array_equal(decoded, walked)  # the encoder knows the order the decoder gives
    assert decoded.shape == np.asarray(faces).shape
    assert sorted_rows(decoded) == sorted_rows(np.asarray(faces))  # rows exactly, corners kept
    return decoded


TETRAHEDRON = [[0, 2, 1], [0, 1, 3], [1, 2, 3], [2, 0, 3]]


def torus(n: int = 6, m: int = 5) -> np.ndarray:
    """A closed surface with a handle (genus 1)."""
    faces = []
    for i in range(n):
        for j in range(m):
            a, b = i * m + j, ((i + 1) % n) * m + j
            c, d = ((i + 1) % n) * m + (j + 1) % m, i * m + (j + 1) % m
            faces += [[a, b, c], [a, c, d]]
    return np.array(faces)


@pytest.mark.parametrize(
    ("faces", "vertex_count"),
    [
        (grid(6), 36),
        (scrambled(grid(9), 81, 1), 81),
        (scrambled(grid(7, quads=True), 49, 2), 49),
        (np.array(TETRAHEDRON), 4),  # closed, no boundary
        (scrambled(torus(), 30, 3), 30),  # a handle
        (pad([[0, 1, 2], [2, 1, 3, 4], [4, 3, 5, 6, 7], [9, 8, 10]]), 12),  # polygons, isolated
        (np.array([[0, 1, 2], [1, 0, 3], [0, 1, 4], [1, 0, 5]]), 6),  # one edge, four faces
        (np.array([[0, 1, 2], [0, 1, 3], [3, 1, 4]]), 5),  # a face of the other orientation
        (np.array([[0, 1, 2], [0, 3, 4], [0, 5, 6]]), 7),  # faces meeting at one vertex only
        (np.array([[0, 1, 1], [1, 2, 2], [0, 0, 0], [2, 1, 0]]), 3),  # repeated vertices
        (np.array([[0, 1, 2], [0, 1, 2], [2, 1, 0]]), 3),  # the same face twice
        (np.concatenate([grid(4), grid(4) + 16, grid(3) + 40]), 49),  # components
        (np.array([[4, 2, 0]]), 5),
        (np.array([[0, 1, 2, -1], [2, 1, 3, -1]]), 4),  # triangles in a table of width 4
    ],
    ids=lambda value: None if isinstance(value, int) else f"{len(value)}faces",
)
def test_every_face_table_round_trips(faces, vertex_count):
    round_trip(np.asarray(faces, dtype=np.int64), vertex_count)


def test_random_triangle_soups_round_trip():
    """Faces with no structure at all: every tip a NEW or FAR, every gate closed or empty."""
    rng = np.random.default_rng(7)
    for _trial in range(30):
        k = int(rng.integers(3, 12))
        faces = rng.integers(0, k, size=(int(rng.integers(1, 25)), 3))
        round_trip(faces, k)


def test_no_faces():
    empty = np.zeros((0, 3), dtype=np.int64)
    params, payload, walked = traversal.encode_traversal(empty, 5)
    assert walked.shape == (0, 3)
    assert traversal.decode_traversal(payload, params, 5, "FACE").shape == (0, 3)


def test_the_mesh_parents_do_not_depend_on_the_face_order():
    """U1's prediction (§6.2) is made from the decoded faces: the walk's order must give the
    same forest as the input's."""
    faces = scrambled(grid(12), 144, 4)
    decoded = round_trip(faces, 144)
    assert np.array_equal(mesh_parents(decoded, 144), mesh_parents(faces, 144))
    assert np.array_equal(mesh_edges(decoded, 144), mesh_edges(faces, 144))


def test_a_mesh_whose_faces_and_vertices_are_scrambled_costs_far_less_than_faces_delta():
    faces = scrambled(grid(40), 1600, 5)
    codec, _, payload, decoded = encode_face_section(faces, 1600)
    delta_payload = encode_faces(faces)[1]
    assert codec == FACES_TRAVERSE
    assert len(payload) < 0.6 * len(delta_payload)
    assert sorted_rows(decoded) == sorted_rows(faces)


def test_the_encoder_keeps_faces_delta_where_it_is_smaller():
    faces = grid(6)  # rows in order: the deltas are tiny
    codec, params, payload, decoded = encode_face_section(faces, 36)
    assert len(payload) <= len(traversal.encode_traversal(faces, 36)[1])
    if codec != FACES_TRAVERSE:
        assert np.array_equal(decoded, faces)
        assert np.array_equal(decode_faces(payload, params, 36, "FACE"), faces)


# ---------------------------------------------------------------------------- broken streams


def coded(
    ops: list[int],
    vertices: list[int],
    references: list[int] = (),  # type: ignore[assignment]
    degrees: list[int] = (),  # type: ignore[assignment]
    count: int = 1,
    width: int = 3,
    corner_order: int = 0,
) -> tuple[dict[str, Any], bytes]:
    return traversal.pack_streams(
        [list(ops), list(degrees), list(vertices), list(references)], count, width, corner_order, 3
    )


def decode(params: dict[str, Any], payload: bytes, vertex_count: int = 5) -> np.ndarray:
    return traversal.decode_traversal(payload, params, vertex_count, "section FACE")


def test_a_hand_written_stream_decodes_as_the_spec_says():
    """A seed (0, 1, 2); across the gate 2 -> 0 (the last pushed) the face walked (0, 2, 3), its
    first tip NEW, stored with corner 0 of the walk at position 2: (2, 3, 0). The walk ends
    there, at M faces: the gates left are never read."""
    ops = [0, 0, 0, 1 + 8 * 2 + 0]
    params, payload = coded(ops, [0, 0, 0, 0], count=2)
    assert decode(params, payload).tolist() == [[0, 1, 2], [2, 3, 0]]


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"corner_order": 2}, "corner_order"),
        ({"ops": [0, 0, 0, 9 * 8 + 1], "count": 2}, "gate operation"),
        ({"ops": [0, 1, 0]}, "names no vertex"),  # PREV on the seed's second corner
        ({"ops": [1, 0, 0]}, "names no vertex"),  # PREV on a first corner
        ({"ops": [0, 0, 3], "references": [-1]}, "not one seen"),  # FAR to vertex 0 is fine...
        ({"ops": [0, 0, 0], "vertices": [0, 0, -1]}, "outside"),  # ...a NEW one placed is not
        ({"ops": [0, 0, 0], "vertices": [0, 0, 9]}, "outside"),
        ({"ops": [0, 0, 0, 0], "vertices": [0, 0, 0]}, "values left"),
        ({"ops": [0, 0], "vertices": [0, 0]}, "ends early"),
        (
            {
                "ops": [0, 0, 0, 1 + 8 * 3],
                "vertices": [0, 0, 0, 0],
                "degrees": [0, 0],
                "count": 2,
                "width": 4,
            },
            "rotation",
        ),
        ({"degrees": [1]}, "corners in a table of width 3"),
    ],
)
def test_every_broken_walk_is_r39(change, message):
    arguments: dict[str, Any] = {"ops": [0, 0, 0], "vertices": [0, 0, 0]}
    if change.get("references") == [-1]:
        arguments["vertices"] = [0, 0]  # the third corner is FAR: vertex 1 + (-1) = 0
        change = {**change, "references": [5]}  # 1 + 5 = 6: not a vertex seen
    arguments.update(change)
    params, payload = coded(**arguments)
    with pytest.raises(FormatError, match=message) as raised:
        decode(params, payload)
    assert raised.value.rule == "R39-traversal"


@pytest.mark.parametrize("value", [1.0, 0.0, True, None])
def test_corner_order_is_an_int(value):
    """§1: an int is never a float, even 1.0 (the JavaScript decoder found this let through)."""
    params, payload = coded([0, 0, 0], [0, 0, 0])
    params["corner_order"] = value
    with pytest.raises(FormatError, match="corner_order") as raised:
        decode(params, payload)
    assert raised.value.rule == "R39-traversal"


@pytest.mark.parametrize(
    "streams",
    [None, [], [[1, 1, 1]] * 3, [[1, 1, 1]] * 3 + [[1, 1]], [[True, 1, 1]] * 4, [[99, 1, 9]] * 4],
)
def test_a_broken_stream_table_is_r39(streams):
    params, payload = coded([0, 0, 0], [0, 0, 0])
    params["streams"] = streams
    with pytest.raises(FormatError) as raised:
        decode(params, payload)
    assert raised.value.rule == "R39-traversal"


def test_bytes_after_the_streams_are_r39():
    params, payload = coded([0, 0, 0], [0, 0, 0])
    with pytest.raises(FormatError, match="bytes of a") as raised:
        decode(params, payload + b"\0")
    assert raised.value.rule == "R39-traversal"


def test_random_damage_to_a_real_walk_is_always_a_format_error():
    faces = scrambled(grid(10, quads=True), 100, 6)
    params, payload, _ = traversal.encode_traversal(faces, 100)
    rng = np.random.default_rng(8)
    for _ in range(150):
        count, corners = faces.shape
        values, corner_order = traversal.read_streams(payload, params, count, corners, 100, "FACE")
        stream = int(rng.integers(4))
        if not values[stream]:
            continue
        position = int(rng.integers(len(values[stream])))
        values[stream][position] += int(rng.choice([-2, -1, 1, 2, 7]))
        broken, data = traversal.pack_streams(values, count, corners, corner_order, 1)
        rule = None
        try:
            decoded = traversal.decode_traversal(data, broken, 100, "FACE")
        except FormatError as error:
            rule = error.rule
        if rule is None:  # a change the walk can absorb still gives a valid table
            assert decoded.shape == faces.shape
            assert ((decoded >= -1) & (decoded < 100)).all()
        else:
            assert rule == "R39-traversal"


def _walked(values: list[list[int]], params: dict[str, Any], k: int, fast: bool) -> object:
    """The faces one of the two walks decodes from ``values``, or its error."""
    (count, width), corner_order = params["shape"], params["corner_order"]
    arrays = [np.array(stream, dtype=np.int64) for stream in values]
    try:
        if fast:
            faces = traversal._walk_triangles(arrays, count, width, k, corner_order, "FACE")
            return faces.tolist()
        rows = traversal._walk(values, count, width, k, corner_order, "FACE")
        return traversal._padded(rows, count, width).tolist()
    except StopIteration:
        return "a stream ends early"
    except FormatError as error:
        return error.rule, str(error)


TRIANGLE_TABLES = [
    (scrambled(grid(9), 81, 1), 81),
    (np.array(TETRAHEDRON), 4),
    (scrambled(torus(), 30, 3), 30),
    (np.array([[0, 1, 2], [1, 0, 3], [0, 1, 4], [1, 0, 5]]), 6),
    (np.array([[0, 1, 2], [0, 1, 3], [3, 1, 4]]), 5),
    (np.array([[0, 1, 1], [1, 2, 2], [0, 0, 0], [2, 1, 0]]), 3),
    (np.array([[0, 1, 2], [0, 1, 2], [2, 1, 0]]), 3),
    (np.concatenate([grid(4), grid(4) + 16, grid(3) + 40]), 49),
    (np.array([[0, 1, 2, -1], [2, 1, 3, -1]]), 4),
]


@pytest.mark.parametrize("corner_order", [0, 1])
def test_the_triangle_walk_decodes_what_the_general_walk_decodes(corner_order):
    """decode_traversal walks a table of triangles with _walk_triangles, which must give the
    faces of _walk, the reference that holds every case of §6.8, on every stream of triangles:
    whole, and damaged (then the same error, or the same faces where the walk absorbs it)."""
    rng = np.random.default_rng(11)
    tables = TRIANGLE_TABLES + [
        (rng.integers(0, k, size=(int(rng.integers(1, 25)), 3)), k)
        for k in rng.integers(3, 12, size=20).tolist()
    ]
    outcomes = set()
    for faces, k in tables:
        walk = traversal._Walk([[v for v in row if v >= 0] for row in faces.tolist()], k)
        values = [walk.ops_for(corner_order), [], walk.new_residuals, walk.references]
        params = {"shape": list(faces.shape), "corner_order": corner_order}
        assert _walked(values, params, k, True) == _walked(values, params, k, False)
        for _ in range(40):
            broken = [list(stream) for stream in values]
            stream = int(rng.choice([0, 0, 2, 3]))
            if not broken[stream]:
                continue
            position = int(rng.integers(len(broken[stream])))
            change = int(rng.integers(4))
            if change == 0:
                broken[stream][position] += int(rng.choice([-2, -1, 1, 2, 4, 8, 24]))
            elif change == 1:
                broken[stream][position] = int(rng.integers(-3, 27))
            elif change == 2:
                del broken[stream][position]
            else:
                broken[stream].insert(position, int(rng.integers(-2, 9)))
            fast = _walked(broken, params, k, True)
            assert fast == _walked(broken, params, k, False)
            outcomes.add(fast[1].split("breaks: ")[-1][:12] if isinstance(fast, tuple) else "ok")
    assert len(outcomes) >= 7, outcomes  # faces, and many kinds of failure, were met


@pytest.mark.skipif(not (DATA / "chicken.npz").exists(), reason=f"{DATA} is absent")
@pytest.mark.parametrize("name", ["chicken.npz", "cloth-vellum.npz", "horse-gallop"])
def test_the_shared_meshes_round_trip_and_shrink(name):
    sequence = load_sequence(DATA / name)
    k = sequence.vertex_count
    _params, payload, _ = traversal.encode_traversal(sequence.faces, k)
    round_trip(sequence.faces, k)
    assert len(payload) < 0.5 * len(encode_faces(sequence.faces)[1])
    assert len(payload) * 8 / k < 21  # bits per vertex, vertex order kept (today 10.5-20)


def test_a_huge_vertex_count_in_the_header_allocates_nothing_by_it():
    """K is only the header's claim when FACE is decoded: the walk's tables grow with the
    vertices it meets, so a tiny section claiming 2**26 vertices decodes at once."""
    faces = scrambled(grid(4), 16, 9)
    params, payload, walked = traversal.encode_traversal(faces, 16)
    decoded = traversal.decode_traversal(payload, params, 2**26, "section FACE")
    assert decoded.tolist() == walked.tolist()


# ------------------------------------------------------------------ the streams' declared counts


def _declared(table: list[list[int]], count: int = 2, width: int = 3, vertices: int = 5):
    """Parameters declaring ``table`` over a payload of the lengths it gives, which is not even
    zstd: a check made on the parameters fails before any stream is decompressed (R29)."""
    params = {"shape": [count, width], "corner_order": 0, "streams": table}
    payload = b"\xff" * sum(entry[2] for entry in table)
    return params, payload, vertices


@pytest.mark.parametrize(
    ("table", "field"),
    [
        ([[6, 1, 9], [1, 1, 9], [3, 1, 9], [0, 1, 9]], "degrees"),  # neither 0 nor M = 2
        ([[6, 1, 9], [3, 1, 9], [3, 1, 9], [0, 1, 9]], "degrees"),
        ([[1, 1, 9], [0, 1, 9], [3, 1, 9], [0, 1, 9]], "ops"),  # fewer than one per face
        ([[13, 1, 9], [0, 1, 9], [3, 1, 9], [0, 1, 9]], "ops"),  # 2 * M * 3 = 12 (triangles)
        ([[6, 1, 9], [0, 1, 9], [6, 1, 9], [0, 1, 9]], "vertices"),  # more NEW than K = 5
        ([[6, 1, 9], [0, 1, 9], [4, 1, 9], [3, 1, 9]], "references"),  # 4 + 3 > M * 3
        ([[6, 1, 9], [0, 1, 9], [0, 1, 9], [7, 1, 9]], "references"),
        ([[2**70, 1, 9], [0, 1, 9], [3, 1, 9], [0, 1, 9]], "ops"),
    ],
)
def test_a_count_beyond_its_bound_is_r39_before_any_stream_is_read(table, field):
    params, payload, vertices = _declared(table)
    with pytest.raises(FormatError, match=r"\(§6\.8\)") as raised:
        traversal.decode_traversal(payload, params, vertices, "FACE")
    assert raised.value.rule == "R39-traversal"
    assert raised.value.field == f"FACE.streams.{field}"


@pytest.mark.parametrize(
    "table",
    [
        [[2, 1, 9], [0, 1, 9], [0, 1, 9], [0, 1, 9]],  # M ops
        [[12, 1, 9], [0, 1, 9], [5, 1, 9], [1, 1, 9]],  # 2 * M * 3 ops, 5 + 1 = M * 3
        [[16, 1, 9], [2, 1, 9], [5, 1, 9], [3, 1, 9]],  # polygons of width 4: 2 * M * 4 ops
    ],
    ids=["least-ops", "most-triangles", "most-polygons"],
)
def test_counts_at_their_bounds_pass_to_the_streams(table):
    """The bounds are inclusive: such a table is refused only by its (garbage) streams."""
    params, payload, vertices = _declared(table, width=4 if table[1][0] else 3)
    with pytest.raises(FormatError) as raised:
        traversal.decode_traversal(payload, params, vertices, "FACE")
    assert raised.value.rule == "R29-zstd-content-size"


def test_streams_beyond_max_section_bytes_are_a_limit_error_before_decompression():
    """Σ count * planes is the bytes the streams decompress to: a decoder limit (§7, R21),
    checked after the planes (R30) and before any frame is read."""
    params, payload, vertices = _declared([[10, 4, 9], [0, 1, 9], [3, 2, 9], [1, 3, 9]])
    small = Limits(max_section_bytes=48)  # one below 40 + 0 + 6 + 3
    with pytest.raises(LimitError, match="max_section_bytes") as limit:
        traversal.decode_traversal(payload, params, vertices, "FACE", small)
    assert (limit.value.rule, limit.value.field) == ("R21-header-limit", "FACE.streams")
    with pytest.raises(FormatError) as raised:  # at the limit: on to the streams
        traversal.decode_traversal(payload, params, vertices, "FACE", Limits(max_section_bytes=49))
    assert raised.value.rule == "R29-zstd-content-size"
    params["streams"][3][1] = 5  # a planes out of range is R30, before the sum
    with pytest.raises(FormatError) as raised:
        traversal.decode_traversal(payload, params, vertices, "FACE", small)
    assert raised.value.rule == "R30-planes"


def test_a_small_file_declaring_huge_streams_is_refused_without_allocating_them():
    """2**28 faces and 6 * 2**28 ops of 4 planes: within max_faces, max_section_bytes for the
    table, and §6.8's bounds, but 6 GiB of streams; refused as R21 before a byte of it exists
    (the payload is the few bytes of a real file's streams)."""
    faces = scrambled(grid(5), 25, 10)
    params, payload, _ = traversal.encode_traversal(faces, 25)
    table = [list(entry) for entry in params["streams"]]
    table[0] = [6 << 28, 4, table[0][2]]
    huge = {**params, "shape": [1 << 28, 3], "streams": table}
    tracemalloc.start()
    try:
        with pytest.raises(LimitError) as raised:
            traversal.decode_traversal(payload, huge, 1 << 26, "FACE")
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert raised.value.rule == "R21-header-limit"
    assert peak < 1 << 20


# ----------------------------------------------------------------- the encoder's gate search


class _SpecWalk(traversal._Walk):
    """The encoder's walk with its gate search as §6.8 writes it (informative): every face in
    the input's order, the first unvisited one with the corners b, a, else a, b."""

    def _across(self, a: int, b: int) -> tuple[int, int, int] | None:
        for first, second, kind in ((b, a, traversal.GATE_FACE), (a, b, traversal.GATE_FLIP)):
            for f, row in enumerate(self.rows):
                n = len(row)
                for j in range(n):
                    if not self.done[f] and row[j] == first and row[(j + 1) % n] == second:
                        return f, j, kind
        return None


def _walk_streams(walk: traversal._Walk) -> tuple[list[int], ...]:
    return (walk.ops_for(0), walk.ops_for(1), walk.degrees, walk.new_residuals, walk.references)


def fan(count: int, alternating: bool = False) -> np.ndarray:
    """``count`` triangles (0, 1, v) on the edge 0-1, every other one turned over if asked."""
    tips = np.arange(2, count + 2)
    faces = np.stack([np.zeros_like(tips), np.ones_like(tips), tips], axis=1)
    if alternating:
        faces[1::2, :2] = faces[1::2, 1::-1]
    return faces


@settings(max_examples=300, **HYPOTHESIS_SETTINGS)
@given(
    st.integers(2, 9).flatmap(
        lambda k: st.tuples(
            st.just(k),
            st.lists(st.lists(st.integers(0, k - 1), min_size=3, max_size=5), max_size=30),
        )
    )
)
def test_the_gate_search_picks_the_face_the_spec_names(mesh):
    """Soups of faces of 3 to 5 corners on a few vertices: edges of many faces in both
    orientations, repeated vertices and faces. The walk is the one of §6.8's plain search."""
    k, rows = mesh
    assert _walk_streams(traversal._Walk(rows, k)) == _walk_streams(_SpecWalk(rows, k))
    assert traversal._Walk(rows, k).order == _SpecWalk(rows, k).order


@pytest.mark.parametrize("alternating", [False, True], ids=["same", "alternating"])
def test_the_gate_search_is_linear_on_an_edge_of_many_faces(alternating):
    """Work counted in lines of traversal.py run, not seconds: a fan of 10,000 faces on one edge
    runs about ten times the lines of a fan of 1,000 (a search from the front each time ran 50
    times as many; the trace stops such a run once it is past the budget)."""
    small = lines_run(
        lambda: traversal.encode_traversal(fan(1000, alternating), 1002),
        [traversal.__file__],
        10**7,
    )
    large = lines_run(
        lambda: traversal.encode_traversal(fan(10000, alternating), 10002),
        [traversal.__file__],
        15 * small,
    )
    assert large <= 11 * small


def test_reading_the_newest_edge_after_many_were_closed_is_linear():
    """into(0) read 1,000 and 10,000 times after as many entries behind its oldest were closed
    (tools.bench.faces.closed_fan): the faces come out, and the decoder runs about ten times
    the lines of traversal.py. The lines do not count C: the ordered dicts used before passed over
    the closed entries inside dict iteration (4 * 160,000 faces took 56 s); python -m tools.bench
    faces times that."""
    small, large = (_closed_fan_lines(count) for count in (1000, 10000))
    assert large <= 11 * small


def _closed_fan_lines(count: int) -> int:
    params, payload, k = closed_fan(count)
    decoded: list[np.ndarray] = []
    lines = lines_run(
        lambda: decoded.append(traversal.decode_traversal(payload, params, k, "FACE")),
        [traversal.__file__],
        10**8,
    )
    assert decoded[0][-1].tolist() == [count + 1, 0, 1]  # the last read found 1
    return lines
