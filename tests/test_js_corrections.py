"""The JavaScript decoder (tuckercodec/web/tkc/) on files with corrections (spec/FORMAT.md §6.9,
§8.1; format 1.3), in node.

Files made here by hand from the spec alone (tests/support/corrections.py: §8.1's P written
literally, e chosen to reach targets in each domain, the RESD section coded with 64-bit zigzag,
planes, chunks and predict 1), whole and in segments, decode to the spec's positions bit for
bit, in either frame order and through frameFloat32, in node and in the Python decoder; their
restored integers are e. The same files edited to break one rule of §6.9 fail with that rule in
both decoders. And files the CLI writes with --max-error and --lossless decode in node to the
Python decoder's bits, as do the real sequences lossless in the domain each gets (slow)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import tuckercodec
from tests.support.compressed import Parts, vector
from tests.support.corrections import (
    Corrections,
    exact_reconstruction,
    exponents_of,
    float_targets,
    grid_targets,
    ordered,
    spec_decode,
    with_corrections,
    wrap,
)
from tests.support.js_decoder import run_node
from tests.support.sequences import shared_file
from tuckercodec import EncodeOptions, FormatError
from tuckercodec.cli import main
from tuckercodec.format import residual

BASES = ["v1-wave-triangles", "v1.1-segments-shared", "v1.2-traverse-polygons-segments"]
DOMAINS = ["grid", "float32", "float64"]


def _corrections(base: str, domain: str, predict: int, seed: int) -> tuple[bytes, list[Any]]:
    """``base`` with corrections in ``domain``: (file, [(P, Corrections)] per segment)."""
    data = vector(base)
    rng = np.random.default_rng(seed)
    made = []
    for number, P in enumerate(exact_reconstruction(data)):
        if domain == "grid":
            step = 1e-4 * (number + 1)
            e, _ = grid_targets(P, step, rng)
            item = Corrections(e, "grid", step=step)
        else:
            e, _ = float_targets(P, 32 if domain == "float32" else 64, rng)
            item = Corrections(e, domain)
        item.predict = predict
        item.chunk_frames = [5, 1, 1 << 40][number % 3] if predict else [7, 100, 3][number % 3]
        item.extra_planes = number % 2
        made.append((P, item))
    return with_corrections(data, [c for _, c in made]), made


def _run(jobs: list[dict[str, Any]], tmp_path: Path) -> list[dict[str, Any]]:
    spec = tmp_path / "jobs.json"
    spec.write_text(json.dumps(jobs))
    return run_node("corrections.mjs", spec)


CASES = [(b, d, p) for b in BASES for d in DOMAINS for p in (0, 1)]


@pytest.fixture(scope="module")
def decoded(tmp_path_factory) -> dict[tuple[str, str, int], Any]:
    """Every case decoded by node: forward, backward, and through frameFloat32."""
    folder = tmp_path_factory.mktemp("corrections")
    jobs: list[dict[str, Any]] = []
    made = {}
    for n, case in enumerate(CASES):
        data, segments = _corrections(*case, seed=n)
        path = folder / f"case{n}.tkc"
        path.write_bytes(data)
        made[case] = (data, segments)
        jobs += [
            {"path": str(path), "out": str(folder / f"case{n}.{order}"), "order": order}
            for order in ("forward", "backward")
        ]
        jobs.append({"path": str(path), "out": str(folder / f"case{n}.f32"), "float32": True})
    results = _run(jobs, folder)
    out = {}
    for n, case in enumerate(CASES):
        out[case] = (made[case], results[3 * n : 3 * n + 3], folder, n)
    return out


def _read(path: Path, segments: list[Any]) -> tuple[np.ndarray, list[np.ndarray]]:
    raw = path.read_bytes()
    sizes = [P.size for P, _ in segments]
    total = sum(sizes)
    positions = np.frombuffer(raw[: 8 * total], "<f8")
    integers, at = [], 8 * total
    for size in sizes:
        integers.append(np.frombuffer(raw[at : at + 8 * size], "<i8"))
        at += 8 * size
    return positions, integers


@pytest.mark.parametrize("case", CASES, ids=["-".join(map(str, c)) for c in CASES])
def test_hand_made_file_decodes_bit_for_bit(decoded, case):
    (data, segments), results, folder, n = decoded[case]
    assert all(r["accepted"] for r in results), [r.get("message") for r in results]
    expected = np.concatenate([spec_decode(P, c).reshape(-1) for P, c in segments])
    # the reference decoder reads the spec as this file's writer did
    python = tuckercodec.decode(data).vertices.reshape(-1)
    assert np.array_equal(python.view("<u8"), expected.view("<u8"))
    for suffix in ("forward", "backward"):
        positions, integers = _read(folder / f"case{n}.{suffix}", segments)
        assert np.array_equal(positions.view("<u8"), expected.view("<u8")), suffix
        for got, (_, c) in zip(integers, segments, strict=True):
            assert np.array_equal(got, c.e.reshape(-1))
    # frameFloat32: the binary64 positions rounded once
    f32, _ = _read(folder / f"case{n}.f32", segments)
    with np.errstate(over="ignore"):  # the largest binary64 rounds to infinity
        rounded = expected.astype(np.float32).astype(np.float64)
    assert np.array_equal(f32.view("<u8"), rounded.view("<u8"))
    residual = results[0]["residual"]
    assert residual == [
        {
            "domain": c.domain,
            "step": c.step,
            "scale": None,
            "exponent": c.exponent,
            "predict": c.predict,
            "coder": 0,
            "codebooks": None,
            "chunkFrames": c.chunk_frames,
            "chunks": -(-P.shape[0] // c.chunk_frames),
        }
        for P, c in segments
    ]
    assert results[0]["version"] == "1.3"


# ------------------------------------------------------------------------------------------
# the decimal domains: the same bits as the Python decoder, over every decade and both ends

DECIMALS = (
    [("decimal-places", d) for d in (0, 3, 10, 22)]
    + [("decimal-digits", p) for p in (1, 6, 14, 15)]
    + [("decimal-digits-float32", p) for p in (1, 6, 9, 15)]
)


def _decimal_e(P: np.ndarray, domain: str, scale: int, rng: np.random.Generator) -> np.ndarray:
    """Integers e that move P to targets over the domain's whole range: near P, at both ends
    (k = +-2^53, o = -1-L and L), zeros of both signs, and every decade of decimal-digits."""
    flat = P.reshape(-1)
    if domain == "decimal-places":
        base = residual.places_ordered(flat, scale)
        limit = 2**53
        goal = base + rng.integers(-1000, 1000, size=base.size)
        ends = [limit, -limit, 0, 1, -1, limit - 1, -limit + 1]
    else:
        base = residual.digits_ordered(flat, scale)
        limit = residual.digits_largest(scale)
        goal = base + rng.integers(-1000, 1000, size=base.size)
        per_decade = 9 * 10 ** (scale - 1)
        decades = [1 + d * per_decade + int(rng.integers(per_decade)) for d in range(45)]
        ends = [limit, -1 - limit, 0, -1, 1, -2, *decades, *(-1 - o for o in decades)]
    goal = np.clip(goal, -1 - limit if domain == "decimal-digits" else -limit, limit)
    goal[7 : 7 + len(ends)] = ends
    return (goal - base).reshape(P.shape)


@pytest.mark.parametrize(("domain", "scale"), DECIMALS, ids=[f"{d}-{s}" for d, s in DECIMALS])
def test_decimal_domain_same_bits_as_python(tmp_path, domain, scale):
    data = vector("v1.1-segments-shared")
    rng = np.random.default_rng(scale)
    items = [
        Corrections(_decimal_e(P, domain, scale, rng), domain, scale=scale, predict=n % 2)
        for n, P in enumerate(exact_reconstruction(data))
    ]
    for item in items:
        item.chunk_frames = 5
    path = tmp_path / "decimal.tkc"
    path.write_bytes(with_corrections(data, items))
    (result,) = _run(
        [{"path": str(path), "out": str(tmp_path / "out"), "order": "backward"}], tmp_path
    )
    assert result["accepted"], result.get("message")
    assert result["residual"][0]["scale"] == scale
    expected = tuckercodec.decode(path).vertices.reshape(-1)
    size = expected.size
    positions = np.frombuffer((tmp_path / "out").read_bytes()[: 8 * size], "<u8")
    assert np.array_equal(positions, expected.view("<u8"))


# ------------------------------------------------------------------------------------------
# one rule broken at a time


def _grid_file(edit=None, *, base: str = "v1-wave-triangles", **fields: Any) -> bytes:
    """``base`` with grid corrections, the first segment's Corrections edited by ``fields``
    and the parts by ``edit(parts)`` before they are packed."""
    data = vector(base)
    items = []
    rng = np.random.default_rng(5)
    for P in exact_reconstruction(data):
        e, _ = grid_targets(P, 1e-3, rng)
        items.append(Corrections(e, "grid", step=1e-3, chunk_frames=4))
    e_last = fields.pop("e_last", None)
    if e_last is not None:  # the last value of the last chunk
        items[-1].e.reshape(-1)[-1] = e_last
    for key, value in fields.items():
        setattr(items[0], key, value)
    return with_corrections(data, items, edit=edit)


def _huge_u2(parts: Parts) -> None:
    """U2 so large that every product overflows: P of §8.1 is not finite."""
    parts.header["u2"] = [1e308] * 9


def _set(section_id: str, **params: Any):
    def edit(parts: Parts) -> None:
        index = parts.index(section_id)
        entry, payload = parts.sections[index]
        parts.sections[index] = ({**entry, **params}, payload)

    return edit


def _drop(key: str, section_id: str = "RESD"):
    def edit(parts: Parts) -> None:
        index = parts.index(section_id)
        entry, payload = parts.sections[index]
        parts.sections[index] = ({k: v for k, v in entry.items() if k != key}, payload)

    return edit


def _remove(section_id: str):
    def edit(parts: Parts) -> None:
        del parts.sections[parts.index(section_id)]

    return edit


def _clear_flag(parts: Parts) -> None:
    parts.flags &= ~4


def _chunks(change):
    """An edit of RESD's chunks table: ``change(chunks)`` on a copy of its lists."""

    def edit(parts: Parts) -> None:
        index = parts.index("RESD")
        entry, payload = parts.sections[index]
        chunks = [list(c) for c in entry["chunks"]]
        change(chunks)
        parts.sections[index] = ({**entry, "chunks": chunks}, payload)

    return edit


def _flip_last_byte(data: bytes) -> bytes:
    """RESD is the last section: a bit of its payload flipped, its CRC no longer matches."""
    return data[:-1] + bytes([data[-1] ^ 1])


def _e_file(domain: str, values: dict[int, Any], **fields: Any) -> bytes:
    """v1-wave-triangles with corrections e = 0 except ``values`` (j -> e, or a function of
    P[j] giving e)."""
    data = vector("v1-wave-triangles")
    (P,) = exact_reconstruction(data)
    e = np.zeros(P.shape, dtype=np.int64)
    for j, v in values.items():
        e.reshape(-1)[j] = v(P.reshape(-1)[j]) if callable(v) else v
    return with_corrections(data, [Corrections(e, domain, **fields)])


def _to32(target: int):
    return lambda p: target - int(ordered(np.array([p], dtype=np.float32), 32)[0])


def _to64(target: int):
    return lambda p: wrap(target - int(ordered(np.array([p]), 64)[0]))


def _set_planes(chunks: list[list[Any]], value: Any) -> None:
    chunks[1][0] = value


def _set_length(chunks: list[list[Any]], value: Any) -> None:
    chunks[1][1] = value


#: name -> (the file, the rule it breaks, the error class)
INVALID: dict[str, tuple[Any, str, str]] = {
    "flag-without-resd": (
        lambda: _grid_file(_remove("RESD")),
        "R26-required-section-missing",
        "FormatError",
    ),
    "segment-resd-missing": (
        lambda: _grid_file(_remove("RESD.1"), base="v1.1-segments-shared"),
        "R26-required-section-missing",
        "FormatError",
    ),
    "resd-without-flag": (
        lambda: _grid_file(_clear_flag),
        "R24-unknown-critical-section",
        "UnsupportedVersionError",
    ),
    "resd-in-segmented-file": (
        lambda: _grid_file(_set("RESD.2", id="RESD"), base="v1.1-segments-shared"),
        "R24-unknown-critical-section",
        "UnsupportedVersionError",
    ),
    "resd-ancillary": (
        lambda: _grid_file(_set("RESD", critical=False)),
        "R27-criticality",
        "FormatError",
    ),
    "resd-codec": (
        lambda: _grid_file(_set("RESD", codec="qmat")),
        "R25-unknown-codec",
        "UnsupportedVersionError",
    ),
    "crc": (lambda: _flip_last_byte(_grid_file()), "R19-section-crc", "ChecksumError"),
    "chunk-zstd": (
        lambda: _grid_file(_chunks(lambda c: c[0].__setitem__(0, c[0][0] + 1))),
        "R29-zstd-content-size",
        "FormatError",
    ),
    "grid-e-beyond-2^53": (
        lambda: _e_file("grid", {40: 2**53 + 1}, step=1e-3),
        "R41-residual-value",
        "FormatError",
    ),
    "grid-e-below-2^53": (
        lambda: _e_file("grid", {41: -(2**53) - 1}, step=1e-3),
        "R41-residual-value",
        "FormatError",
    ),
    "grid-not-finite": (
        lambda: _e_file("grid", {7: 2**53}, step=1e300),
        "R41-residual-value",
        "FormatError",
    ),
    "float32-e-beyond-2^32": (
        lambda: _e_file("float32", {3: -(2**32) - 1}),
        "R41-residual-value",
        "FormatError",
    ),
    "float32-infinity": (
        lambda: _e_file("float32", {5: _to32(2139095040)}),
        "R41-residual-value",
        "FormatError",
    ),
    "float32-minus-infinity": (
        lambda: _e_file("float32", {5: _to32(-2139095041)}),
        "R41-residual-value",
        "FormatError",
    ),
    "float64-infinity": (
        lambda: _e_file("float64", {9: _to64(9218868437227405312)}),
        "R41-residual-value",
        "FormatError",
    ),
    "float64-nan": (
        lambda: _e_file("float64", {11: _to64(9218868437227405313)}),
        "R41-residual-value",
        "FormatError",
    ),
    "float64-minus-infinity": (  # -infinity's ordered integer, one below -max's
        lambda: _e_file("float64", {10: _to64(-9218868437227405313)}),
        "R41-residual-value",
        "FormatError",
    ),
    # §8.1's weights: not finite (U2 so large that W overflows), or too large for the exponent
    # (R·max|w| beyond 2^53 when e is three less than the least that fits)
    "grid-weights-not-finite": (
        lambda: _grid_file(_huge_u2),
        "R41-residual-value",
        "FormatError",
    ),
    "weights-beyond-2^53": (
        lambda: with_corrections(
            vector("v1-wave-triangles"),
            [
                Corrections(
                    np.zeros((24, 81, 3), np.int64),
                    "grid",
                    step=1e-3,
                    exponent=exponents_of(vector("v1-wave-triangles"))[0] - 3,
                )
            ],
        ),
        "R41-residual-value",
        "FormatError",
    ),
}
for _name, _edit in {
    "domain": _set("RESD", domain="float16"),
    "domain-missing": _drop("domain"),
    "step-int": _set("RESD", step=1),
    "step-zero": _set("RESD", step=0.0),
    "step-nan": _set("RESD", step=float("nan")),
    "step-missing": _drop("step"),
    "predict": _set("RESD", predict=2),
    "predict-bool": _set("RESD", predict=True),
    "chunk-frames-zero": _set("RESD", chunk_frames=0),
    "chunk-frames-float": _set("RESD", chunk_frames=4.0),
    "chunks-count": _set("RESD", chunks=[[1, 10]]),
    "chunks-not-array": _set("RESD", chunks={"a": 1}),
    "chunks-planes-zero": _chunks(lambda c: _set_planes(c, 0)),
    "chunks-planes-nine": _chunks(lambda c: _set_planes(c, 9)),
    "chunks-planes-float": _chunks(lambda c: _set_planes(c, 1.0)),
    "chunks-length-negative": _chunks(lambda c: _set_length(c, -1)),
    "chunks-length-sum": _chunks(lambda c: _set_length(c, c[1][1] + 1)),
    "chunks-entry-three": _chunks(lambda c: c[1].append(0)),
    "exponent-1023": _set("RESD", exponent=1023),
    "exponent-minus-1023": _set("RESD", exponent=-1023),
    "exponent-float": _set("RESD", exponent=0.0),
    "exponent-missing": _drop("exponent"),
}.items():
    INVALID[f"R40-{_name}"] = ((lambda e=_edit: _grid_file(e)), "R40-residual", "FormatError")

_DIGITS_L6 = 45 * 9 * 10**5  # L of decimal-digits with 6 digits
for _name, (_make, _rule) in {
    "R40-places-23": (lambda: _e_file("decimal-places", {}, scale=23), "R40-residual"),
    "R40-places-negative": (lambda: _e_file("decimal-places", {}, scale=-1), "R40-residual"),
    "R40-digits-0": (lambda: _e_file("decimal-digits", {}, scale=0), "R40-residual"),
    "R40-digits-16": (lambda: _e_file("decimal-digits", {}, scale=16), "R40-residual"),
    "R40-places-missing": (
        lambda: with_corrections(
            vector("v1-wave-triangles"),
            [Corrections(np.zeros((24, 81, 3), np.int64), "decimal-places", scale=2)],
            edit=_drop("places"),
        ),
        "R40-residual",
    ),
    "R40-digits-float": (
        lambda: with_corrections(
            vector("v1-wave-triangles"),
            [Corrections(np.zeros((24, 81, 3), np.int64), "decimal-digits", scale=6)],
            edit=_set("RESD", digits=6.0),
        ),
        "R40-residual",
    ),
    "places-e-beyond-2^54": (
        lambda: _e_file("decimal-places", {4: 2**54 + 1}, scale=3),
        "R41-residual-value",
    ),
    "places-k-beyond-2^53": (
        lambda: _e_file("decimal-places", {4: 2**53 + 2**40}, scale=3),
        "R41-residual-value",
    ),
    "digits-e-beyond-2L+1": (
        lambda: _e_file("decimal-digits", {8: -(2 * _DIGITS_L6 + 2)}, scale=6),
        "R41-residual-value",
    ),
    "digits-o-beyond-L": (
        lambda: _e_file("decimal-digits", {8: 2 * _DIGITS_L6}, scale=6),
        "R41-residual-value",
    ),
}.items():
    INVALID[_name] = (_make, _rule, "FormatError")

# e = -2^63 is beyond 2^53 (R41): numpy's abs of it overflows to itself, which the reference
# decoder once let through
INVALID["grid-e-minus-2^63"] = (
    lambda: _e_file("grid", {5: -(2**63)}, step=1e-3),
    "R41-residual-value",
    "FormatError",
)


@pytest.fixture(scope="module")
def refused(tmp_path_factory) -> dict[str, dict[str, Any]]:
    folder = tmp_path_factory.mktemp("refused")
    jobs = []
    for name, (make, _, _) in INVALID.items():
        path = folder / f"{name}.tkc"
        path.write_bytes(make())
        jobs.append({"path": str(path)})
    return dict(zip(INVALID, _run(jobs, folder), strict=True))


@pytest.mark.parametrize("name", list(INVALID))
def test_broken_rule_is_reported(refused, name):
    """The JavaScript decoder reports the rule, and so does the Python one."""
    make, rule, kind = INVALID[name]
    got = refused[name]
    assert not got.get("crashed"), got["message"]
    assert not got["accepted"], f"accepted a file that breaks {rule}"
    assert (got["rule"], got["kind"]) == (rule, kind), got["message"]
    with pytest.raises(FormatError) as python:
        tuckercodec.decode(make())
    assert (python.value.rule, type(python.value).__name__) == (rule, kind)


def test_chunk_size_limit(tmp_path):
    """Each chunk's decompressed size N_c·P against max_section_bytes (R21), after R40."""
    data = _grid_file(extra_planes=7)  # 8 planes in the first chunk of 4 frames
    path = tmp_path / "a.tkc"
    path.write_bytes(data)
    K = 81
    limit = 4 * K * 3 * 8 - 1
    jobs = [
        {"path": str(path), "limits": {"max_section_bytes": limit}},
        {"path": str(path), "limits": {"max_section_bytes": limit + 1}},
    ]
    over, under = _run(jobs, tmp_path)
    assert (over["rule"], over["kind"]) == ("R21-header-limit", "LimitError"), over
    assert under["accepted"], under.get("message")


# ------------------------------------------------------------------------------------------
# files the reference encoder writes: the same bits as the Python decoder

CLOTH = Path(__file__).resolve().parents[1] / "tuckercodec" / "data" / "cloth-vellum.npz"
ENCODINGS = {
    "max-error": ["--max-error", "0.1%"],
    "lossless": ["--lossless"],
    "max-error-segments": ["--max-error", "0.1%", "--segment-frames", "20"],
    "lossless-segments": ["--lossless", "--segment-frames", "20"],
}


@pytest.fixture(scope="module")
def encoded(tmp_path_factory) -> dict[str, Any]:
    """cloth-vellum encoded by the CLI in each mode, then decoded by node in both frame orders
    (and through frameFloat32)."""
    folder = tmp_path_factory.mktemp("encoded")
    paths = {}
    jobs: list[dict[str, Any]] = []
    for name, options in ENCODINGS.items():
        path = folder / f"{name}.tkc"
        assert main(["encode", str(CLOTH), "-o", str(path), *options]) == 0
        paths[name] = path
        jobs += [
            {"path": str(path), "out": str(folder / f"{name}.{order}"), "order": order}
            for order in ("forward", "backward")
        ]
        jobs.append({"path": str(path), "out": str(folder / f"{name}.f32"), "float32": True})
    results = _run(jobs, folder)
    return {
        name: (paths[name], results[3 * n : 3 * n + 3], folder) for n, name in enumerate(ENCODINGS)
    }


@pytest.mark.parametrize("name", list(ENCODINGS))
def test_python_encoded_file_same_bits_as_python(encoded, name):
    path, results, folder = encoded[name]
    assert all(r["accepted"] for r in results), [r.get("message") for r in results]
    # 1.3, 1.6 where the encoder found a position factor smaller adaptively coded, 1.7 where
    # it found corrections so (§6.9's coder 1, flag bit 4), 1.9 where it found the faces' new
    # vertices smaller as places in a uniform stream (§6.8's ranks 1: the cloth's vertex order
    # is not its walk's)
    version, found = results[0]["version"], results[0]["residual"]
    assert version in ("1.3", "1.6", "1.7", "1.9") and found, "the encoder wrote no corrections"
    flags = Parts(path.read_bytes()).flags
    assert bool(flags & residual.ADAPTIVE_CORRECTIONS) == any(r["coder"] == 1 for r in found)
    expected = tuckercodec.decode(path).vertices
    assert expected.dtype == np.float64
    size = expected.size
    for suffix in ("forward", "backward"):
        positions = np.frombuffer((folder / f"{name}.{suffix}").read_bytes()[: 8 * size], "<u8")
        assert np.array_equal(positions, expected.reshape(-1).view("<u8")), suffix
    f32 = np.frombuffer((folder / f"{name}.f32").read_bytes()[: 8 * size], "<f8")
    assert np.array_equal(f32, expected.reshape(-1).astype(np.float32).astype(np.float64))
    error = results[0]["error"]
    if name.startswith("lossless"):
        with np.load(CLOTH) as original:
            assert np.array_equal(expected, original["V"].astype(np.float64))
        assert error["lossless"] is True
    else:
        assert {r["domain"] for r in results[0]["residual"]} == {"grid"}
        assert error["targetMaxDistance"] is not None


@pytest.mark.slow
@pytest.mark.parametrize("name", ["horse-gallop"])
def test_real_sequence_lossless_same_bits_as_python(tmp_path, name):
    """A real sequence lossless in the domain the encoder picks for it (horse gallop, read from
    OBJ text: decimals of 6 significant digits): node decodes the input's bits, as the Python
    decoder does. (Every other domain has its vector and its hand-made files above; chicken and
    samba add a minute to every run and no code path.)"""
    sequence = tuckercodec.load_sequence(shared_file(name), progress=False)
    path = tmp_path / "lossless.tkc"
    path.write_bytes(tuckercodec.encode(sequence, options=EncodeOptions(lossless=True)))
    (result,) = _run([{"path": str(path), "out": str(tmp_path / "out")}], tmp_path)
    assert result["accepted"], result.get("message")
    expected = tuckercodec.decode(path).vertices
    got = np.frombuffer((tmp_path / "out").read_bytes()[: 8 * expected.size], "<u8")
    assert np.array_equal(got, expected.reshape(-1).view("<u8"))
    assert np.array_equal(expected, sequence.vertices)
