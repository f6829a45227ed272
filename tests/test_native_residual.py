"""The compiled core's corrections (§6.9, §8.1) against the pure-Python reference: the same
bits decoded, the same bytes encoded, and the same error (class, rule, field and message) on
every file, whether a conformance vector, a real sequence, or random and mutated ones."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import zstandard

from tests.support.sequences import load_shared_npz
from tools.generate.vectors import Parts
from tuckercodec import Decoder, MeshSequence, encode
from tuckercodec.errors import FormatError
from tuckercodec.format import residual
from tuckercodec.format.limits import DEFAULT_LIMITS
from tuckercodec.system import native

VECTORS = Path(__file__).resolve().parents[1] / "spec" / "vectors"
WITH_CORRECTIONS = sorted(p for p in VECTORS.glob("*.tkc") if b"RESD" in p.read_bytes())
VALID = [p for p in WITH_CORRECTIONS if p.name.startswith("v1.3")]


@pytest.fixture(autouse=True)
def _needs_core() -> None:
    if native.core() is None:
        pytest.skip("the compiled core is not installed (python -m tools.build_native)")


def _outcome(call: Callable[..., Any], *args: Any, **kwargs: Any) -> tuple[Any, ...]:
    """What a call gives, comparable bit for bit: its arrays' bytes, or its error's class,
    rule, field and message."""
    try:
        result = call(*args, **kwargs)
    except FormatError as error:
        return ("error", type(error).__name__, error.rule, error.field, str(error))
    return _comparable(result)


def _comparable(result: Any) -> tuple[Any, ...]:
    if isinstance(result, tuple):
        return tuple(_comparable(item) for item in result)
    if isinstance(result, np.ndarray):
        return ("array", result.dtype.str, result.shape, result.tobytes())
    return ("value", result)


def _assert_alike(call: Callable[..., Any], *args: Any, **kwargs: Any) -> tuple[Any, ...]:
    """The outcome of ``call(*args, **kwargs)`` with the compiled core, checked to be the pure
    Python reference's."""
    compiled = _outcome(call, *args, **kwargs)
    with native.pure_python():
        reference = _outcome(call, *args, **kwargs)
    assert compiled == reference
    return compiled


def _decode_all(data: bytes) -> Callable[[], Any]:
    def run() -> Any:
        decoder = Decoder(data)
        decoder.check()
        return decoder.positions(), decoder.frame(-1)

    return run


@pytest.mark.parametrize("path", WITH_CORRECTIONS, ids=lambda p: p.stem)
def test_every_vector_with_corrections_decodes_alike(path):
    _assert_alike(_decode_all(path.read_bytes()))


# -- mutated files ------------------------------------------------------------------------------


def _chunks_of(parts: Parts, section: int) -> tuple[residual.ResidualLayout, list[np.ndarray]]:
    entry, payload = parts.entries[section], parts.payloads[section]
    frames = parts.header["frames"]
    if entry["id"] != "RESD":  # RESD.s: the segment's frames
        number = int(entry["id"].split(".")[1])
        segment = parts.header["segments"][number]
        frames = segment["frames"] if isinstance(segment, dict) else segment[1]
    vertices = parts.header["vertices"]
    layout = residual.read_layout(entry, len(payload), frames, vertices, DEFAULT_LIMITS, "RESD")
    values = [
        residual.decode_chunk(payload, layout, n, vertices, "RESD")
        for n in range(len(layout.planes))
    ]
    return layout, values


#: Integers that reach every R41 check of every domain.
EXTREMES = np.array(
    [0, 1, -1, 2**32, -(2**32) - 1, 2**53 + 1, -(2**54) - 1, 2**62, -(2**63), 2**63 - 1,
     residual.FINITE32[1], residual.FINITE64[0], 45 * 9 * 10**14 * 2 + 2],
    dtype=np.int64,
)  # fmt: skip


def _mutate(data: bytes, rng: np.random.Generator) -> bytes:
    """The file with one RESD section changed: a parameter, some integers (repacked, so that
    only their values are wrong), or a byte of the payload (its CRC fixed)."""
    parts = Parts(data)
    sections = [n for n, e in enumerate(parts.entries) if e["id"].startswith("RESD")]
    section = int(rng.choice(sections))
    entry = parts.entries[section]
    kind = int(rng.integers(0, 4))
    if kind == 0:  # a parameter: any of §6.9's, to a value in range or not
        key = str(rng.choice(["domain", "step", "places", "digits", "exponent", "predict"]))
        choices: dict[str, list[Any]] = {
            "domain": [*residual.DOMAINS, "float16", 3],
            "step": [1e-9, 0.5, 1e300, -1.0, float("nan"), 2],
            "places": [0, 3, 22, 23, -1],
            "digits": [1, 6, 15, 16, 0],
            "exponent": [-1022, -60, 0, 40, 1022, 1023],
            "predict": [0, 1, 2],
        }
        entry[key] = choices[key][int(rng.integers(len(choices[key])))]
        for extra in ("places", "digits", "step"):  # a domain needs its scale
            entry.setdefault(extra, {"places": 3, "digits": 6, "step": 0.25}[extra])
    elif kind == 1:  # integers: small ones, or extremes, repacked
        layout, chunks = _chunks_of(parts, section)
        values = np.concatenate(chunks)
        flat = values.reshape(-1)
        picks = rng.integers(0, flat.size, size=int(rng.integers(1, 6)))
        if rng.random() < 0.5:
            flat[picks] += rng.integers(-1000, 1000, size=picks.size)
        else:
            flat[picks] = rng.choice(EXTREMES, size=picks.size)
        params, payload = residual.encode_section(
            values, layout.kind, 1, exponent=layout.exponent, predict=int(rng.integers(0, 2))
        )
        entry.update(params)
        parts.payloads[section] = payload
    elif kind == 2:  # a byte of a payload
        damaged = bytearray(parts.payloads[section])
        if damaged:
            damaged[int(rng.integers(len(damaged)))] ^= 1 << int(rng.integers(8))
        parts.payloads[section] = bytes(damaged)
    else:  # chunk_frames, or a chunk's planes
        if rng.random() < 0.5:
            entry["chunk_frames"] = int(rng.integers(1, 5))
        elif entry["chunks"]:
            number = int(rng.integers(len(entry["chunks"])))
            entry["chunks"][number][0] = int(rng.integers(0, 10))
    return parts.pack()


@pytest.mark.parametrize("path", VALID, ids=lambda p: p.stem)
def test_mutated_files_decode_alike(path):
    rng = np.random.default_rng(sum(path.name.encode()))
    data = path.read_bytes()
    kinds = set()
    for _ in range(60):
        outcome = _assert_alike(_decode_all(_mutate(data, rng)))
        kinds.add(outcome[0] if outcome[0] == "error" else outcome[0][0])
    assert "error" in kinds  # the mutations reach the checks, not only valid files


# -- the functions, on random values ------------------------------------------------------------

#: Values of every kind §6.9 meets: zeros of both signs, subnormals, the extremes of binary32
#: and binary64, decimals, and what is not finite.
SPECIAL = np.array(
    [0.0, -0.0, 5e-324, -2.2e-308, 1e-45, 3.4028234663852886e38, 3.5e38, 1.7976931348623157e308,
     -1.7976931348623157e308, 0.1, -0.125, 123456.789, 1e22, 9.999995, np.inf, -np.inf, np.nan],
)  # fmt: skip


def _random_domain(rng: np.random.Generator) -> residual.Domain:
    name = str(rng.choice(residual.DOMAINS))
    if name == residual.GRID:
        return residual.Domain(name, step=float(rng.choice([1e-6, 0.001, 0.37, 1e200])))
    if name in residual.SCALES:
        _, least, most = residual.SCALES[name]
        return residual.Domain(name, scale=int(rng.integers(least, most + 1)))
    return residual.Domain(name)


def _random_positions(rng: np.random.Generator, size: int) -> np.ndarray:
    scale = 10.0 ** rng.integers(-30, 30)
    values = rng.standard_normal(size) * scale
    if size and rng.random() < 0.5:
        values[rng.integers(0, size, size=3)] = rng.choice(SPECIAL, size=3)
    if rng.random() < 0.3:
        with np.errstate(over="ignore"):  # beyond binary32: infinities, as wanted
            values = values.astype(np.float32).astype(np.float64)
    return values


def _random_corrections(rng: np.random.Generator, size: int) -> np.ndarray:
    corrections = rng.integers(-3, 4, size=size, dtype=np.int64)
    if size and rng.random() < 0.4:
        corrections[rng.integers(0, size, size=2)] = rng.choice(EXTREMES, size=2)
    return corrections


def test_correct_is_alike_on_random_values():
    rng = np.random.default_rng(7)
    errors = 0
    for _ in range(3000):
        domain = _random_domain(rng)
        size = int(rng.integers(0, 40))
        exact = _random_positions(rng, size).reshape(-1, 1, 1) if size else np.empty((0, 1, 1))
        corrections = _random_corrections(rng, size).reshape(exact.shape)
        outcome = _assert_alike(residual.correct, exact, corrections, domain, "RESD")
        errors += outcome[0] == "error"
    assert 300 < errors < 2700  # both the valid and the refused are well covered


def test_ordered_integers_are_alike_on_random_values():
    rng = np.random.default_rng(8)
    for _ in range(2000):
        domain = _random_domain(rng)
        if domain.name == residual.GRID:
            continue
        values = _random_positions(rng, int(rng.integers(0, 40)))
        values = values[np.isfinite(values)]  # the encoder's input is finite
        _assert_alike(residual.ordered_in, values, domain)
        back = residual.ordered_in(values, domain)
        _assert_alike(residual.correct, values, back - back, domain, "input")


def test_chunks_restore_alike_from_random_planes():
    """Random byte planes, of every width, with and without prediction: the restored integers
    are the same (the zstd frame is read by the same code either way)."""
    rng = np.random.default_rng(9)
    for _ in range(1500):
        frames, vertices = int(rng.integers(1, 5)), int(rng.integers(0, 6))
        planes, predict = int(rng.integers(1, 9)), int(rng.integers(0, 2))
        count = frames * vertices * 3
        raw = rng.integers(0, 256, size=count * planes, dtype=np.uint8)
        if rng.random() < 0.5:  # mostly small integers, as real corrections are
            raw[count:] = 0
        payload = zstandard.ZstdCompressor(level=1, write_content_size=True).compress(raw.tobytes())
        layout = residual.ResidualLayout(
            residual.FLOAT64, None, predict, frames, (planes,), (0, len(payload)), frames
        )
        _assert_alike(residual.decode_chunk, payload, layout, 0, vertices, "RESD")


def test_sections_pack_alike():
    rng = np.random.default_rng(10)
    for _ in range(300):
        shape = (int(rng.integers(1, 7)), int(rng.integers(1, 5)), 3)
        values = rng.integers(-(2 ** int(rng.integers(1, 63))), 2**40, size=shape)
        values[rng.random(shape) < 0.05] = rng.choice(EXTREMES)
        chunk_frames = int(rng.integers(1, 4))
        domain = _random_domain(rng)
        _assert_alike(residual.encode_section, values, domain, 1, chunk_frames=chunk_frames)


# -- real data ----------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("name", "options"),
    [
        ("cloth-vellum.npz", {"lossless": True}),
        ("cloth-vellum.npz", {"max_error": "0.05%"}),
        ("samba.npz", {"lossless": True}),
        ("chicken.npz", {"max_error": "0.1%"}),
    ],
    ids=["cloth-lossless", "cloth-bound", "samba-lossless", "chicken-bound"],
)
def test_real_sequences_encode_and_decode_alike(name, options):
    vertices, faces = load_shared_npz(name)
    sequence = MeshSequence(vertices[:10], faces)
    compiled = encode(sequence, **options)
    with native.pure_python():
        reference = encode(sequence, **options)
    assert compiled == reference
    assert b"RESD" in compiled
    _assert_alike(_decode_all(compiled))
