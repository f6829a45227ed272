"""The JavaScript decoder's topology.js (U1's mesh prediction, spec §6.2) and traversal.js
(faces-traverse, §6.8) against the Python reference, in node (tests/js/tkc_topology.mjs).

Longer than most test modules (about 590 lines): the cases are built here from the reference
encoder (hand-made face tables, damaged streams and parameters, crafted residuals, real files),
and one node run per group checks them all, so the builders and their checks stay together.

Every case is decoded by both decoders: the faces and the restored integers must be identical,
and a file one rejects the other rejects with the same rule. Nothing may crash with another
error or run long (node runs under a deadline).
"""

from __future__ import annotations

import hashlib
import json
import random
import subprocess
from pathlib import Path
from typing import Any

import msgpack
import numpy as np
import pytest

import tuckercodec
from tests.support.adaptive_files import stored_integers
from tests.support.js_decoder import node
from tests.support.sequences import shared_case, shared_encoded
from tuckercodec import FormatError
from tuckercodec.format import streams, traversal
from tuckercodec.format.container import parse_container
from tuckercodec.format.qmat import decode_matrix
from tuckercodec.io.samples import sample_path
from tuckercodec.model.topology import MeshPrediction, mesh_parents

SCRIPT = Path(__file__).resolve().parent / "js" / "tkc_topology.mjs"
VECTORS = Path(__file__).resolve().parents[1] / "spec" / "vectors"
NODE_SECONDS = 120.0  # a whole group; a walk that loops trips it
DAMAGE_RULES = {"R39-traversal", "R30-planes", "R29-zstd-content-size"}
#: Where the reference differs from the spec (a known leniency of the reference's; the spec is
#: what both decoders must follow): it accepts corner_order 1.0,
#: a msgpack float, as 1, but §6.8 says "an int 0 or 1" and §1 "an int is never a float".
SPEC_OVER_REFERENCE = {"corner-order-float": ("error", "R39-traversal")}


def _sha(array: np.ndarray, dtype: str) -> str:
    return hashlib.sha256(np.ascontiguousarray(array, dtype=dtype).tobytes()).hexdigest()


def _outcome(call: Any, dtype: str) -> tuple[str, str]:
    """("ok", SHA-256 of the result) or ("error", the rule) of a reference call."""
    try:
        return "ok", _sha(call(), dtype)
    except FormatError as error:
        return "error", str(error.rule)


class Cases:
    """Cases written to a folder for one node run, each with the reference's outcome."""

    def __init__(self, folder: Path) -> None:
        self.folder = folder
        self.specs: list[dict[str, Any]] = []
        self.expected: dict[str, tuple[str, str]] = {}

    def _file(self, name: str, data: bytes) -> str:
        file = f"{len(self.specs)}-{name}"
        (self.folder / file).write_bytes(data)
        return file

    def traverse(
        self,
        name: str,
        params: dict[str, Any],
        payload: bytes,
        vertices: int,
        spec: tuple[str, str] | None = None,
        adaptive: bool = False,
        uniform: bool = False,
    ) -> None:
        """A FACE payload with its parameters; the reference is decode_traversal, unless
        ``spec`` gives the outcome the spec requires where the reference is known to differ.
        ``adaptive``: the file sets flag bit 3, so that ``coder`` may be 1 (format 1.6);
        ``uniform``: flag bit 6, so that ``ranks`` is read and may be 1 (format 1.9)."""
        rows, width = params["shape"]
        self.expected[name] = spec or _outcome(
            lambda: traversal.decode_traversal(
                payload,
                params,
                vertices,
                "FACE",
                adaptive_coding=adaptive,
                uniform_ranks=uniform,
            ),
            "<i4",
        )
        entry = {"id": "FACE", "codec": "faces-traverse", **params}
        self.specs.append(
            {
                "kind": "traverse",
                "name": name,
                "entry": self._file("entry", msgpack.packb(entry, use_bin_type=True)),
                "payload": self._file("payload", payload),
                "K": vertices,
                "M": rows,
                "n": width,
                "adaptive": adaptive,
                "uniform": uniform,
            }
        )

    def restore(
        self, name: str, faces: np.ndarray, vertices: int, residuals: np.ndarray, predict: list[int]
    ) -> None:
        """A U1 stream (len(predict) columns of int32 residuals); the reference is decode_matrix."""
        columns = np.asarray(residuals, dtype=np.int64).reshape(len(predict), vertices)
        payload, planes = streams.pack_integers(columns.reshape(-1))
        params = {
            "shape": [vertices, len(predict)],
            "planes": planes,
            "steps": np.ones(len(predict), "<f4").tobytes(),
            "predict": bytes(predict),
        }
        mesh = MeshPrediction(faces, vertices)
        self.expected[name] = _outcome(
            lambda: decode_matrix(payload, params, mesh, "U1", coding_tools=True).q.T, "<f8"
        )
        self._restore_spec(name, faces, vertices, columns.astype("<i4").tobytes(), predict)

    def wide(self, name: str, faces: np.ndarray, vertices: int, residuals: list[int]) -> None:
        """One predictor-1 column whose sums pass 2^53 (residuals as float64: int32 cannot get
        there on a small mesh); the reference is exact Python ints along the parents."""
        parent = mesh_parents(faces, vertices)
        exact: dict[int, int] = {}

        def value(v: int) -> int:
            chain = []
            while v not in exact and v >= 0:
                chain.append(v)
                v = int(parent[v])
            for u in reversed(chain):
                exact[u] = residuals[u] + (exact[int(parent[u])] if parent[u] >= 0 else 0)
            return exact[chain[0]] if chain else exact[v]

        q = np.array([float(value(v)) for v in range(vertices)])  # float(int): ties to even
        self.expected[name] = ("ok", _sha(q, "<f8"))
        data = np.array(residuals, "<f8").tobytes()
        self._restore_spec(name, faces, vertices, data, [1], wide=True)

    def _restore_spec(
        self,
        name: str,
        faces: np.ndarray,
        vertices: int,
        data: bytes,
        predict: list[int],
        **more: Any,
    ) -> None:
        rows, width = faces.shape
        self.specs.append(
            {
                "kind": "restore",
                "name": name,
                "faces": self._file("faces", np.ascontiguousarray(faces, "<i4").tobytes()),
                "K": vertices,
                "M": rows,
                "n": width,
                "residuals": self._file("residuals", data),
                "predict": predict,
                **more,
            }
        )

    def run(self, repeat: int = 1) -> dict[str, dict[str, Any]]:
        """Runs node on every case; returns its results by name."""
        manifest = self.folder / "manifest.json"
        manifest.write_text(json.dumps({"cases": self.specs}))
        done = subprocess.run(
            [node(), str(SCRIPT), str(manifest), "--repeat", str(repeat)],
            capture_output=True,
            text=True,
            timeout=NODE_SECONDS,
            check=False,
        )
        assert done.returncode == 0, f"node {SCRIPT.name} failed:\n{done.stderr[-3000:]}"
        return {result["name"]: result for result in json.loads(done.stdout)}

    def check(self, repeat: int = 1) -> dict[str, dict[str, Any]]:
        """Runs node and asserts every case has the reference's outcome."""
        results = self.run(repeat)
        wrong = []
        for name, (status, value) in self.expected.items():
            got = results[name]
            assert "crash" not in got, f"{name}: crashed: {got['crash']}"
            mine = ("ok", got["sha256"]) if got["accepted"] else ("error", got["rule"])
            if mine != (status, value):
                wrong.append(f"{name}: reference {status} {value}, JavaScript {got}")
        assert not wrong, "\n".join(wrong[:20])
        return results


# --- face tables ------------------------------------------------------------------------------


def _table(rows: list[list[int]], width: int | None = None) -> np.ndarray:
    width = width or max(map(len, rows), default=3)
    table = np.full((len(rows), width), -1, dtype=np.int64)
    for r, row in enumerate(rows):
        table[r, : len(row)] = row
    return table


def _torus(u: int, v: int) -> list[list[int]]:
    rows = []
    for i in range(u):
        for j in range(v):
            a, b = i * v + j, i * v + (j + 1) % v
            c, d = ((i + 1) % u) * v + j, ((i + 1) % u) * v + (j + 1) % v
            rows += [[a, b, d], [a, d, c]]
    return rows


def _strip(vertices: int) -> list[list[int]]:
    """A path 0 - 1 - ... of degenerate triangles: depth vertices - 1."""
    return [[i, i + 1, i + 1] for i in range(vertices - 1)]


def _renumbered(rows: list[list[int]], vertices: int, seed: int) -> list[list[int]]:
    rng = random.Random(seed)
    order = list(range(vertices))
    rng.shuffle(order)
    shuffled = [[order[x] for x in row] for row in rows]
    rng.shuffle(shuffled)
    return shuffled


def _tables() -> dict[str, tuple[np.ndarray, int]]:
    """Hand-made face tables of §6.8's last paragraph: (faces, K)."""
    rng = random.Random(14)
    quads = [
        [i * 6 + j, i * 6 + j + 1, (i + 1) * 6 + j + 1, (i + 1) * 6 + j]
        for i in range(5)
        for j in range(5)
    ]
    polygons = (
        quads[:10]
        + [[30, 31, 32, 33, 34, 35, 0]]
        + [q[:3] for q in quads[10:]]
        + [[5, 11, 17, 23, 29]]
    )
    soup = [rng.sample(range(40), 3) for _ in range(150)]
    tetra = [[0, 1, 2], [0, 3, 1], [1, 3, 2], [0, 2, 3]]
    return {
        "tetrahedron": (_table(tetra), 4),
        "torus": (_table(_torus(8, 11)), 88),
        "torus-renumbered": (_table(_renumbered(_torus(9, 7), 63, 1)), 63),
        "polygons": (_table(polygons, 8), 40),
        "non-manifold-edge": (_table([[0, 1, 2], [1, 0, 3], [0, 1, 4], [4, 1, 5], [1, 0, 6]]), 7),
        "bowtie": (_table([[0, 1, 2], [0, 3, 4], [0, 2, 5], [3, 0, 6]]), 7),
        "repeated-vertex": (
            _table([[0, 1, 1], [0, 1, 2, 1], [2, 2, 2], [1, 3, 2, 3], [0, 2, 3]], 4),
            4,
        ),
        "flipped-and-duplicate": (
            _table([[0, 1, 2], [0, 1, 3], [0, 1, 2], [2, 1, 0], [3, 2, 1]]),
            4,
        ),
        "components-and-isolated": (
            _table(tetra + [[x + 10 for x in row] for row in _torus(4, 5)] + [[40, 42, 41]]),
            45,
        ),
        "soup": (_table(soup), 40),
        "single-face": (_table([[2, 0, 1]]), 3),
        "no-faces": (np.zeros((0, 3), np.int64), 5),
        "wide-rows": (_table([[0, 1, 2], [2, 1, 3]], 9), 4),
    }


# --- traversal --------------------------------------------------------------------------------


def test_traverse_hand_made_tables(tmp_path):
    """Every table decodes to the reference's faces in walk order (which is also what the
    encoder says it wrote), in both corner orders."""
    cases = Cases(tmp_path)
    walked = {}
    for name, (faces, vertices) in _tables().items():
        params, payload, walk = traversal.encode_traversal(faces, vertices)
        cases.traverse(name, params, payload, vertices)
        walked[name] = _sha(walk, "<i4")
        count, corners = faces.shape
        coded, order = traversal.read_streams(payload, params, count, corners, vertices, "FACE")
        other, other_payload = traversal.pack_streams(coded, count, corners, 1 - order, 19)
        cases.traverse(f"{name}-corner-order-{1 - order}", other, other_payload, vertices)
    results = cases.check()
    for name, sha in walked.items():
        assert results[name]["sha256"] == sha, name
    assert {cases.expected[name][0] for name in walked} == {"ok"}


def _base(name: str) -> tuple[list[list[int]], int, int, int, np.ndarray]:
    faces, vertices = _tables()[name]
    params, payload, _ = traversal.encode_traversal(faces, vertices)
    count, corners = faces.shape
    coded, order = traversal.read_streams(payload, params, count, corners, vertices, "FACE")
    return coded, order, vertices, faces.shape[1], faces


def test_traverse_damaged_parameters(tmp_path):
    """corner_order and the streams table, each broken in one way: R39 (R30 for planes 0 or 5),
    as the reference says."""
    faces, vertices = _tables()["torus"]
    good, payload, _ = traversal.encode_traversal(faces, vertices)
    table = good["streams"]
    breaks: dict[str, Any] = {
        "corner-order-missing": {"corner_order": None},
        "corner-order-2": {"corner_order": 2},
        "corner-order-float": {"corner_order": 1.0},
        "corner-order-bool": {"corner_order": False},
        "streams-missing": {"streams": None},
        "streams-not-array": {"streams": {"ops": 1}},
        "streams-three": {"streams": table[:3]},
        "streams-five": {"streams": [*table, [0, 1, 9]]},
        "entry-short": {"streams": [table[0][:2], *table[1:]]},
        "entry-long": {"streams": [[*table[0], 0], *table[1:]]},
        "entry-not-array": {"streams": [5, *table[1:]]},
        "count-negative": {"streams": [[-1, *table[0][1:]], *table[1:]]},
        "count-float": {"streams": [[float(table[0][0]), *table[0][1:]], *table[1:]]},
        "count-too-large": {"streams": [[2 * 176 * 3 + 1, *table[0][1:]], *table[1:]]},
        "count-huge": {"streams": [[2**64 - 1, *table[0][1:]], *table[1:]]},
        "count-wrong": {"streams": [[table[0][0] + 1, *table[0][1:]], *table[1:]]},
        "degrees-count-wrong": {"streams": [table[0], [1, *table[1][1:]], *table[2:]]},
        "planes-float": {"streams": [[table[0][0], 1.0, table[0][2]], *table[1:]]},
        "planes-negative": {"streams": [table[0], [table[1][0], -1, table[1][2]], *table[2:]]},
        "planes-zero": {"streams": [table[0], [table[1][0], 0, table[1][2]], *table[2:]]},
        "planes-five": {"streams": [*table[:3], [table[3][0], 5, table[3][2]]]},
        "planes-huge": {"streams": [[table[0][0], 2**63, table[0][2]], *table[1:]]},
        "planes-more": {"streams": [[table[0][0], 4, table[0][2]], *table[1:]]},
        "length-short": {"streams": [*table[:3], [table[3][0], table[3][1], table[3][2] - 1]]},
        "length-long": {"streams": [[table[0][0], table[0][1], table[0][2] + 1], *table[1:]]},
        "length-shifted": {
            "streams": [
                [table[0][0], table[0][1], table[0][2] + 1],
                [table[1][0], table[1][1], table[1][2] - 1],
                *table[2:],
            ]
        },
        "length-huge": {"streams": [[table[0][0], table[0][1], 2**64 - 1], *table[1:]]},
    }
    cases = Cases(tmp_path)
    for name, change in breaks.items():
        params = {**good, **change}
        params = {key: value for key, value in params.items() if value is not None}
        cases.traverse(name, params, payload, vertices, SPEC_OVER_REFERENCE.get(name))
    results = cases.check()
    for name in breaks:
        assert cases.expected[name][0] == "error", name
        assert results[name]["rule"] in DAMAGE_RULES, (name, results[name])


def test_traverse_damaged_streams(tmp_path):
    """The walk's checks, one by one, then random edits of the stream values: the same verdict
    and faces as the reference, every rejection R39."""
    cases = Cases(tmp_path)

    def add(
        name: str, coded: list[list[int]], order: int, vertices: int, shape: tuple[int, int]
    ) -> None:
        params, payload = traversal.pack_streams(coded, *shape, order, 19)
        cases.traverse(name, params, payload, vertices)

    coded, order, vertices, width, faces = _base("polygons")
    shape = faces.shape
    ops, degrees, news, refs = coded
    targeted = {
        "seed-prev-first": [[1, *ops[1:]], degrees, news, refs],
        "seed-next-first": [[2, *ops[1:]], degrees, news, refs],
        "op-four": [[4, *ops[1:]], degrees, news, refs],
        "op-negative": [[-1, *ops[1:]], degrees, news, refs],
        "gate-op-too-large": [[*ops[:5], 8 * width + 1, *ops[6:]], degrees, news, refs],
        "new-seen": [ops, degrees, [news[0], -2, *news[2:]], refs],
        "new-outside": [ops, degrees, [*news[:-1], vertices], refs],
        "new-below-zero": [ops, degrees, [-2, *news[1:]], refs],
        "degree-low": [ops, [-1, *degrees[1:]], news, refs],
        "degree-high": [ops, [width - 2, *degrees[1:]], news, refs],
        "degrees-short": [ops, degrees[:-1], news, refs],
        "degrees-long": [ops, [*degrees, 0], news, refs],
        "ops-short": [ops[:-1], degrees, news, refs],
        "ops-long": [[*ops, 0], degrees, news, refs],
        "vertices-short": [ops, degrees, news[:-1], refs],
        "vertices-long": [ops, degrees, [*news, 0], refs],
        "references-long": [ops, degrees, news, [*refs, 0]],
        "far-unseen": [[3, *ops[1:]], degrees, news, [39, *refs]],
        "far-outside": [[3, *ops[1:]], degrees, news, [-1, *refs]],
    }
    for name, streams_ in targeted.items():
        add(name, streams_, order, vertices, shape)
    # a gate face whose rotation is not below its degree: rotation n-1 on a triangle
    tri, tri_order, tri_vertices, _, tri_faces = _base("torus")
    first_gate = next(i for i, o in enumerate(tri[0]) if i >= 3 and o > 0)
    rotated = [*tri[0][:first_gate], 8 * 3 + 1, *tri[0][first_gate + 1 :]]
    add("rotation-too-large", [rotated, *tri[1:]], tri_order, tri_vertices, tri_faces.shape)
    # PREV and NEXT on empty lists: a seed's second corner on an empty boundary
    add("seed-prev-empty", [[0, 1, 0], [], [0, 0], []], 0, 3, (1, 3))
    add("seed-next-empty", [[0, 2, 0], [], [0], []], 0, 3, (1, 3))

    rng = random.Random(1414)
    for base in ("polygons", "soup", "non-manifold-edge", "repeated-vertex", "torus-renumbered"):
        coded, order, vertices, width, faces = _base(base)
        for trial in range(60):
            edited = [list(stream) for stream in coded]
            s = rng.choice([i for i, stream in enumerate(edited) if stream] or [0])
            stream = edited[s]
            where = rng.randrange(len(stream) + 1)
            how = rng.choice(["change", "change", "change", "drop", "insert", "swap"])
            if how == "insert" or not stream:
                stream.insert(where, rng.choice([0, 1, 2, 3, -1, rng.randrange(-9, 9 * width)]))
            elif how == "drop":
                del stream[min(where, len(stream) - 1)]
            elif how == "swap" and len(stream) > 1:
                i = min(where, len(stream) - 2)
                stream[i], stream[i + 1] = stream[i + 1], stream[i]
            else:
                i = min(where, len(stream) - 1)
                stream[i] = rng.choice([stream[i] + 1, stream[i] - 1, 0, 3, rng.randrange(-50, 50)])
            add(f"{base}-edit-{trial}", edited, order, vertices, faces.shape)
    results = cases.check()
    for name in [*targeted, "rotation-too-large", "seed-prev-empty", "seed-next-empty"]:
        assert results[name]["rule"] == "R39-traversal", (name, results[name])
    assert sum(not r["accepted"] for r in results.values()) > len(results) // 2


def test_traverse_stream_bounds_and_memory(tmp_path):
    """§6.8's bounds on the declared counts, each broken by one, and the streams beyond
    max_section_bytes (2**28 faces declaring 6 GiB of ops, in a file of a few hundred bytes):
    the same rule as the reference, before any stream is decompressed. A header's K of 2**26,
    and a walk past the 1024 faces the decoded table starts with: the same faces, and typed
    arrays that grow with the values read (K sized 576 MB of them before)."""
    faces, vertices = _tables()["polygons"]
    good, payload, _ = traversal.encode_traversal(faces, vertices)
    (ops, *_), (degrees, *_), (news, *_), (references, *_) = good["streams"]
    count, width = faces.shape
    corners = count * width

    def counts(o: int = ops, g: int = degrees, v: int = news, r: int = references) -> Any:
        table = [list(entry) for entry in good["streams"]]
        for entry, value in zip(table, [o, g, v, r], strict=True):
            entry[0] = value
        return {**good, "streams": table}

    breaks = {
        "bound-degrees": counts(g=count - 1),
        "bound-ops-below-faces": counts(o=count - 1),
        "bound-ops-above": counts(o=2 * corners + 1),
        "bound-vertices-above-k": counts(v=vertices + 1),
        "bound-vertices-and-references": counts(r=corners - news + 1),
    }
    cases = Cases(tmp_path)
    for name, params in breaks.items():
        cases.traverse(name, params, payload, vertices)
    table = [list(entry) for entry in good["streams"]]
    triangles, tri_vertices = _tables()["torus"]
    tri_params, tri_payload, _ = traversal.encode_traversal(triangles, tri_vertices)
    huge_ops = [6 << 28, 4, tri_params["streams"][0][2]]
    huge = {**tri_params, "shape": [1 << 28, 3], "streams": [huge_ops, *tri_params["streams"][1:]]}
    cases.traverse("streams-beyond-max-section-bytes", huge, tri_payload, tri_vertices)
    cases.traverse("vertices-in-header-2-26", tri_params, tri_payload, 1 << 26)
    big = _table(_renumbered(_torus(40, 30), 1200, 3))
    big_params, big_payload, _ = traversal.encode_traversal(big, 1200)
    cases.traverse("table-grows-past-1024-faces", big_params, big_payload, 1200)
    results = cases.check()
    for name in breaks:
        assert results[name]["rule"] == "R39-traversal", (name, results[name])
        assert "count" in results[name]["message"], (name, results[name])  # not a stream's
    assert results["streams-beyond-max-section-bytes"]["rule"] == "R21-header-limit"
    assert results["streams-beyond-max-section-bytes"]["kind"] == "LimitError"
    assert results["vertices-in-header-2-26"]["array_buffer_bytes"] < 1 << 20
    assert table == good["streams"]  # the cases changed copies only


def test_traverse_damaged_bytes(tmp_path):
    """Bytes of the zstd frames changed or cut: R29, R39 or the same faces as the reference."""
    faces, vertices = _tables()["soup"]
    params, payload, _ = traversal.encode_traversal(faces, vertices)
    rng = random.Random(29)
    cases = Cases(tmp_path)
    for trial in range(80):
        data = bytearray(payload)
        for _ in range(rng.randint(1, 3)):
            data[rng.randrange(len(data))] ^= 1 << rng.randrange(8)
        cases.traverse(f"flip-{trial}", params, bytes(data), vertices)
    table = params["streams"]
    cut = {**params, "streams": [[*table[0][:2], table[0][2] - 1], *table[1:]]}
    cases.traverse("cut-ops", cut, payload[: table[0][2] - 1] + payload[table[0][2] :], vertices)
    for name, result in cases.check().items():
        assert result["accepted"] or result["rule"] in DAMAGE_RULES, (name, result)


# --- mesh prediction --------------------------------------------------------------------------


def _residuals(rng: np.random.Generator, vertices: int, scale: int) -> np.ndarray:
    return rng.integers(-scale, scale + 1, size=vertices)


def test_restore_predictors(tmp_path):
    """Predictors 1 and 2 on every hand-made table and on face tables in walk order, with
    residuals from small to int32's extremes (large ones leave ±2^32: R32, as the reference)."""
    rng = np.random.default_rng(2)
    cases = Cases(tmp_path)
    tables = _tables()
    for name, (faces, vertices) in tables.items():
        _, _, walk = traversal.encode_traversal(faces, vertices)
        for label, table in (("", faces), ("-walk", walk)):
            for scale in (3, 2**20, 2**30, 2**31 - 1):
                columns = [_residuals(rng, vertices, scale) for _ in range(4)]
                residuals = np.concatenate(columns)
                cases.restore(f"{name}{label}-{scale}", table, vertices, residuals, [2, 1, 0, 2])
    results = cases.check()
    verdicts = {cases.expected[name][0] for name in results}
    assert verdicts == {"ok", "error"}  # both paths ran
    assert {r["rule"] for r in results.values() if not r["accepted"]} == {"R32-predictor"}


def test_restore_depth_limit(tmp_path):
    """Predictor 2 on a forest of 2048 depths restores; on 2049 it is R32; predictor 1 does not
    care."""
    rng = np.random.default_rng(3)
    cases = Cases(tmp_path)
    for vertices in (2048, 2049):
        faces = _table(_strip(vertices))
        cases.restore(f"strip-{vertices}-mean", faces, vertices, _residuals(rng, vertices, 5), [2])
        cases.restore(
            f"strip-{vertices}-parents", faces, vertices, _residuals(rng, vertices, 5), [1]
        )
    results = cases.check()
    assert results["strip-2048-mean"]["max_depth"] == 2047
    assert results["strip-2048-mean"]["accepted"]
    assert results["strip-2049-mean"]["rule"] == "R32-predictor"
    assert results["strip-2049-parents"]["accepted"]


def test_restore_many_sources(tmp_path):
    """A vertex with 2^17 + 3 sources (a bipyramid's far apex) takes the BigInt path."""
    ring = 2**17 + 3
    apex = ring + 1
    rows = [[0, i, i % ring + 1] for i in range(1, ring + 1)]
    rows += [[apex, i % ring + 1, i] for i in range(1, ring + 1)]
    faces, vertices = _table(rows), ring + 2
    rng = np.random.default_rng(4)
    small = _residuals(rng, vertices, 9)
    large = rng.integers(0, 2**20, size=vertices)  # the ring near 2^31, its terms near 3·2^31
    large[0], large[apex] = 2**31 - 1, -(2**31)
    cases = Cases(tmp_path)
    cases.restore("bipyramid", faces, vertices, np.concatenate([small, large]), [2, 2])
    result = cases.check()["bipyramid"]
    assert result["big_sources"] and result["accepted"]


def test_restore_past_2_to_53(tmp_path):
    """Predictor 1 sums past 2^53 are exact integers rounded once to float64 (ties to even):
    2^53 - 1 + 2 - 2 must give 2^53 - 1, not the 2^53 - 2 of a float64 running sum."""
    cases = Cases(tmp_path)
    faces = _table(_strip(6))
    cases.wide("tie", faces, 6, [2**53 - 1, 2, -2, -5, 1, 0])
    rng = random.Random(53)
    faces = _table(_renumbered(_torus(5, 6), 30, 2))
    cases.wide("torus", faces, 30, [rng.randrange(-(2**52), 2**52) for _ in range(30)])
    cases.check()


# --- real files -------------------------------------------------------------------------------


def _file_cases(cases: Cases, label: str, data: bytes) -> None:
    """The FACE section (if faces-traverse) and every U1 section of a file, as cases."""
    container = parse_container(data)
    vertices = container.header["vertices"]
    payload = {
        s.id: data[container.data_start + s.offset :][: s.length] for s in container.sections
    }
    sections = {s.id: s for s in container.sections}
    face = sections["FACE"]
    if face.codec == "faces-traverse":
        params, face_payload = face.params, payload["FACE"]
        cases.traverse(
            f"{label}-FACE",
            params,
            face_payload,
            vertices,
            None,
            container.adaptive,
            container.uniform_ranks,
        )
    faces = tuckercodec.decode(data, frames=[0]).faces
    mesh = MeshPrediction(faces, vertices)
    for section_id, section in sections.items():
        if section_id != "U1" and not section_id.startswith("U1."):
            continue
        # zstd planes or (1.6, the encoder's choice where smaller) an adaptive stream
        stream = stored_integers(section_id, section.params, payload[section_id], mesh)
        cases.restore(
            f"{label}-{section_id}", faces, vertices, stream, list(section.params["predict"])
        )


FILES = ["sample", "v1.2-traverse-triangles", "v1.2-traverse-polygons-segments"]
SHARED = ["samba.npz", "chicken.npz", "horse-gallop", "cloth-vellum.npz"]


def _file_data(name: str) -> bytes:
    if name == "sample":
        return tuckercodec.encode(tuckercodec.load_sequence(sample_path()))
    if name in SHARED:
        return shared_encoded(name).data  # at the default target, KG 0.1
    return (VECTORS / f"{name}.tkc").read_bytes()


@pytest.mark.parametrize("name", FILES + [shared_case(s) for s in SHARED])
def test_real_files(tmp_path, name):
    """The faces and every restored U1 column of real files, bit for bit (predictor 2 in use)."""
    cases = Cases(tmp_path)
    data = _file_data(name)
    _file_cases(cases, name, data)
    results = cases.check()
    assert all(result["accepted"] for result in results.values())
    if name != "v1.2-traverse-polygons-segments":
        assert any(2 in spec.get("predict", []) for spec in cases.specs), "no predictor 2 to test"


def measure(name: str = "samba.npz", repeat: int = 20) -> dict[str, Any]:
    """Times (fastest of ``repeat``) of traversal.js on a real file's FACE and of topology.js on
    its U1, in node: ``python tests/test_js_topology.py [NAME] [REPEAT]`` (NAME as in SHARED)."""
    import tempfile

    with tempfile.TemporaryDirectory() as folder:
        cases = Cases(Path(folder))
        _file_cases(cases, name, _file_data(name))
        results = cases.check(repeat)
    u1 = next(spec for spec in cases.specs if spec["kind"] == "restore")
    return {
        "file": name,
        "K": u1["K"],
        "faces": u1["M"],
        "U1 columns": len(u1["predict"]),
        "predictor 2 columns": u1["predict"].count(2),
        **{
            f"{key} {field}": value
            for key, r in results.items()
            for field, value in r.items()
            if field.endswith("ms")
        },
    }


if __name__ == "__main__":
    import sys

    arguments = sys.argv[1:]
    name = arguments[0] if arguments else "samba.npz"
    repeat = int(arguments[1]) if len(arguments) > 1 else 20
    print(json.dumps(measure(name, repeat), indent=1))
