"""The compiled core's adaptive coder (§6.14) against the pure-Python reference
(``tuckercodec/format/adaptive.py``): the same bytes encoded, the same integers decoded, and on
damaged streams the same verdict (the same integers, or R46 with the same message), for
sequence orders and mesh orders of real face tables."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from typing import Any

import numpy as np
import pytest

from tests.support.sequences import grid_faces, wave_sequence
from tuckercodec import Decoder, MeshSequence, decoder, encode, internal
from tuckercodec.errors import FormatError
from tuckercodec.format import adaptive
from tuckercodec.model.topology import mesh_prediction
from tuckercodec.system import native


@pytest.fixture(autouse=True)
def _needs_core() -> None:
    if native.core() is None:
        pytest.skip("the compiled core is not installed (python -m tools.build_native)")


def _outcome(call: Callable[..., Any], *args: Any) -> tuple[Any, ...]:
    """What a call gives, comparable bit for bit: its bytes or array, or its error's class,
    rule, field and message."""
    try:
        result = call(*args)
    except FormatError as error:
        return ("error", type(error).__name__, error.rule, error.field, str(error))
    if isinstance(result, np.ndarray):
        return ("array", result.dtype.str, result.shape, result.tobytes())
    return ("bytes", result)


def _alike(call: Callable[..., Any], *args: Any) -> tuple[Any, ...]:
    """The outcome of ``call(*args)`` with the compiled core, checked to be the reference's."""
    compiled = _outcome(call, *args)
    with native.pure_python():
        reference = _outcome(call, *args)
    assert compiled == reference
    return compiled


def _matrices(rows: int, rng: np.random.Generator) -> Iterator[np.ndarray]:
    """(cols, rows) int64 matrices of several magnitude distributions."""
    yield np.zeros((3, rows), dtype=np.int64)
    yield np.rint(rng.laplace(0, 2, (4, rows))).astype(np.int64)
    # a factor's columns: large first, smaller after, as U1's are
    scales = np.array([3000.0, 200.0, 30.0, 4.0, 0.5])[:, None]
    yield np.rint(rng.laplace(0, 1, (5, rows)) * scales).astype(np.int64)
    # any size up to 2**62, either sign, with zeros between
    bits = rng.integers(0, 63, (2, rows))
    huge = rng.integers(0, 1 << 62, (2, rows)) >> (62 - bits)
    yield np.where(rng.random((2, rows)) < 0.2, 0, huge * rng.choice([-1, 1], (2, rows)))
    yield -np.abs(rng.integers(-(1 << 20), 1 << 20, (1, rows)))


def _mesh_orders() -> Iterator[tuple[str, adaptive.CodingOrder]]:
    """U1's orders (adaptive.mesh_order) of small real face tables."""
    quads = np.array([[0, 1, 5, 4], [1, 2, 6, 5], [2, 3, 7, 6], [4, 5, 9, 8]], dtype=np.int64)
    two = np.concatenate([grid_faces(4), grid_faces(3) + 16])
    mixed = np.array([[0, 1, 2, -1], [1, 3, 4, 2], [4, 5, 6, -1]], dtype=np.int64)
    for name, faces, vertex_count in [
        ("grid", grid_faces(6), 36),
        ("quads with loose vertices", quads, 13),
        ("two pieces", two, 25),
        ("mixed widths", mixed, 8),
        ("no faces", np.zeros((0, 3), dtype=np.int64), 5),
    ]:
        steps = mesh_prediction(faces, vertex_count).mean_steps
        order = adaptive.mesh_order(vertex_count, steps.rows, steps.sources, steps.source_ends)
        yield name, order


def _cases() -> Iterator[tuple[str, np.ndarray, adaptive.CodingOrder]]:
    rng = np.random.default_rng(46)
    for rows in (1, 2, 3, 17, 60):
        for index, matrix in enumerate(_matrices(rows, rng)):
            yield f"sequence {rows} #{index}", matrix, adaptive.sequence_order(rows)
    for name, order in _mesh_orders():
        rows = order.order.size
        for index, matrix in enumerate(_matrices(rows, rng)):
            yield f"mesh {name} #{index}", matrix, order
    yield "one column", rng.integers(-9, 9, (1, 40)), adaptive.sequence_order(40)
    yield "no columns", np.zeros((0, 4), dtype=np.int64), adaptive.sequence_order(4)
    yield "no rows", np.zeros((3, 0), dtype=np.int64), adaptive.sequence_order(0)


CASES = list(_cases())


@pytest.mark.parametrize(("name", "matrix", "order"), CASES, ids=[c[0] for c in CASES])
def test_same_bytes_and_integers(
    name: str, matrix: np.ndarray, order: adaptive.CodingOrder
) -> None:
    outcome = _alike(adaptive.encode_columns, matrix, order)
    payload = outcome[1]
    cols, rows = matrix.shape
    decoded = _alike(adaptive.decode_columns, payload, cols, rows, order, "U1")
    assert decoded == ("array", "<i8", matrix.shape, matrix.astype(np.int64).tobytes())


def _damaged(payload: bytes, rng: np.random.Generator) -> Iterator[bytes]:
    """The payload cut short, made longer, and with bytes changed."""
    for cut in sorted({1, 2, len(payload) // 2, len(payload) - 1}):
        if 0 < cut <= len(payload):
            yield payload[:-cut]
    yield payload + b"\x00"
    yield payload + b"\xff\x00\x00"
    for _ in range(6):
        damaged = bytearray(payload)
        at = int(rng.integers(0, len(payload)))
        damaged[at] ^= int(rng.integers(1, 256))
        yield bytes(damaged)
    last = bytearray(payload)
    last[-1] ^= 1  # a change the range may absorb: the same integers, or R46
    yield bytes(last)


DAMAGED = [c for c in CASES if c[1].size and c[0].endswith(("#1", "#2", "#3"))]


@pytest.mark.parametrize(("name", "matrix", "order"), DAMAGED, ids=[c[0] for c in DAMAGED])
def test_same_verdict_on_damage(name: str, matrix: np.ndarray, order: adaptive.CodingOrder) -> None:
    rng = np.random.default_rng(len(name))
    payload = adaptive.encode_columns(matrix, order)
    cols, rows = matrix.shape
    verdicts = set()
    for damaged in _damaged(payload, rng):
        outcome = _alike(adaptive.decode_columns, damaged, cols, rows, order, "U3.s")
        verdicts.add(outcome[0])
    assert "error" in verdicts


def test_the_edges_of_the_format() -> None:
    order = adaptive.sequence_order(1)
    # 2**63 is written (63 exponent decisions 1) and refused by both decoders
    payload = _alike(adaptive.encode_columns, np.array([[-(1 << 63)]]), order)[1]
    outcome = _alike(adaptive.decode_columns, payload, 1, 1, order, "CORE")
    assert outcome[2:] == ("R46-adaptive-stream", "CORE", outcome[4])
    assert "more than 62 bits" in outcome[4]
    for broken in [b"", b"\x00" * 4, b"\x01" + b"\x00" * 9, b"\x00\xff\xff\xff\xff"]:
        assert _alike(adaptive.decode_columns, broken, 0, 1, order, "CENT")[0] == "error"
    # more integers than any payload of its length holds: refused before anything is allocated
    huge = adaptive.sequence_order(1 << 20)
    outcome = _alike(adaptive.decode_columns, b"\x00" * 5, 1 << 20, 1 << 20, huge, "U1")
    assert "cannot come from 5 bytes" in outcome[4]


def test_the_core_checks_its_arguments() -> None:
    core = native.core()
    assert core is not None
    order = adaptive.sequence_order(3)
    arrays = [
        np.ascontiguousarray(a, dtype=np.int64) for a in (order.order, order.sources, order.ends)
    ]
    # the bound is the core's own too, before it allocates
    with pytest.raises(core.Broken) as error:
        core.adaptive_decode(b"\x00" * 5, 1 << 40, 3, *arrays, False)
    assert error.value.args[0] == "R46-adaptive-stream"
    # arrays that are not an order of the rows: the caller's mistake, a ValueError
    for bad in (
        [np.array([0, 1, 3]), arrays[1], arrays[2]],
        [arrays[0], np.array([0, 1, -1]), arrays[2]],
        [arrays[0], arrays[1], np.array([0, 0, 2, 1])],
        [arrays[0], arrays[1], np.array([0, 0, 1])],
    ):
        with pytest.raises(ValueError, match="invalid coding order") as refused:
            core.adaptive_decode(b"\x00" * 5, 1, 3, *bad, False)
        assert not isinstance(refused.value, core.Broken)
        with pytest.raises(ValueError, match="invalid coding order"):
            core.adaptive_encode(np.zeros((1, 3), dtype=np.int64), *bad, False)


def _with_payloads(data: bytes, change: dict[str, Callable[[bytes], bytes]]) -> bytes:
    """``data`` with the payloads of the sections named in ``change`` changed (CRCs made anew)."""
    container = internal.parse_container(data)
    sections = []
    for section, entry in zip(container.sections, container.header["sections"], strict=True):
        payload = bytes(container.payload(data, section))
        payload = change.get(str(entry["id"]), lambda p: p)(payload)
        entry = {k: v for k, v in entry.items() if k not in ("offset", "length", "crc32")}
        sections.append((entry, payload))
    header = {k: v for k, v in container.header.items() if k != "sections"}
    return internal.pack_container(header, sections, flags=container.flags, minor=container.minor)


def test_a_file_reports_its_first_broken_factor(monkeypatch: pytest.MonkeyPatch) -> None:
    """U3, CORE and CENT decode on a thread beside U1 in the compiled core (here whatever their
    size, their thread started before FACE is read): the error reported is still the first in
    §5's order, FACE's before theirs, U1's before theirs, as in pure Python."""
    monkeypatch.setattr(decoder, "BESIDE_U1", 1)
    sequence = MeshSequence(wave_sequence(60, 20), grid_faces(20))
    data = encode(sequence, target_kg=0.02)
    coders = {e["id"]: e.get("coder") for e in internal.parse_container(data).header["sections"]}
    assert all(coders[stem] == adaptive.CODER_ADAPTIVE for stem in ("U1", "U3", "CORE", "CENT"))
    _alike(lambda d: Decoder(d).frame(0), data)
    cut: Callable[[bytes], bytes] = lambda payload: payload[:-1]  # noqa: E731
    longer: Callable[[bytes], bytes] = lambda payload: payload + b"\0"  # noqa: E731
    # the others' thread starts before FACE is read: FACE's error comes first too
    broken_sets = [("U1",), ("U3",), ("CORE", "CENT"), ("U1", "U3"), ("U1", "CENT"), ("CENT",)]
    for broken in [*broken_sets, ("FACE", "U3"), ("FACE", "CORE", "U1")]:
        for change in (cut, longer):
            damaged = _with_payloads(data, dict.fromkeys(broken, change))
            outcome = _alike(lambda d: Decoder(d).frame(0), damaged)
            assert outcome[0] == "error" and outcome[3] == f"section {broken[0]}"


@pytest.mark.parametrize("rows", [0, 1, 2, 3, 4, 9, 1000])
def test_the_sequence_order_is_its_definition(rows: int) -> None:
    """Ascending rows, row r after rows r - 1 and r - 2 (those that exist), in that order."""
    order = adaptive.sequence_order(rows)
    sources = [w for r in range(rows) for w in (r - 1, r - 2) if w >= 0]
    ends = np.cumsum([0] + [min(r, 2) for r in range(rows)])
    assert not order.mesh
    expected = [(order.order, range(rows)), (order.sources, sources), (order.ends, ends)]
    for array, values in expected:
        assert array.dtype == np.int64 and array.tolist() == list(values)
