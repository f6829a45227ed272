"""The JavaScript decoder's codebooks (format 1.8, spec/FORMAT.md §6.9: RESD's ``codebooks``,
preamble flag bit 5, rule R47), in node.

Three kinds of file. Sequences whose coordinates take few distinct values (a sheet on a coarse
grid, in each lossless domain the encoder picks, segmented too, and chicken, a real float64
cache), encoded lossless by the reference encoder, which gives them codebooks; and the same
files with their chunks re-coded as zstd planes (``coder`` 0, ``predict`` 0 or 1, chunks of a
few frames), the codebooks' bytes kept. Then files made by hand from the spec alone, in every
domain but the grid: for each axis a codebook of chosen ordered integers (ties between two
entries, entries at both ends of the domain's range, so that the nearest-entry gaps pass 2^63),
e = t - j for a chosen position t, and the position the value of C[t]; and codebooks of one,
two and 64 neighbouring entries, where the decoder's index of midpoints is at its smallest
(tests/js/codebooks.test.mjs tests that index alone). Node must decode every one to the bits of
the Python decoder (and of the input, or of C[t]). Last, edits that break one rule of
``codebooks``, of a codebook's frame or entries, or of t, must get the Python decoder's verdict
and the rule named here.
"""

from __future__ import annotations

import bisect
import dataclasses
import itertools
import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import zstandard

import tuckercodec
from tests.support.compressed import Parts, vector, with_preamble
from tests.support.corrections import (
    Corrections,
    exact_reconstruction,
    from_ordered,
    ordered,
    with_corrections,
    wrap,
)
from tests.support.js_decoder import compare_verdicts, run_node
from tests.support.sequences import load_shared_npz
from tuckercodec.format import residual
from tuckercodec.format.limits import DEFAULT_LIMITS
from tuckercodec.io.samples import sheet_triangles, wave_sheet

FLAG_ADAPTIVE_CORRECTIONS = 1 << 4
FLAG_CODEBOOKS = 1 << 5
R40, R41, R47, R29 = "R40-residual", "R41-residual-value", "R47-codebook", "R29-zstd-content-size"
#: The ordered integers each lossless domain allows (§6.9, R47), p or d given where it matters.
RANGES = {
    "float32": (-2139095040, 2139095039),
    "float64": (-9218868437227405312, 9218868437227405311),
    "decimal-places": (-(2**53), 2**53),
}


def _digits_bound(digits: int) -> int:
    return 405 * 10 ** (digits - 1)


def _range(domain: str, scale: int) -> tuple[int, int]:
    if domain in RANGES:
        return RANGES[domain]
    return -1 - _digits_bound(scale), _digits_bound(scale)


def _run(jobs: list[dict[str, Any]], folder: Path) -> list[dict[str, Any]]:
    spec = folder / "jobs.json"
    spec.write_text(json.dumps(jobs))
    return run_node("corrections.mjs", spec)


def _decode_all(files: dict[str, bytes], folder: Path) -> dict[str, tuple[dict[str, Any], Any]]:
    """Each file decoded by node in one run (checked whole, then every frame alone, backward):
    its verdict and its positions as uint64 bits (None if refused)."""
    jobs = []
    for name, data in files.items():
        path = folder / f"{name}.tkc"
        path.write_bytes(data)
        jobs.append({"path": str(path), "out": str(folder / f"{name}.out"), "order": "backward"})
    results = _run(jobs, folder)
    out = {}
    for name, result in zip(files, results, strict=True):
        bits = None
        if result["accepted"]:
            count = result["frames"] * result["vertices"] * 3
            bits = np.frombuffer((folder / f"{name}.out").read_bytes()[: 8 * count], "<u8")
        out[name] = (result, bits)
    return out


def _python_bits(data: bytes) -> np.ndarray:
    return tuckercodec.decode(data).vertices.reshape(-1).view("<u8")


def _residual_entries(data: bytes) -> list[dict[str, Any]]:
    return [entry for entry, _ in Parts(data).sections if entry["codec"] == "residual"]


# ------------------------------------------------------------------------------------------
# the reference encoder's codebooks, and the same with zstd chunks


def _sheet(frames: int = 20, grid: int = 8) -> np.ndarray:
    return wave_sheet(frames, grid)


#: name -> (the positions, encode options). Which domain each gets is the encoder's choice
#: (test_encoded_cases_cover_the_domains checks that they take several).
ENCODED: dict[str, tuple[Any, dict[str, Any]]] = {
    "sixty-fourths": (lambda: np.round(_sheet() * 64) / 64, {}),
    "sixty-fourths-of-pi": (lambda: np.round(_sheet() * 64) * (np.pi / 64), {}),
    "hundredths": (lambda: np.round(_sheet() * 100) / 100, {}),
    "hundredths-float32": (lambda: (np.round(_sheet() * 100) / 100).astype(np.float32), {}),
    "thousandths-float32": (lambda: (np.round(_sheet() * 1000) / 1000).astype(np.float32), {}),
    # a codebook on z alone: x and y take every value
    "one-axis": (
        lambda: np.concatenate([_sheet()[..., :2], np.round(_sheet()[..., 2:] * 8) / 8], axis=2),
        {},
    ),
    "segments": (
        lambda: np.round(_sheet(frames=30) * 64) * (np.pi / 64),
        {"segment_frames": 10},
    ),
}


def _encoded(name: str) -> tuple[bytes, np.ndarray]:
    make, options = ENCODED[name]
    positions = np.asarray(make())
    sequence = tuckercodec.MeshSequence(positions, sheet_triangles(8))
    return tuckercodec.encode(sequence, lossless=True, **options), positions


def _stored_e(data: bytes, entry: dict[str, Any], payload: bytes) -> np.ndarray:
    """A section's restored integers e, (F', K, 3), by the reference's own chunk decoder."""
    parts = Parts(data)
    K = int(parts.header["vertices"])
    segments = parts.header.get("segments")
    number = int(entry["id"].partition(".")[2] or 0)
    frames = int(segments[number]["frames"]) if segments else int(parts.header["frames"])
    where = entry["id"]
    layout = residual.read_layout(
        entry, len(payload), frames, K, DEFAULT_LIMITS, where,
        adaptive_corrections=True, codebooks=True,
    )  # fmt: skip
    chunks = [
        residual.decode_chunk(payload, layout, c, K, where) for c in range(len(layout.planes))
    ]
    return np.concatenate(chunks)


def zstd_twin(data: bytes, predict: int, chunk_frames: int, extra_planes: int = 0) -> bytes:
    """``data`` with every RESD chunk re-coded as zstd planes (§6.9), with ``predict`` and
    ``chunk_frames``; the codebooks and their bytes kept."""
    parts = Parts(data)
    for index, (entry, payload) in enumerate(parts.sections):
        if entry["codec"] != "residual":
            continue
        e = _stored_e(data, entry, payload)
        books = sum(length for _, _, length in entry.get("codebooks", []))
        item = Corrections(
            e, entry["domain"], scale=entry.get("places", entry.get("digits", 0)), predict=predict,
            chunk_frames=chunk_frames, extra_planes=extra_planes, exponent=entry["exponent"],
        )  # fmt: skip
        new_entry, chunks = item.section(entry["id"], e.shape[0])
        new_entry = {**new_entry, "codebooks": entry["codebooks"]}
        parts.sections[index] = (new_entry, payload[:books] + chunks)
    flags = parts.flags & ~FLAG_ADAPTIVE_CORRECTIONS
    return with_preamble(parts.pack(), flags=flags)


@pytest.fixture(scope="module")
def encoded(tmp_path_factory) -> dict[str, Any]:
    """Every encoded case and its zstd twins, decoded by node in one run."""
    folder = tmp_path_factory.mktemp("encoded")
    files, inputs = {}, {}
    for n, name in enumerate(ENCODED):
        data, positions = _encoded(name)
        inputs[name] = positions
        files[name] = data
        files[f"{name}.zstd"] = zstd_twin(data, predict=n % 2, chunk_frames=[3, 1, 7][n % 3])
        files[f"{name}.zstd-wide"] = zstd_twin(
            data, predict=1 - n % 2, chunk_frames=1 << 20, extra_planes=8
        )
    return {"files": files, "inputs": inputs, "decoded": _decode_all(files, folder)}


@pytest.mark.parametrize("name", list(ENCODED))
def test_encoded_codebooks_decode_to_the_inputs_bits(encoded, name):
    expected = np.asarray(encoded["inputs"][name], dtype=np.float64).reshape(-1).view("<u8")
    for variant in (name, f"{name}.zstd", f"{name}.zstd-wide"):
        data = encoded["files"][variant]
        result, bits = encoded["decoded"][variant]
        assert result["accepted"], (variant, result.get("message"))
        assert result["version"] == "1.8"
        # the encoder gave the case codebooks
        entries = _residual_entries(data)
        assert all(any(count for count, _, _ in e["codebooks"]) for e in entries), entries
        counts = [[count for count, _, _ in e["codebooks"]] for e in entries]
        assert [r["codebooks"] for r in result["residual"]] == counts
        coders = [r["coder"] for r in result["residual"]]
        assert coders == [e.get("coder", 0) for e in entries]
        assert variant == name or set(coders) == {0}
        assert np.array_equal(bits, expected), variant
        assert np.array_equal(_python_bits(data), expected), variant


def test_encoded_cases_cover_the_domains(encoded):
    """The encoded cases take codebooks in several domains, and some in adaptive chunks (if
    the encoder's choices change so that they do not, change the cases: the hand-made files
    below cover every domain regardless)."""
    entries = [e for name in ENCODED for e in _residual_entries(encoded["files"][name])]
    assert {"float32", "float64", "decimal-digits"} <= {e["domain"] for e in entries}
    assert any(e.get("coder") == 1 for e in entries)


@pytest.mark.slow
@pytest.mark.parametrize("frames", [40, 400])
def test_chicken_lossless_codebooks_same_bits_as_python(tmp_path, frames):
    """Chicken (float64 copies of 17-digit text): the encoder gives it codebooks in the domain
    decimal-places; node decodes the input's bits, as the Python decoder does, the encoder's
    file and its zstd twin alike."""
    V, F = load_shared_npz("chicken.npz")
    sequence = tuckercodec.MeshSequence(V[:frames], F)
    data = tuckercodec.encode(sequence, lossless=True)
    entries = _residual_entries(data)
    assert any(count for e in entries for count, _, _ in e.get("codebooks", [])), entries
    files = {"chicken": data, "chicken.zstd": zstd_twin(data, predict=1, chunk_frames=16)}
    expected = sequence.vertices.reshape(-1).view("<u8")
    for name, (result, bits) in _decode_all(files, tmp_path).items():
        assert result["accepted"], result.get("message")
        assert np.array_equal(bits, expected), name
        assert np.array_equal(_python_bits(files[name]), expected), name


# ------------------------------------------------------------------------------------------
# codebooks made by hand from the spec: every domain, ties, the ends of the ranges


def spec_nearest(book: list[int], b: int) -> int:
    """j of §6.9, literally: the largest index with C[j] <= b (0 if none), or j + 1 where
    C[j + 1] - b < b - C[j] (exact Python ints; a tie keeps j)."""
    j = bisect.bisect_right(book, b) - 1
    if j < 0:
        return 0
    if j + 1 < len(book) and book[j + 1] - b < b - book[j]:
        return j + 1
    return j


def base_of(P: np.ndarray, domain: str, scale: int) -> np.ndarray:
    """b of §6.9 for every value of P (int64, P's shape)."""
    if domain == "float32":
        with np.errstate(over="ignore"):
            return ordered(P.astype(np.float32), 32).reshape(P.shape)
    if domain == "float64":
        return ordered(P, 64).reshape(P.shape)
    if domain == "decimal-places":
        return residual.places_ordered(P, scale)
    return residual.digits_ordered(P, scale)


def value_of(o: np.ndarray, domain: str, scale: int) -> np.ndarray:
    """The position an ordered integer o stands for (§6.9), float64."""
    if domain in ("float32", "float64"):
        bits = 32 if domain == "float32" else 64
        return from_ordered(o.reshape(-1), bits).astype(np.float64).reshape(o.shape)
    if domain == "decimal-places":
        return residual.places_values(o, scale)
    values = residual.digits_values(o, scale)
    if domain == "decimal-digits-float32":
        return values.astype(np.float32).astype(np.float64)
    return values


def book_bytes(book: list[int], extra_planes: int = 0) -> tuple[list[int], bytes]:
    """A codebook's ``[count, planes, length]`` and zstd frame (§6.9): d[0] = C[0], d[m] =
    C[m] - C[m - 1] wrapped to 64 bits, zigzagged, in byte planes."""
    d = np.array([wrap(book[0])] + [wrap(b - a) for a, b in itertools.pairwise(book)], np.int64)
    u = (d.view(np.uint64) << np.uint64(1)) ^ (d >> 63).view(np.uint64)
    planes = min(max(1, (int(u.max()).bit_length() + 7) // 8) + extra_planes, 8)
    raw = b"".join(
        ((u >> np.uint64(8 * p)) & np.uint64(0xFF)).astype(np.uint8).tobytes()
        for p in range(planes)
    )
    frame = zstandard.ZstdCompressor(level=3, write_content_size=True).compress(raw)
    return [len(book), planes, len(frame)], frame


def _book_for(
    bases: np.ndarray, low: int, high: int, rng: np.random.Generator, anywhere: int, ends: bool
) -> list[int]:
    """An axis's codebook: both ends of the range (with ``ends``), some of the axis's own b,
    pairs b - d and b + d around others (ties, where nothing falls between), and ``anywhere``
    more."""
    values = [int(v) for v in bases.reshape(-1)]
    entries = {low, high} if ends else set()
    entries |= {values[i] for i in rng.choice(len(values), size=min(20, len(values)))}
    for i in rng.choice(len(values), size=8):
        d = int(rng.integers(1, 50))
        entries |= {values[i] - d, values[i] + d}
    entries |= {int(v) for v in rng.integers(low, high, size=anywhere, endpoint=True)}
    return sorted(v for v in entries if low <= v <= high)


@dataclasses.dataclass
class HandMade:
    """A hand-made file with codebooks, the positions it must decode to, and how many values
    took a tie between two entries, an entry at an end of the codebook, or had b outside it."""

    data: bytes
    expected: np.ndarray
    ties: int = 0
    ends: int = 0
    outside: int = 0


def hand_made(
    base: str,
    domain: str,
    scale: int = 0,
    *,
    predict: int = 0,
    chunk_frames: int = 1 << 30,
    extra_planes: int = 0,
    axes: tuple[int, ...] = (0, 1, 2),
    seed: int = 0,
    anywhere: int = 5,
    ends: bool = True,
    books_hook: Any = None,
    e_hook: Any = None,
    book_of: Any = None,
) -> HandMade:
    """``base`` with corrections in ``domain`` through a codebook on each of ``axes`` (e = 0 on
    the others). ``books_hook(axis, C)`` may change a codebook after e is chosen, ``e_hook(e, j,
    n)`` e itself (j the nearest entries, n the entries), to break a rule. ``book_of(b)`` gives
    each codebook from the axis's b instead of :func:`_book_for`."""
    data = vector(base)
    rng = np.random.default_rng(seed)
    low, high = _range(domain, scale)
    made = HandMade(b"", np.empty(0))
    items, all_books, expected = [], [], []
    for P in exact_reconstruction(data):
        b = base_of(P, domain, scale)
        e = np.zeros(P.shape, np.int64)
        o = b.copy()
        books: list[list[int] | None] = [None, None, None]
        for x in axes:
            if book_of is not None:
                book = book_of(b[..., x])
            else:
                book = _book_for(b[..., x], low, high, rng, anywhere, ends)
            flat = [int(v) for v in b[..., x].reshape(-1)]
            j = np.array([spec_nearest(book, v) for v in flat])
            made.outside += sum(v < book[0] or v > book[-1] for v in flat)
            for v in flat:
                k = bisect.bisect_right(book, v) - 1
                made.ties += int(0 <= k < len(book) - 1 and book[k + 1] - v == v - book[k])
            t = np.clip(j + rng.integers(-3, 4, size=j.size), 0, len(book) - 1)
            t[rng.choice(t.size, size=4)] = [0, len(book) - 1, 0, len(book) - 1]
            made.ends += int(np.count_nonzero((t == 0) | (t == len(book) - 1)))
            steps = (t - j).astype(np.int64)
            if e_hook is not None:
                e_hook(steps, j, len(book))
            e[..., x] = steps.reshape(b.shape[:2])
            o[..., x] = np.array([book[i] for i in t], np.int64).reshape(b.shape[:2])
            books[x] = books_hook(x, book) if books_hook is not None else book
        expected.append(value_of(o, domain, scale))
        all_books.append(books)
        items.append(
            Corrections(e, domain, scale=scale, predict=predict, chunk_frames=chunk_frames,
                        extra_planes=extra_planes)
        )  # fmt: skip

    def add_books(parts: Parts) -> None:
        sections = [
            n for n, (entry, _) in enumerate(parts.sections) if entry["codec"] == "residual"
        ]
        for index, books in zip(sections, all_books, strict=True):
            entry, payload = parts.sections[index]
            table, head = [], b""
            for book in books:
                param, frame = book_bytes(book, extra_planes) if book else ([0, 0, 0], b"")
                table.append(param)
                head += frame
            parts.sections[index] = ({**entry, "codebooks": table}, head + payload)

    made.data = with_corrections(data, items, edit=add_books)
    made.expected = np.concatenate([v.reshape(-1) for v in expected])
    return made


def _middle(bases: np.ndarray) -> int:
    return int(np.sort(bases.reshape(-1))[bases.size // 2])


def _one_entry(bases: np.ndarray) -> list[int]:
    """A codebook of one entry: no midpoint, every b's j is 0."""
    return [_middle(bases)]


def _two_entries(bases: np.ndarray) -> list[int]:
    """Two entries either side of one b: a tie there, and one midpoint."""
    return [_middle(bases) - 5, _middle(bases) + 5]


def _neighbours(bases: np.ndarray) -> list[int]:
    """64 entries one apart around one b: a span narrower than the midpoints are many."""
    return list(range(_middle(bases) - 32, _middle(bases) + 32))


#: name -> hand_made's arguments
HAND_MADE: dict[str, tuple[tuple[Any, ...], dict[str, Any]]] = {
    "float32": (("v1-wave-triangles", "float32"), {"chunk_frames": 5}),
    "float32-wide": (("v1-wave-triangles", "float32"), {"extra_planes": 8, "predict": 1}),
    "float64": (("v1-wave-triangles", "float64"), {"predict": 1}),
    "float64-segments": (
        ("v1.1-segments-shared", "float64"),
        {"axes": (0, 2), "chunk_frames": 3, "seed": 1},
    ),
    # entries near the values alone: some b below the first entry or above the last
    "float64-inside": (("v1-wave-triangles", "float64"), {"anywhere": 0, "ends": False}),
    "digits-15-inside": (
        ("v1-wave-triangles", "decimal-digits", 15),
        {"anywhere": 0, "ends": False, "chunk_frames": 6},
    ),
    "places-3": (("v1-wave-triangles", "decimal-places", 3), {"chunk_frames": 4}),
    "places-22": (("v1-wave-triangles", "decimal-places", 22), {"predict": 1}),
    "digits-4": (("v1-wave-triangles", "decimal-digits", 4), {"axes": (1,)}),
    "digits-15": (("v1-wave-triangles", "decimal-digits", 15), {"predict": 1, "seed": 2}),
    "digits-float32-7": (
        ("v1.1-segments-shared", "decimal-digits-float32", 7),
        {"chunk_frames": 2, "seed": 3},
    ),
    # codebooks of 1, 2 and 64 entries (one apart): the index of midpoints at its smallest
    "float64-one-entry": (("v1-wave-triangles", "float64"), {"book_of": _one_entry}),
    "places-3-two-entries": (
        ("v1-wave-triangles", "decimal-places", 3),
        {"book_of": _two_entries, "predict": 1},
    ),
    "digits-15-neighbours": (
        ("v1-wave-triangles", "decimal-digits", 15),
        {"book_of": _neighbours, "chunk_frames": 5},
    ),
}


@pytest.fixture(scope="module")
def hand_made_files(tmp_path_factory) -> dict[str, Any]:
    folder = tmp_path_factory.mktemp("hand-made")
    made = {name: hand_made(*args, **kw) for name, (args, kw) in HAND_MADE.items()}
    return {"made": made, "decoded": _decode_all({n: m.data for n, m in made.items()}, folder)}


@pytest.mark.parametrize("name", list(HAND_MADE))
def test_hand_made_codebooks_decode_to_the_entries_values(hand_made_files, name):
    made = hand_made_files["made"][name]
    result, bits = hand_made_files["decoded"][name]
    assert result["accepted"], result.get("message")
    assert result["version"] == "1.8"
    expected = made.expected.view("<u8")
    assert np.array_equal(bits, expected)
    assert np.array_equal(_python_bits(made.data), expected)  # the reference reads it so too


def test_hand_made_codebooks_take_ties_and_both_ends(hand_made_files):
    """The files exercise what an inexact search would get wrong: b halfway between two
    entries (the lower kept), t at either end of the codebook (the domain's extreme values),
    in every domain, and b below the first entry or above the last."""
    made = hand_made_files["made"]
    assert all(m.ends > 0 for m in made.values())
    for domain in ("float32", "float64", "places-3", "digits-4", "digits-15"):
        assert made[domain].ties > 0, domain
    assert made["places-3-two-entries"].ties > 0
    assert made["float64-inside"].outside > 0 and made["digits-15-inside"].outside > 0


# ------------------------------------------------------------------------------------------
# one rule broken at a time: the Python decoder's verdict, and the rule named


def _file(**kw: Any) -> bytes:
    """The hand-made float32 file of v1-wave-triangles, chunks of 5 frames, changed by ``kw``."""
    return hand_made("v1-wave-triangles", "float32", chunk_frames=5, **kw).data


def _edit(change):
    """An edit of the RESD section: ``change(entry, payload)`` gives the new ones."""

    def edit(data: bytes) -> bytes:
        parts = Parts(data)
        index = parts.index("RESD")
        parts.sections[index] = change(*parts.sections[index])
        return parts.pack()

    return edit


def _set(**params: Any):
    return _edit(lambda entry, payload: ({**entry, **params}, payload))


def _book(axis: int, change):
    """An edit of one codebook: ``change(param, frame)`` gives its new [count, planes,
    length] (its length made right unless it says otherwise) and bytes."""

    def section(entry: dict[str, Any], payload: bytes) -> tuple[dict[str, Any], bytes]:
        table = [list(param) for param in entry["codebooks"]]
        frames, at = [], 0
        for _, _, length in table:
            frames.append(payload[at : at + length])
            at += length
        table[axis], frames[axis] = change(table[axis], frames[axis])
        return {**entry, "codebooks": table}, b"".join(frames) + payload[at:]

    return _edit(section)


def _resized(param: list[int], frame: bytes) -> tuple[list[int], bytes]:
    return [param[0], param[1], len(frame)], frame


def _without_flag(data: bytes) -> bytes:
    return with_preamble(data, flags=Parts(data).flags & ~FLAG_CODEBOOKS)


def _coder_first(data: bytes) -> bytes:
    broken = _set(coder=2, codebooks="none")(data)
    return with_preamble(broken, flags=Parts(broken).flags | FLAG_ADAPTIVE_CORRECTIONS)


def _grid_with_book(data: bytes) -> bytes:
    """A grid file given a codebook: none is allowed there."""
    frame = book_bytes([1, 2, 3])[1]
    return _edit(
        lambda entry, payload: (
            {**entry, "codebooks": [[3, 1, len(frame)], [0, 0, 0], [0, 0, 0]]},
            frame + payload,
        )
    )(data)


def _grid(data: bytes) -> bytes:
    P = exact_reconstruction(data)[0]
    return with_corrections(data, [Corrections(np.zeros(P.shape, np.int64), "grid", step=1e-3)])


def _at_zero(change):
    """e_hook: the first value's e changed by ``change(j, n)``."""

    def hook(steps: np.ndarray, j: np.ndarray, n: int) -> None:
        steps[0] = change(int(j[0]), n)

    return hook


def _entries(change):
    """books_hook: axis 0's codebook changed by ``change(C, low, high)``."""
    low, high = RANGES["float32"]
    return lambda axis, book: change(list(book), low, high) if axis == 0 else book


def _replace(index: int, value: Any):
    def change(book: list[int], low: int, high: int) -> list[int]:
        book[index] = value(book, low, high)
        return book

    return change


#: name -> (the file, broken, and the rule it breaks, or None: accepted)
EDITS: dict[str, tuple[Any, str | None]] = {
    "codebooks-not-an-array": (lambda: _set(codebooks=3)(_file()), R40),
    "codebooks-nil": (lambda: _set(codebooks=None)(_file()), R40),
    "codebooks-two-entries": (lambda: _set(codebooks=[[0, 0, 0]] * 2)(_file()), R40),
    "codebooks-four-entries": (lambda: _set(codebooks=[[0, 0, 0]] * 4)(_file()), R40),
    "codebook-not-an-array": (lambda: _book(1, lambda p, f: (5, f))(_file()), R40),
    "codebook-two-ints": (lambda: _book(1, lambda p, f: (p[:2], f))(_file()), R40),
    "codebook-float": (lambda: _book(1, lambda p, f: ([float(p[0]), *p[1:]], f))(_file()), R40),
    "codebook-bool": (lambda: _book(1, lambda p, f: ([True, *p[1:]], f))(_file()), R40),
    "codebook-count-0": (lambda: _book(1, lambda p, f: ([0, p[1], 0], b""))(_file()), R40),
    "codebook-planes-0": (lambda: _book(1, lambda p, f: ([p[0], 0, p[2]], f))(_file()), R40),
    "codebook-planes-9": (lambda: _book(1, lambda p, f: ([p[0], 9, p[2]], f))(_file()), R40),
    "codebook-length-negative": (lambda: _book(1, lambda p, f: ([*p[:2], -1], f))(_file()), R40),
    # count up to K·F' (81 vertices, 24 frames)
    "codebook-count-above-KF": (
        lambda: _book(1, lambda p, f: ([81 * 24 + 1, *p[1:]], f))(_file()),
        R40,
    ),
    "codebook-count-KF": (lambda: _book(1, lambda p, f: ([81 * 24, *p[1:]], f))(_file()), R29),
    "grid-with-codebook": (lambda: _grid_with_book(_grid(vector("v1-wave-triangles"))), R40),
    "codebook-longer": (lambda: _book(0, lambda p, f: ([*p[:2], p[2] + 1], f))(_file()), R40),
    "codebook-byte-more": (lambda: _book(0, lambda p, f: _resized(p, f + b"\0"))(_file()), R29),
    "codebook-cut": (lambda: _book(0, lambda p, f: _resized(p, f[:-1]))(_file()), R29),
    "codebook-planes-more": (
        lambda: _book(0, lambda p, f: ([p[0], p[1] + 1, p[2]], f))(_file()),
        R29,
    ),
    "codebook-count-fewer": (lambda: _book(0, lambda p, f: ([p[0] - 1, *p[1:]], f))(_file()), R29),
    # `coder` (R46) is checked before `codebooks`
    "coder-before-codebooks": (lambda: _coder_first(_file()), "R46-adaptive-stream"),
    # without flag bit 5, `codebooks` is an unknown parameter: its bytes are counted as chunks'
    "without-flag-bit-5": (lambda: _without_flag(_file()), R40),
    # R47: entries that do not increase, or leave the domain's ordered integers
    "entry-repeated": (
        lambda: _file(books_hook=_entries(_replace(1, lambda c, lo, hi: c[0]))),
        R47,
    ),
    "entry-decreasing": (
        lambda: _file(books_hook=_entries(_replace(2, lambda c, lo, hi: c[1] - 1))),
        R47,
    ),
    "entries-wrapped": (
        lambda: _file(books_hook=_entries(lambda c, lo, hi: [*c[:-1], c[-1] + 2**64 - 2**40])),
        R47,
    ),
    "entry-below-range": (
        lambda: _file(books_hook=_entries(_replace(0, lambda c, lo, hi: lo - 1))),
        R47,
    ),
    "entry-above-range": (
        lambda: _file(books_hook=_entries(_replace(-1, lambda c, lo, hi: hi + 1))),
        R47,
    ),
    # R41: t = j + e outside 0..n - 1 (the domain's range of e does not apply)
    "t-past-the-end": (lambda: _file(e_hook=_at_zero(lambda j, n: n - j)), R41),
    "t-below-0": (lambda: _file(e_hook=_at_zero(lambda j, n: -j - 1)), R41),
    "t-last": (lambda: _file(e_hook=_at_zero(lambda j, n: n - 1 - j)), None),
    "e-huge": (lambda: _file(e_hook=_at_zero(lambda j, n: 2**62)), R41),
    "e-lowest": (lambda: _file(e_hook=_at_zero(lambda j, n: -(2**63))), R41),
    "e-above-float32-range": (lambda: _file(e_hook=_at_zero(lambda j, n: 2**32 + 1)), R41),
}


@pytest.mark.parametrize("name", list(EDITS))
def test_broken_rule_same_verdict_as_python(tmp_path, name):
    make, rule = EDITS[name]
    differ, _, (python,) = compare_verdicts([make()], tmp_path, lambda p, j: False)
    assert not differ, differ
    assert python == ({"accepted": True} if rule is None else python | {"rule": rule}), python


def test_flag_bit_5_without_codebooks_reads_as_before(tmp_path):
    """With flag bit 5, a RESD section without `codebooks`, or with three [0, 0, 0], is what it
    was: the same bits as the file without the bit."""
    P = exact_reconstruction(vector("v1-wave-triangles"))[0]
    e = np.arange(P.size, dtype=np.int64).reshape(P.shape) % 7 - 3
    plain = with_corrections(vector("v1-wave-triangles"), [Corrections(e, "float64", predict=1)])
    flags = Parts(plain).flags | FLAG_CODEBOOKS
    files = {
        "plain": plain,
        "absent": with_preamble(plain, flags=flags, minor=8),
        "empty": _set(codebooks=[[0, 0, 0]] * 3)(plain),
    }
    assert Parts(files["empty"]).flags & FLAG_CODEBOOKS
    expected = _python_bits(plain)
    for name, (result, bits) in _decode_all(files, tmp_path).items():
        assert result["accepted"], (name, result.get("message"))
        assert np.array_equal(bits, expected), name
        assert np.array_equal(_python_bits(files[name]), expected), name


def _grid_empty_codebooks() -> tuple[bytes, bytes]:
    """A grid file, and the same with three [0, 0, 0] codebooks (allowed in the grid domain)."""
    plain = _grid(vector("v1-wave-triangles"))
    return plain, _set(codebooks=[[0, 0, 0]] * 3)(plain)


def test_grid_with_empty_codebooks_reads_as_before(tmp_path):
    plain, empty = _grid_empty_codebooks()
    assert Parts(empty).flags & FLAG_CODEBOOKS
    expected = _python_bits(plain)
    for name, (result, bits) in _decode_all({"plain": plain, "empty": empty}, tmp_path).items():
        assert result["accepted"], (name, result.get("message"))
        assert np.array_equal(bits, expected), name


def test_python_reads_grid_with_empty_codebooks():
    plain, empty = _grid_empty_codebooks()
    assert np.array_equal(_python_bits(empty), _python_bits(plain))


@pytest.mark.parametrize("limit", ["max_section_bytes", "max_chunk_values"])
def test_codebook_size_limits(tmp_path, limit):
    """Each codebook's decompressed size n·P against max_section_bytes, and its entries n
    against max_chunk_values (R21, at step 18): refused one below, read at the limit."""
    data = hand_made("v1-wave-triangles", "float64", chunk_frames=1, anywhere=1000).data
    (entry,) = _residual_entries(data)
    sizes = {
        "max_section_bytes": max(count * planes for count, planes, _ in entry["codebooks"]),
        "max_chunk_values": max(count for count, _, _ in entry["codebooks"]),
    }
    largest = sizes[limit]
    # the chunks (of one frame: never held to max_chunk_values) are below it
    assert sizes["max_section_bytes"] > max(81 * 3 * planes for planes, _ in entry["chunks"])
    path = tmp_path / "a.tkc"
    path.write_bytes(data)
    jobs = [
        {"path": str(path), "limits": {limit: largest - 1}},
        {"path": str(path), "limits": {limit: largest}},
    ]
    over, under = _run(jobs, tmp_path)
    assert (over["rule"], over["kind"]) == ("R21-header-limit", "LimitError"), over
    assert "codebook" in over["message"] and limit in over["message"]
    assert under["accepted"], under.get("message")
    limits = dataclasses.replace(DEFAULT_LIMITS, **{limit: largest - 1})
    with pytest.raises(tuckercodec.LimitError) as python:
        tuckercodec.decode(data, limits=limits)
    assert python.value.rule == "R21-header-limit" and "codebook" in str(python.value)
    tuckercodec.decode(data, limits=dataclasses.replace(limits, **{limit: largest}))
