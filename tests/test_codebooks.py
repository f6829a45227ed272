"""Format 1.8: RESD codebooks (spec §6.9 *Codebooks*, flag bit 5, R47).

Where an axis's values are few (a quantized cache, rigid or keyframed parts), a lossless file
stores each axis's sorted ordered integers once and its corrections as differences of positions
in that list. The encoder keeps a codebook only where the section, codebooks counted, is
smaller; the decoded bits are the input's. The conformance vectors (``v1.8-*``, ``R47-*`` and
the ``-codebook(s)`` vectors of R29, R40 and R41) hold the decoders to the layout and the rules.
"""

from __future__ import annotations

import dataclasses
import itertools
from contextlib import nullcontext

import msgpack
import numpy as np
import pytest

import tuckercodec as tc
from tuckercodec import Decoder, MeshSequence
from tuckercodec.format import residual
from tuckercodec.format.container import parse_container
from tuckercodec.format.limits import DEFAULT_LIMITS
from tuckercodec.io.samples import sheet_triangles, wave_sheet
from tuckercodec.system import native

FLOAT64 = residual.Domain(residual.FLOAT64)


def _resd(data: bytes) -> dict[str, object]:
    entry = parse_container(data, DEFAULT_LIMITS).section("RESD")
    assert entry is not None
    return dict(entry.params)


def _coarse_sheet(frames: int = 20, side: int = 8, step: float = 1 / 32) -> np.ndarray:
    """A waving sheet whose coordinates are rounded to ``step``: few distinct values, each
    repeated across frames and vertices, as in a cache quantized to a grid."""
    return np.round(wave_sheet(frames, side) / step) * step


def _bit_exact(decoded: np.ndarray, original: np.ndarray) -> bool:
    return np.array_equal(decoded.view(np.int64), original.view(np.int64))


# ------------------------------------------------------------------------------------------
# the nearest entry (§6.9): exact, with ties to the lower


def test_the_nearest_entry_takes_the_lower_on_a_tie_and_clamps_at_the_ends():
    book = np.array([-10, 0, 4, 100], dtype=np.int64)
    base = np.array([-50, -10, -6, -5, -4, 0, 2, 3, 52, 53, 100, 10**6], dtype=np.int64)
    expected = [0, 0, 0, 0, 1, 1, 1, 2, 2, 3, 3, 3]
    assert residual.nearest_entries(book, base).tolist() == expected


def test_the_midpoints_give_the_rule_of_the_spec_exactly():
    """floor((C[m] + C[m+1]) / 2) without overflow, against Python's integers."""
    low, high = residual.FINITE64
    book = np.array([low, low + 1, -(2**40) - 1, 0, 3, 2**62, high], dtype=np.int64)
    expected = [(int(a) + int(b)) // 2 for a, b in itertools.pairwise(book)]
    assert residual.midpoints(book).tolist() == expected


def test_the_nearest_entry_is_exact_across_the_whole_int64_range():
    """Gaps up to 2**64 - 1 (float64's ordered integers span both signs): no overflow."""
    low, high = residual.FINITE64
    book = np.array([low, -(2**40), 0, 3, high], dtype=np.int64)
    rng = np.random.default_rng(2)
    base = np.concatenate([
        rng.integers(low, high, size=2000, dtype=np.int64),
        np.array([low + 1, -(2**62), -1, 1, 2**62, high - 1, low // 2, high // 2 + 1]),
    ])  # fmt: skip

    def nearest(b: int) -> int:  # Python's integers: no width at all
        entries = [int(c) for c in book]
        j = max([n for n, c in enumerate(entries) if c <= b], default=0)
        up = j + 1 < len(entries) and entries[j] <= b and entries[j + 1] - b < b - entries[j]
        return j + up

    found = residual.nearest_entries(book, base).tolist()
    assert found == [nearest(int(b)) for b in base]


def test_positions_in_the_codebook_come_back_as_the_domain_corrections():
    rng = np.random.default_rng(3)
    values = rng.choice(np.linspace(-2.0, 2.0, 41), size=(5, 30, 3))
    exact = values + rng.normal(scale=0.04, size=values.shape)
    ordered = residual.ordered_in(values, FLOAT64)
    books = residual.codebooks_of(ordered)
    assert books is not None and all(book is not None for book in books)
    plain = residual.residuals_of(exact, values, FLOAT64)
    positions = tuple(
        None if book is None else np.searchsorted(book, ordered[..., axis])
        for axis, book in enumerate(books)
    )
    stored = residual.codebook_integers(plain, ordered, books, positions)
    assert np.abs(stored).max() <= 3  # positions, not ulps
    corrections = residual.from_codebooks(exact, stored, FLOAT64, books, "RESD")
    assert _bit_exact(residual.correct(exact, corrections, FLOAT64, "RESD"), values)


def test_a_position_beyond_the_codebook_is_r41():
    book = np.array([1, 2, 3], dtype=np.int64)
    exact = np.zeros((1, 1, 3))
    stored = np.array([[[0, 0, 3]]], dtype=np.int64)  # b of 0.0 is 0, nearest C[0]: 0 + 3 > 2
    with pytest.raises(tc.FormatError) as caught:
        residual.from_codebooks(exact, stored, FLOAT64, (None, None, book), "RESD")
    assert caught.value.rule == "R41-residual-value" and "axis 2" in str(caught.value)
    huge = np.array([[[0, 0, -(2**63)]]], dtype=np.int64)  # no wrap back into range
    with pytest.raises(tc.FormatError):
        residual.from_codebooks(exact, huge, FLOAT64, (None, None, book), "RESD")


# ------------------------------------------------------------------------------------------
# the section's parameters and codebooks (R40, R47)


def _section(books: residual.Codebooks, domain: residual.Domain = FLOAT64):
    integers = np.zeros((2, 4, 3), dtype=np.int64)
    return residual.encode_section(integers, domain, 3, predict=0, codebooks=books)


def test_codebooks_read_back_and_the_reference_writes_the_same_bytes():
    first, last = np.array([-5, 7, 2**40], dtype=np.int64), np.arange(8, dtype=np.int64)
    books = (first, None, last)
    params, payload = _section(books)
    assert params["codebooks"][1] == [0, 0, 0]
    with native.pure_python():
        assert _section(books) == (params, payload)
    layout = residual.read_layout(
        params, len(payload), 2, 4, DEFAULT_LIMITS, "RESD", codebooks=True
    )
    decoded_first, axis_1, decoded_last = residual.decode_codebooks(payload, layout, "RESD")
    assert axis_1 is None and decoded_first is not None and decoded_last is not None
    assert np.array_equal(decoded_first, first) and np.array_equal(decoded_last, last)
    chunk = residual.decode_chunk(payload, layout, 0, 4, "RESD")
    assert not chunk.any()


def test_codebooks_are_an_unknown_parameter_without_flag_bit_5():
    params, _ = _section((None, None, np.arange(3, dtype=np.int64)))
    plain, plain_payload = residual.encode_section(
        np.zeros((2, 4, 3), dtype=np.int64), FLOAT64, 3, predict=0
    )
    layout = residual.read_layout(
        {**plain, "codebooks": params["codebooks"]}, len(plain_payload), 2, 4, DEFAULT_LIMITS, "R"
    )
    assert layout.codebooks == ()


@pytest.mark.parametrize(
    "books",
    [
        [[0, 0, 0], [0, 0, 0]],
        "none",
        [[0, 0, 0], [0, 0, 0], [1, 9, 0]],
        [[0, 0, 0], [0, 0, 0], [0, 1, 0]],
        [[0, 0, 0], [0, 0, 0], [25, 1, 0]],  # more entries than the section's 24 values
        [[0, 0, 0], [0, 0, 0], [1, 1, -1]],
        [[0, 0, 0], [0, 0, 0], [1, 1, True]],
    ],
)
def test_malformed_codebooks_are_r40(books):
    params, payload = _section((None, None, np.arange(3, dtype=np.int64)))
    with pytest.raises(tc.FormatError) as caught:
        residual.read_layout(
            {**params, "codebooks": books}, len(payload), 2, 4, DEFAULT_LIMITS, "R", codebooks=True
        )
    assert caught.value.rule == "R40-residual"


def test_a_grid_section_may_declare_three_empty_codebooks():
    """R40 allows [0, 0, 0] for every axis in any domain: nothing to read, nothing to map."""
    grid = residual.Domain(residual.GRID, step=0.5)
    params, payload = residual.encode_section(np.zeros((2, 4, 3), dtype=np.int64), grid, 3)
    params = {**params, "codebooks": [[0, 0, 0]] * 3}
    layout = residual.read_layout(params, len(payload), 2, 4, DEFAULT_LIMITS, "R", codebooks=True)
    assert residual.decode_codebooks(payload, layout, "R") == (None, None, None)


def test_a_grid_has_no_codebooks():
    grid = residual.Domain(residual.GRID, step=0.5)
    params, payload = _section((None, None, np.arange(3, dtype=np.int64)), grid)
    with pytest.raises(tc.FormatError) as caught:
        residual.read_layout(params, len(payload), 2, 4, DEFAULT_LIMITS, "R", codebooks=True)
    assert caught.value.rule == "R40-residual" and "grid" in str(caught.value)


@pytest.mark.parametrize(
    ("domain", "entries"),
    [
        (FLOAT64, [3, 3, 4]),
        (FLOAT64, [5, 4]),
        (residual.Domain(residual.FLOAT32), [0, residual.FINITE32[1] + 1]),
        (residual.Domain(residual.PLACES, scale=2), [-(2**53) - 1, 0]),
        (residual.Domain(residual.DIGITS, scale=3), [0, residual.digits_largest(3) + 1]),
    ],
)
def test_codebooks_that_do_not_increase_or_leave_the_domain_are_r47(domain, entries):
    params, payload = _section((None, None, np.array(entries, dtype=np.int64)), domain)
    layout = residual.read_layout(params, len(payload), 2, 4, DEFAULT_LIMITS, "R", codebooks=True)
    with pytest.raises(tc.FormatError) as caught:
        residual.decode_codebooks(payload, layout, "R")
    assert caught.value.rule == "R47-codebook"


# ------------------------------------------------------------------------------------------
# the encoder: bit for bit, and never larger


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_a_quantized_cache_is_lossless_with_codebooks_and_smaller(dtype):
    sheet = MeshSequence(_coarse_sheet().astype(dtype).astype(np.float64), sheet_triangles(8))
    data = tc.encode(sheet, lossless=True)
    assert tc.info(data).format_version == "1.8"
    assert "codebooks" in _resd(data)
    assert _bit_exact(Decoder(data).positions(), sheet.vertices)
    before = tc.encode(sheet, lossless=True, format_version="1.7")
    assert len(data) < len(before)


def test_decimals_keep_their_domain_and_gain_codebooks():
    """Values read from %.3f text of a coarse grid: decimal-places integers in the codebooks."""
    text = np.array([[[float(f"{v:.3f}") for v in row] for row in frame] for frame in
                     _coarse_sheet(12, 6, 0.125) + 0.0005])  # fmt: skip
    sheet = MeshSequence(text, sheet_triangles(6))
    data = tc.encode(sheet, lossless=True)
    params = _resd(data)
    assert params["domain"] == residual.PLACES and "codebooks" in params
    assert _bit_exact(Decoder(data).positions(), sheet.vertices)


def test_segments_each_carry_their_codebooks():
    sheet = MeshSequence(_coarse_sheet(24), sheet_triangles(8))
    result = tc.encode_with_report(sheet, lossless=True, segment_frames=8)
    container = parse_container(result.data, DEFAULT_LIMITS)
    sections = [s for s in container.sections if s.id.startswith("RESD.")]
    assert len(sections) == 3 and all("codebooks" in s.params for s in sections)
    decoder = Decoder(result.data)
    assert _bit_exact(decoder.positions(), sheet.vertices)
    assert _bit_exact(decoder.positions([17]), sheet.vertices[[17]])


def test_values_that_are_all_different_get_no_codebooks():
    rng = np.random.default_rng(8)
    noisy = wave_sheet(10, 6) + rng.normal(scale=1e-3, size=(10, 36, 3))
    data = tc.encode(MeshSequence(noisy, sheet_triangles(6)), lossless=True)
    assert "codebooks" not in _resd(data) and tc.info(data).format_version != "1.8"


def test_the_pure_python_reference_writes_the_same_file():
    sheet = MeshSequence(_coarse_sheet(10, 6), sheet_triangles(6))
    compiled = tc.encode(sheet, lossless=True)
    with native.pure_python():
        assert tc.encode(sheet, lossless=True) == compiled
        assert _bit_exact(Decoder(compiled).positions(), sheet.vertices)


def test_a_codebook_counts_its_parameters_when_it_is_weighed():
    """The section with codebooks must be smaller with its key counted, or it is not kept."""
    sheet = MeshSequence(_coarse_sheet(10, 6), sheet_triangles(6))
    params = _resd(tc.encode(sheet, lossless=True))
    assert "codebooks" in params
    assert len(msgpack.packb(params["codebooks"])) > 0


# ------------------------------------------------------------------------------------------
# the compiled core: the same integers as the reference, and the same R41


@pytest.mark.parametrize(
    "domain",
    [FLOAT64, residual.Domain(residual.FLOAT32), residual.Domain(residual.PLACES, scale=3)],
)
def test_the_compiled_core_finds_the_same_entries_and_corrections(domain):
    rng = np.random.default_rng(17)
    grid = np.linspace(-3.0, 3.0, 61)
    values = rng.choice(grid, size=(9, 80, 3)).astype(np.float32).astype(np.float64)
    values = np.round(values, 3)
    exact = values + rng.normal(scale=0.05, size=values.shape)
    exact[4, 7, 1] = np.nan  # not finite: 0 outside float32, whatever is stored
    ordered = residual.ordered_in(values, domain)
    books = residual.codebooks_of(ordered)
    assert books is not None
    positions = tuple(
        None if book is None else np.searchsorted(book, ordered[..., axis])
        for axis, book in enumerate(books)
    )
    plain = ordered - residual.ordered_in(np.nan_to_num(exact), domain)
    compiled = residual.codebook_integers(plain, ordered, books, positions)
    decoded = residual.from_codebooks(exact, compiled, domain, books, "RESD")
    with native.pure_python():
        assert np.array_equal(
            residual.codebook_integers(plain, ordered, books, positions), compiled
        )
        assert np.array_equal(
            residual.from_codebooks(exact, compiled, domain, books, "RESD"), decoded
        )
    beyond = compiled.copy()
    beyond[8, 79, 2] = 10**6
    for pure in (False, True):
        with (
            native.pure_python() if pure else nullcontext(),
            pytest.raises(tc.FormatError) as caught,
        ):
            residual.from_codebooks(exact, beyond, domain, books, "RESD")
        assert caught.value.rule == "R41-residual-value" and "axis 2" in str(caught.value)


def test_a_codebook_beyond_max_chunk_values_is_refused_before_it_is_read():
    """Every frame needs the whole codebook: it is held to max_chunk_values entries (R21)."""
    params, payload = _section((None, None, np.arange(5, dtype=np.int64)))
    small = dataclasses.replace(DEFAULT_LIMITS, max_chunk_values=4)
    with pytest.raises(tc.LimitError) as caught:
        residual.read_layout(params, len(payload), 2, 4, small, "RESD", codebooks=True)
    assert caught.value.rule == "R21-header-limit" and "codebook" in str(caught.value)
    layout = residual.read_layout(params, len(payload), 2, 4, DEFAULT_LIMITS, "R", codebooks=True)
    assert layout.codebooks[2][0] == 5
