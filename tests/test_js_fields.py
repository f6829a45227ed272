"""The JavaScript decoder (tuckercodec/web/tkc/fields.js) on format 1.5's animated fields
(FLD.n, spec/FORMAT.md §6.13), against the Python decoder, in node: the cloth of ../shared/data
with its velocity, speed and per-face velocity as fields in float32 and float64, encoded in each
mode (tucker for a relative target, grid for a bound, exact for lossless): grid and exact bit
for bit, tucker within §8's tolerance; crafted chunks (several per field, every predictor,
integers whose differences wrap at 64 bits); and the same rule, file for file, on files whose
fields' sections are damaged (tests/js/outcomes.mjs)."""

from __future__ import annotations

import functools
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import tuckercodec
from tests.support.compressed import Parts
from tests.support.js_decoder import compare_verdicts, python_verdict, run_node
from tests.support.sequences import load_shared_npz
from tools.generate import vectors as make_vectors
from tuckercodec import Field, MeshSequence
from tuckercodec.format import fields as fmt
from tuckercodec.format.residual import FINITE32

FRAMES = slice(24, 36)  # frames where the cloth moves: every field changes
FRAME_RATE = 24.0
TARGETS = {"tucker": "rel:1", "grid": "max:0.001", "exact": "lossless"}
TOLERANCE = 1e-9  # spec/FORMAT.md §8, relative to the largest |value|
DTYPES: dict[str, np.dtype[Any]] = {"f32": np.dtype("<f4"), "f64": np.dtype("<f8")}


@functools.cache
def _cloth() -> tuple[np.ndarray, np.ndarray, list[Field]]:
    """The cloth's frames (or skip), faces, and its fields: velocity (float32 and float64),
    speed, and the faces' mean velocity and speed."""
    vertices, faces = load_shared_npz("cloth-vellum.npz")
    positions = vertices[FRAMES].astype(np.float64)
    faces = faces.astype(np.int64)
    velocity = (np.gradient(positions, axis=0) * FRAME_RATE).astype(np.float32)
    face_velocity = velocity[:, faces].mean(axis=2)
    fields = [
        Field("velocity", velocity, "vertex", "velocity"),
        Field("velocity64", velocity.astype(np.float64), "vertex", "velocity"),
        Field("speed", np.linalg.norm(velocity, axis=2)),
        Field("face velocity", face_velocity.astype(np.float64), "face", "velocity"),
        Field("face speed", np.linalg.norm(face_velocity, axis=2).astype(np.float32), "face"),
    ]
    return positions, faces, fields


@functools.cache
def cloth_with_fields(mode: str) -> bytes:
    """The cloth with its fields, every field stored in ``mode``."""
    positions, faces, fields = _cloth()
    sequence = MeshSequence(positions, faces, fields=fields)
    data = tuckercodec.encode(sequence, target_kg=0.5, field_target=TARGETS[mode])
    modes = make_vectors.field_modes(tuckercodec.Decoder(data))
    assert modes == [mode] * len(fields), modes  # the test covers the mode it names
    return data


def _js_fields(data: bytes, tmp_path: Path, name: str = "in") -> tuple[dict[str, Any], bytes]:
    source, output = tmp_path / f"{name}.tkc", tmp_path / f"{name}.bin"
    source.write_bytes(data)
    result = run_node("fields.mjs", source, output)
    assert not result.get("crashed"), result["message"]
    return result, output.read_bytes() if result["accepted"] else b""


def _check_same_as_python(data: bytes, tmp_path: Path, name: str = "in") -> None:
    facts, raw = _js_fields(data, tmp_path, name)
    assert facts["accepted"], facts["message"]
    expected = tuckercodec.Decoder(data)
    wanted = expected.fields()
    assert [f["name"] for f in facts["fields"]] == expected.field_names
    assert len(facts["fields"]) == len(wanted)
    for got, want in zip(facts["fields"], wanted, strict=True):
        assert (got["name"], got["role"], got["domain"], got["components"]) == (
            want.name,
            want.role,
            want.domain,
            want.components,
        )
        dtype = DTYPES[got["type"]]
        assert dtype == want.values.dtype.newbyteorder("<")
        values = np.frombuffer(raw, dtype, want.values.size, got["at"]).reshape(want.values.shape)
        if got["mode"] == "tucker":
            # §8: the sum's order may differ by rounding; a float32 value by one ulp beside it
            scale = float(np.abs(want.values).max())
            allowed = TOLERANCE * scale + 1e-12
            if dtype == np.float32:
                allowed = allowed + np.spacing(np.abs(want.values))
            worst = np.abs(values.astype(np.float64) - want.values)
            assert (worst <= allowed).all(), f"{want.name}: differs by {worst.max():.3g}"
        else:
            assert values.tobytes() == want.values.astype(dtype).tobytes(), f"{want.name} differs"


@pytest.mark.parametrize("mode", sorted(TARGETS))
def test_cloth_fields_as_python(mode, tmp_path):
    _check_same_as_python(cloth_with_fields(mode), tmp_path)


# ------------------------------------------------------------------------------------------
# crafted chunks: values no encoder writes, which both decoders must read the same way


def _with_chunks(data: bytes, changes: dict[int, tuple[np.ndarray, dict[str, Any]]]) -> bytes:
    """The file with each field ``number``'s integers (F, N, c) replaced, chunked as its
    parameters (``predict``, ``chunk_frames``...) say: ``changes[number] = (integers, params)``."""
    parts = Parts(data)
    for number, (integers, params) in changes.items():
        at = parts.index(f"FLD.{number}")
        entry, _ = parts.sections[at]
        chunks, payload = fmt.pack_chunks(integers, params["predict"], params["chunk_frames"], 3)
        parts.sections[at] = ({**entry, **params, "chunks": chunks}, payload)
    return parts.pack()


def _crafted_integers(
    shape: tuple[int, int, int], dtype: Any, rng: np.random.Generator
) -> tuple[np.ndarray, np.ndarray]:
    """Grid integers of any size up to 2^53, and the ordered integers of finite values of
    ``dtype`` with random bits (both signs, the largest, the zeros)."""
    grid = rng.integers(-(2**52), 2**52, size=shape, dtype=np.int64)
    grid[0, :2, 0] = [2**53, -(2**53)]
    bits = rng.integers(0, 2**64, size=shape, dtype=np.uint64)
    if dtype == np.float64:
        values = bits.view(np.float64)
    else:
        values = (bits & np.uint64(0xFFFFFFFF)).astype(np.uint32).view(np.float32)
    values = np.where(np.isfinite(values), values, -0.0).astype(dtype)
    values.reshape(-1)[:4] = [np.finfo(dtype).max, -np.finfo(dtype).max, -0.0, 0.0]
    return grid, fmt.exact_integers(values)


def _crafted(data: bytes, rng: np.random.Generator) -> list[bytes]:
    """Fields 1 (float64 velocity) and 2 (float32 speed) of a grid file, as grid integers of
    any size and as the ordered integers of random finite values (whose differences wrap at
    64 bits), in chunks of 1, 5 and more frames than the file has, with each predictor."""
    decoder = tuckercodec.Decoder(data)
    frames, vertices = decoder.info.frames, decoder.info.vertices
    integers = {
        1: _crafted_integers((frames, vertices, 3), np.float64, rng),
        2: _crafted_integers((frames, vertices, 1), np.float32, rng),
    }
    cases = []
    for predict in fmt.PREDICTORS:
        for chunk_frames in (1, 5, frames + 3):
            layout = {"predict": predict, "chunk_frames": chunk_frames}
            step = float(rng.uniform(1e-6, 1e-3))
            grid = {n: (q[0], {**layout, "step": step}) for n, q in integers.items()}
            exact = {n: (q[1], {**layout, "mode": "exact"}) for n, q in integers.items()}
            cases += [_with_chunks(data, grid), _with_chunks(data, exact)]
    return cases


def test_crafted_chunks_same_bits(tmp_path):
    """Chunk by chunk, every predictor, differences that wrap at 64 bits, the extreme
    values: the Python decoder's bits."""
    data = cloth_with_fields("grid")
    cases = _crafted(data, np.random.default_rng(3))
    for n, case in enumerate(cases):
        _check_same_as_python(case, tmp_path, f"case{n}")


def test_crafted_values_out_of_range_refused(tmp_path):
    """A grid integer beyond 2^53, an exact integer that is no finite value's: R45 in both."""
    data = cloth_with_fields("grid")
    decoder = tuckercodec.Decoder(data)
    shape = (decoder.info.frames, decoder.info.vertices, 1)
    beyond = np.zeros(shape, dtype=np.int64)
    beyond[3, 7, 0] = 2**53 + 1
    infinity = np.zeros(shape, dtype=np.int64)
    infinity[5, 2, 0] = FINITE32[1] + 1
    huge = np.full(shape, 2**40, dtype=np.int64)
    cases = [
        _with_chunks(data, {2: (beyond, {"predict": 1, "chunk_frames": 4})}),
        _with_chunks(data, {2: (infinity, {"predict": 2, "chunk_frames": 5, "mode": "exact"})}),
        # q · step overflows float32
        _with_chunks(data, {2: (huge, {"predict": 0, "chunk_frames": 4, "step": 1e300})}),
    ]
    for n, case in enumerate(cases):
        # the reference's q * step overflows with a RuntimeWarning before its R45
        with np.errstate(over="ignore"):
            python = python_verdict(case)
        assert python == {"accepted": False, "rule": "R45-field", "kind": "FormatError"}
        facts, _ = _js_fields(case, tmp_path, f"case{n}")
        assert (facts.get("rule"), facts.get("kind")) == (python["rule"], python["kind"])


# ------------------------------------------------------------------------------------------
# damaged files: the same verdict from both decoders

CASES = 240


def _damaged_value(value: Any, rng: np.random.Generator) -> Any:
    """``value`` changed in type or a little in value, lists and bytes at any depth."""
    if isinstance(value, bool):
        return [not value, 1, None][int(rng.integers(3))]
    if isinstance(value, int):
        choices = [value + 1, value - 1, -1, 0, 9, 2**33, 2**64 - 1, 1.0, True, "1"]
        return choices[int(rng.integers(len(choices)))]
    if isinstance(value, float):
        choices = [value * 2, -value, math.inf, math.nan, 0.0, 1, value * 1e300, None]
        return choices[int(rng.integers(len(choices)))]
    if isinstance(value, str):
        choices = ["", "vertex", "face", "f32", "f64", "grid", "exact", "tucker", "x" * 300, 7]
        return choices[int(rng.integers(len(choices)))]
    if isinstance(value, bytes):  # a qmat's steps or predict
        damaged = bytearray(value)
        if damaged and rng.random() < 0.7:
            damaged[int(rng.integers(len(damaged)))] = int(rng.integers(256))
            return bytes(damaged)
        return bytes(damaged[:-1]) if damaged else b"\x00"
    if isinstance(value, list):
        value = list(value)
        if not value or rng.random() < 0.2:
            return [None, [], [*value, 0], value[:-1]][int(rng.integers(4))]
        at = int(rng.integers(len(value)))
        value[at] = _damaged_value(value[at], rng)
        return value
    return 0


def _damaged_payload(entry: dict[str, Any], payload: bytes, rng: np.random.Generator) -> bytes:
    """Bits of the payload flipped, or the payload cut short (a chunked field's chunk table
    made to agree, so that the cut reaches the zstd frame)."""
    if rng.random() < 0.5:
        damaged = bytearray(payload)
        for _ in range(int(rng.integers(1, 4))):
            damaged[int(rng.integers(len(damaged)))] ^= 1 << int(rng.integers(8))
        return bytes(damaged)
    cut = int(rng.integers(1, min(len(payload), 40) + 1))
    chunks = entry.get("chunks")
    if isinstance(chunks, list) and chunks and rng.random() < 0.8:
        last = chunks[-1]
        if last[1] >= cut:
            entry["chunks"] = [*chunks[:-1], [last[0], last[1] - cut]]
    return payload[:-cut]


def _damaged(data: bytes, rng: np.random.Generator) -> bytes:
    parts = Parts(data)
    chosen = [n for n, (e, _) in enumerate(parts.sections) if e["id"].startswith("FLD.")]
    at = int(rng.choice(chosen))
    entry, payload = parts.sections[at]
    entry = dict(entry)
    kind = int(rng.integers(10))
    if kind < 3 and payload:
        payload = _damaged_payload(entry, payload, rng)
    elif kind == 3:  # the table's rules: criticality, codec, numbering
        change = int(rng.integers(4))
        if change == 0:
            entry["critical"] = True
        elif change == 1:
            entry["codec"] = "field" if entry["codec"] == "qmat" else "qmat"
        elif change == 2:
            entry["id"] = "FLD.7" if entry["id"].count(".") == 1 else entry["id"] + "X"
        else:
            del parts.sections[at]  # a field's descriptor or factor missing
            return parts.pack()
    else:  # a parameter
        keys = sorted(k for k in entry if k not in ("id", "critical", "codec"))
        key = str(rng.choice(keys))
        if rng.random() < 0.1:
            del entry[key]
        else:
            entry[key] = _damaged_value(entry[key], rng)
    parts.sections[at] = (entry, payload)
    return parts.pack()


def test_damaged_fields_same_verdict(tmp_path):
    rng = np.random.default_rng(45)
    bases = [cloth_with_fields(mode) for mode in sorted(TARGETS)]
    files = [_damaged(bases[n % len(bases)], rng) for n in range(CASES)]
    differ, zstd_only, verdicts = compare_verdicts(files, tmp_path, _zstd_strictness)
    rules = {verdict.get("rule") for verdict in verdicts}
    assert not differ, f"{len(differ)} of {len(files)} verdicts differ: {differ[:5]}"
    assert len(zstd_only) <= len(files) // 25, f"zstd disagrees too often: {zstd_only}"
    # the damage reaches the field's rule, the qmat factors' and the zstd frames'
    wanted = {"R45-field", "R28-shape", "R29-zstd-content-size", "R31-steps", "R32-predictor"}
    assert wanted <= rules, rules


def _zstd_strictness(python: dict[str, Any], javascript: dict[str, Any]) -> bool:
    """A corrupt Zstandard frame that libzstd takes and fzstd refuses (R29), or the reverse
    (spec/FORMAT.md §6.1 allows both): the decoder that took it may then refuse the integers it
    got. Any other difference is a bug."""
    verdicts = [python, javascript]
    refused = [v for v in verdicts if v.get("rule") == "R29-zstd-content-size"]
    others = [v for v in verdicts if v.get("rule") != "R29-zstd-content-size"]
    later = {"R45-field", "R32-predictor"}
    return len(refused) == 1 and (others[0]["accepted"] or others[0].get("rule") in later)
