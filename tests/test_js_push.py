"""The JavaScript decoder's push of predictor 2 (format 1.6, spec/FORMAT.md §6.2 "Push", §6.3's
``mean_push``, §5 step 16, R32): tuckercodec/web/tkc/qmat.js and topology.js, in node.

The files here are crafted from the vectors of 1.6 without any Python support for ``mean_push``:
each U1 section's integers q are restored with push 2 (as the file stores them), then stored again
as the residuals of other pushes, computed by the small reference of the formula below
(:func:`pushed_residuals`), in §6.1's zstd planes, with ``mean_push`` set. q is unchanged, so the
JavaScript decoder must give the original file's positions bit for bit. Files that break R32's
rule on ``mean_push`` in one way each must be refused with R32-predictor, in §5 step 16's order.
The BigInt path (a vertex with 2^16 sources or more) is checked on a crafted mesh through
tests/js/tkc_topology.mjs.
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from tests.support.adaptive_files import (
    AdaptiveParts,
    adaptive_parts,
    stored_integers,
    taken_apart,
    zstd_copy,
)
from tests.support.compressed import vector
from tests.support.js_decoder import decoded_frames, run_node
from tuckercodec.format import faces, streams
from tuckercodec.format.prediction import mean_accumulate
from tuckercodec.model.topology import MeanSteps, MeshPrediction, mesh_prediction

R32 = "R32-predictor"
#: Predictor 2's push where a file gives none (§6.2).
PUSH = 2


def pushed_residuals(q: np.ndarray, steps: MeanSteps, push: int) -> np.ndarray:
    """One column's predictor-2 residuals with push ``push`` (§6.2), from its integers ``q``
    (K,): V = Σ_{w in S(v)} ((6 + a) q[w] - a q[anchor(w)]), pred = floor((2V + 6c) / (12c)),
    in int64 (|2V + 6c| < 2^39 c: exact for any c here)."""
    q = np.asarray(q, dtype=np.int64)
    residual = q.copy()
    if steps.rows.size == 0:
        return residual
    terms = (6 + push) * q[steps.sources] - push * q[steps.anchors]
    total = np.add.reduceat(terms, steps.source_ends[:-1])  # every row has a source
    counts = np.diff(steps.source_ends)
    residual[steps.rows] -= np.floor_divide(2 * total + 6 * counts, 12 * counts)
    return residual


def _mesh(parts: AdaptiveParts) -> MeshPrediction:
    """The file's mesh, from its faces as FACE decodes them."""
    entry, payload = parts.sections[parts.index("FACE")]
    params = {k: v for k, v in entry.items() if k not in ("id", "critical", "codec")}
    vertices = int(parts.header["vertices"])
    coded = faces.decode_face_section(entry["codec"], payload, params, vertices, "section FACE")
    return mesh_prediction(coded, vertices)


def _u1_ids(parts: AdaptiveParts) -> list[str]:
    return [str(e["id"]) for e, _ in parts.sections if str(e["id"]).split(".")[0] == "U1"]


def _columns(parts: AdaptiveParts, section_id: str, mesh: MeshPrediction) -> np.ndarray:
    """A U1 section's stored integers, (cols, K) int64."""
    entry, payload = parts.sections[parts.index(section_id)]
    rows, cols = entry["shape"]
    return stored_integers(section_id, entry, payload, mesh).reshape(cols, rows)


def _integers(stored: np.ndarray, predict: bytes, mesh: MeshPrediction) -> np.ndarray:
    """q of a U1 section's predictor-2 columns (the others left as stored), push 2."""
    q = stored.copy()
    meaned = [c for c, p in enumerate(predict) if p == 2]
    if meaned:
        q[meaned] = mean_accumulate(stored[meaned].T, mesh.mean_steps).T
    return q


def pushed_copy(parts: AdaptiveParts, pushes: dict[str, list[int]]) -> bytes:
    """The file with each U1 section of ``pushes`` stored again with those pushes (cols bytes):
    its predictor-2 columns' residuals recomputed, every column in zstd planes (coder 0), and
    ``mean_push`` set. The flags and every other section are kept as they are."""
    mesh = _mesh(parts)
    sections = list(parts.sections)
    for section_id, push in pushes.items():
        n = parts.index(section_id)
        entry, _ = sections[n]
        stored = _columns(parts, section_id, mesh)
        q = _integers(stored, entry["predict"], mesh)
        columns = stored.copy()
        for c, p in enumerate(entry["predict"]):
            if p == 2:
                columns[c] = pushed_residuals(q[c], mesh.mean_steps, push[c])
        packed, planes = streams.pack_integers(columns.reshape(-1))
        sections[n] = ({**entry, "coder": 0, "planes": planes, "mean_push": bytes(push)}, packed)
    return AdaptiveParts(parts.flags, parts.minor, parts.header, sections).pack()


def _verdicts(files: list[bytes], tmp_path: Path) -> list[dict[str, Any]]:
    paths = []
    for n, data in enumerate(files):
        path = tmp_path / f"case{n:03d}.tkc"
        path.write_bytes(data)
        paths.append(path)
    verdicts: list[dict[str, Any]] = run_node("outcomes.mjs", *paths)
    return verdicts


# ------------------------------------------------------------------------------------------
# the reference of the formula, and valid files


@pytest.mark.parametrize("name", ["v1.6-adaptive", "v1.6-adaptive-segments"])
def test_the_formula_at_push_2_gives_the_files_residuals(name):
    """:func:`pushed_residuals` with push 2 is predictor 2 as the vectors store it (so the
    crafted files below rest on the spec's formula, not on a guess)."""
    parts = taken_apart(vector(name))
    mesh = _mesh(parts)
    checked = 0
    for section_id in _u1_ids(parts):
        predict = parts.sections[parts.index(section_id)][0]["predict"]
        stored = _columns(parts, section_id, mesh)
        q = _integers(stored, predict, mesh)
        for c, p in enumerate(predict):
            if p == 2:
                assert np.array_equal(pushed_residuals(q[c], mesh.mean_steps, PUSH), stored[c])
                checked += 1
    assert checked


#: Pushes per U1 section of v1.6-adaptive (predict 1 1 2 2 2 2): a column with predictor 1
#: ignores its byte, whatever it is within 0..9.
ADAPTIVE_PUSHES = {
    "every push 0": [0] * 6,
    "every push 9": [9] * 6,
    "every push 2, written": [2] * 6,
    "mixed": [2, 2, 0, 3, 6, 9],
    "mixed, predictor 1 bytes ignored": [9, 0, 1, 4, 5, 8],
    "odd pushes": [7, 7, 1, 7, 5, 3],
}


@pytest.mark.parametrize("pushes", list(ADAPTIVE_PUSHES.values()), ids=list(ADAPTIVE_PUSHES))
def test_pushed_u1_gives_the_same_positions(tmp_path, pushes):
    """v1.6-adaptive with its U1 stored again with other pushes: the same frames, bit for bit,
    while the stored residuals did change (except where every push is 2)."""
    parts = taken_apart(vector("v1.6-adaptive"))
    crafted = pushed_copy(parts, {"U1": pushes})
    again = taken_apart(crafted)
    mesh = _mesh(parts)
    original = _columns(parts, "U1", mesh)
    changed = _columns(again, "U1", mesh)
    assert again.flags & 8 and again.sections[again.index("U1")][0]["mean_push"] == bytes(pushes)
    meaned = [p == 2 for p in parts.sections[parts.index("U1")][0]["predict"]]
    differs = [not np.array_equal(a, b) for a, b in zip(original, changed, strict=True)]
    expected = [m and p != PUSH for m, p in zip(meaned, pushes, strict=True)]
    assert differs == expected
    assert np.array_equal(
        decoded_frames(crafted, tmp_path, "pushed"),
        decoded_frames(vector("v1.6-adaptive"), tmp_path, "original"),
    )


def test_pushed_segments_give_the_same_positions(tmp_path):
    """Both segments' U1 (U1.0 every column predictor 2, U1.1 one) with pushes of their own."""
    parts = taken_apart(vector("v1.6-adaptive-segments"))
    crafted = pushed_copy(parts, {"U1.0": [0, 1, 3, 6, 8, 9], "U1.1": [4, 9, 4, 4, 4, 4]})
    assert np.array_equal(
        decoded_frames(crafted, tmp_path, "pushed"),
        decoded_frames(vector("v1.6-adaptive-segments"), tmp_path, "original"),
    )


# ------------------------------------------------------------------------------------------
# files that break R32's rule on mean_push, one way each, in §5 step 16's order


def _edited(parts: AdaptiveParts, section_id: str, **changes: Any) -> bytes:
    """The file with one section's entry keys changed (None: the key taken out)."""
    n = parts.index(section_id)
    entry, payload = parts.sections[n]
    entry = {k: v for k, v in {**entry, **changes}.items() if v is not None}
    sections = list(parts.sections)
    sections[n] = (entry, payload)
    return AdaptiveParts(parts.flags, parts.minor, parts.header, sections).pack()


def _cases() -> list[tuple[str, bytes, str | None]]:
    """(what, file, the rule it breaks or None for a valid file)."""
    parts = taken_apart(vector("v1.6-adaptive"))
    pushed = taken_apart(pushed_copy(parts, {"U1": [2, 2, 0, 3, 6, 9]}))
    unflagged = taken_apart(zstd_copy(vector("v1.6-adaptive")))
    assert not unflagged.flags & 8
    fields = adaptive_parts(vector("v1.5-fields"))
    bad = b"\x02\x02\x0a\x02\x02\x02"
    return [
        ("the pushed copy", pushed.pack(), None),
        ("every push 2 on an adaptive U1", _edited(parts, "U1", mean_push=b"\x02" * 6), None),
        ("byte 10", _edited(pushed, "U1", mean_push=bad), R32),
        ("byte 255", _edited(pushed, "U1", mean_push=b"\xff" + bytes(5)), R32),
        ("byte 10 on a predictor-1 column", _edited(pushed, "U1", mean_push=b"\x0a" * 6), R32),
        ("one byte short", _edited(pushed, "U1", mean_push=bytes(5)), R32),
        ("one byte more", _edited(pushed, "U1", mean_push=bytes(7)), R32),
        ("empty", _edited(pushed, "U1", mean_push=b""), R32),
        ("a list, not a bin", _edited(pushed, "U1", mean_push=[2] * 6), R32),
        ("an int, not a bin", _edited(pushed, "U1", mean_push=2), R32),
        ("a str, not a bin", _edited(pushed, "U1", mean_push="\x02" * 6), R32),
        ("without flag bit 3", _edited(unflagged, "U1", mean_push=b"\x02" * 6), R32),
        ("on U3", _edited(parts, "U3", mean_push=b"\x02" * 6), R32),
        ("on CENT", _edited(parts, "CENT", mean_push=b"\x02" * 3), R32),
        ("on CORE", _edited(parts, "CORE", mean_push=b"\x02"), R32),
        ("on a field's U1", _edited(fields, "FLD.0.U1", mean_push=b"\x02"), R32),
        ("mean_push before coder", _edited(pushed, "U1", mean_push=bad, coder=2), R32),
        ("planes before mean_push", _edited(pushed, "U1", mean_push=bad, planes=0), "R30-planes"),
        ("steps before mean_push", _edited(pushed, "U1", mean_push=bad, steps=b""), "R31-steps"),
        (
            "step values before mean_push",
            _edited(pushed, "U1", mean_push=bad, steps=np.zeros(6, "<f4").tobytes()),
            "R31-steps",
        ),
        ("predict before mean_push", _edited(pushed, "U1", mean_push=bad, predict=b""), R32),
        ("coder after a good mean_push", _edited(pushed, "U1", coder=2), "R46-adaptive-stream"),
    ]


def test_mean_push_is_checked_in_step_16s_order(tmp_path):
    """Each file breaks R32's rule on ``mean_push`` (or another of step 16's checks beside it)
    in one way, or is valid: the JavaScript decoder refuses it with the rule of the first check
    it fails, planes, steps, predict, then mean_push, then the coder."""
    cases = _cases()
    verdicts = _verdicts([data for _, data, _ in cases], tmp_path)
    wrong = []
    for (what, _, rule), got in zip(cases, verdicts, strict=True):
        assert not got.get("crashed"), (what, got)
        expected = {"accepted": True} if rule is None else {"accepted": False, "rule": rule}
        if {k: got.get(k) for k in expected} != expected:
            wrong.append((what, expected, got))
    assert not wrong, wrong


def test_a_push_outside_the_range_of_predictor_2_is_refused(tmp_path):
    """A pushed column whose restored value leaves ±2^32: R32, as with push 2."""
    parts = taken_apart(pushed_copy(taken_apart(vector("v1.6-adaptive")), {"U1": [2, 2, 9] * 2}))
    n = parts.index("U1")
    entry, _ = parts.sections[n]
    mesh = _mesh(parts)
    columns = _columns(parts, "U1", mesh)
    columns[2, mesh.mean_steps.rows] = 2**31 - 1  # every depth a large step further out
    packed, planes = streams.pack_integers(columns.reshape(-1))
    parts.sections[n] = ({**entry, "planes": planes}, packed)
    (verdict,) = _verdicts([parts.pack()], tmp_path)
    assert (verdict["accepted"], verdict.get("rule")) == (False, R32), verdict


# ------------------------------------------------------------------------------------------
# many sources: the BigInt path


def test_a_vertex_with_many_sources_is_exact_with_any_push(tmp_path):
    """A bipyramid whose far apex has 2^16 + 3 sources (the float path's limit for a push other
    than 2): each push's column restores to the q its residuals came from."""
    ring = 2**16 + 3
    apex = ring + 1
    rows = [[0, i, i % ring + 1] for i in range(1, ring + 1)]
    rows += [[apex, i % ring + 1, i] for i in range(1, ring + 1)]
    table, vertices = np.array(rows, dtype=np.int64), ring + 2
    steps = MeshPrediction(table, vertices).mean_steps
    assert int(np.diff(steps.source_ends).max()) >= 2**16
    rng = np.random.default_rng(32)
    pushes = [0, 1, 2, 5, 9]
    q = np.empty((len(pushes), vertices), dtype=np.int64)
    residuals = np.empty_like(q)
    for c, push in enumerate(pushes):
        # the ring near -2^30 and its anchor, the root 0, at 2^29: the apex's terms near
        # -(15 + 9/2)·2^30 with push 9 (every residual still an int32)
        q[c] = -rng.integers(2**30, 2**30 + 2**20, size=vertices)
        q[c, 0], q[c, apex] = 2**29, -(2**31) + 7 + c
        residuals[c] = pushed_residuals(q[c], steps, push)
    assert np.abs(residuals).max() < 2**31
    (tmp_path / "faces").write_bytes(table.astype("<i4").tobytes())
    (tmp_path / "residuals").write_bytes(residuals.astype("<i4").tobytes())
    spec = {
        "kind": "restore",
        "name": "bipyramid",
        "faces": "faces",
        "K": vertices,
        "M": len(rows),
        "n": 3,
        "residuals": "residuals",
        "predict": [2] * len(pushes),
        "push": pushes,
    }
    manifest = tmp_path / "manifest.json"
    manifest.write_text(json.dumps({"cases": [spec]}))
    (result,) = run_node("tkc_topology.mjs", manifest)
    assert result["accepted"], result
    assert result["sha256"] == hashlib.sha256(q.astype("<f8").tobytes()).hexdigest()
