"""A bound on every vertex, and every bit: --max-error and --lossless (format 1.3, spec §6.9).

Every promise is measured here independently of the encoder: the decoded positions against the
input, vertex by vertex (Euclidean distance), or bit by bit.
"""

from __future__ import annotations

import numpy as np
import pytest

import tuckercodec as tc
from tests.support.sequences import (
    grid_faces,
    load_shared_npz,
    shared_file,
    wave_sequence,
)
from tuckercodec import Decoder, EncodeOptions, Encoder, MeshSequence
from tuckercodec.cli import main
from tuckercodec.errors import FormatError, UnreachableTargetError
from tuckercodec.format import residual
from tuckercodec.format.container import parse_container
from tuckercodec.format.limits import DEFAULT_LIMITS
from tuckercodec.io.samples import sample_path


def _worst(decoded: np.ndarray, original: np.ndarray) -> float:
    return float(np.sqrt(np.square(decoded - original).sum(axis=2)).max())


def _diagonal(values: np.ndarray) -> float:
    return float(np.linalg.norm(values.max(axis=(0, 1)) - values.min(axis=(0, 1))))


def _same_bits(a: np.ndarray, b: np.ndarray) -> bool:
    return bool(np.array_equal(a.view(np.int64), b.view(np.int64)))


@pytest.fixture(scope="module")
def cloth() -> MeshSequence:
    return tc.load_sequence(sample_path())


@pytest.fixture(scope="module")
def rough() -> MeshSequence:
    return MeshSequence(wave_sequence(30, 9, seed=3), grid_faces(9))


# -- the ordered integers and the decimals (§6.9) ---------------------------------------------


def test_ordered_integers_are_monotone_and_their_own_inverse():
    values = np.array(
        [-np.inf, -3.5, -1e-300, -5e-324, -0.0, 0.0, 5e-324, 1e-300, 1.0, 3.5, np.inf]
    )
    ordered = residual.ordered64(values)
    assert np.all(np.diff(ordered) > 0)
    assert ordered[4] == -1 and ordered[5] == 0 and ordered[6] == 1
    assert _same_bits(residual.from_ordered64(ordered), values)
    single = np.array(
        [-np.inf, -3.5, -1e-30, -1e-45, -0.0, 0.0, 1e-45, 1e-30, 1.0, np.inf], np.float32
    )
    ordered32 = residual.ordered32(single)
    assert np.all(np.diff(ordered32) > 0)
    assert ordered32[-1] == 2139095040  # +infinity, one above the largest finite (§6.9)
    back = residual.from_ordered32(ordered32)
    assert np.array_equal(back.view(np.int32), single.view(np.int32))


@pytest.mark.parametrize("digits", [1, 6, 9, 15])
def test_decimal_digits_give_back_every_decimal_of_that_many_digits(digits):
    rng = np.random.default_rng(digits)
    # decades the domain holds: E_min = p - 23 up to 44 above it (§6.9)
    exponents = rng.integers(digits - 19, min(digits + 19, 14), 2000)
    texts = [f"{v:.{digits}g}" for v in rng.standard_normal(2000) * 10.0**exponents]
    values = np.array([float(t) for t in [*texts, "0", "-0", "1e-3", "-1e5"]])
    ordered = residual.digits_ordered(values, digits)
    assert _same_bits(residual.digits_values(ordered, digits), values)
    distinct = np.unique(values[values != 0])  # (+0 and -0 compare equal: 0 and -1)
    assert np.all(np.diff(residual.digits_ordered(distinct, digits)) > 0)  # monotone


@pytest.mark.parametrize("places", [0, 3, 8, 10])
def test_decimal_places_give_back_every_decimal_with_that_many_places(places):
    rng = np.random.default_rng(places)
    values = np.array([float(f"{v:.{places}f}") for v in rng.uniform(-50, 50, 3000)])
    values = values[values != 0]  # "-0.000" is -0, which a decimal integer cannot hold
    ordered = residual.places_ordered(values, places)
    assert _same_bits(residual.places_values(ordered, places), values)


def test_the_exact_reconstruction_is_section_8_1_written_out():
    """§8.1 one value at a time: B and W in their order, the integer weights, S summed in
    Python's exact integers, then S x 2**e + CENT; bit for bit against the reference."""
    rng = np.random.default_rng(7)
    i, k, vertices, frames = 5, 4, 7, 3
    q1 = rng.integers(-3000, 3000, size=(vertices, i))
    steps = rng.uniform(1e-4, 1e-3, size=i).astype(np.float32)
    core = rng.standard_normal((i, 3, k))
    u2 = np.linalg.qr(rng.standard_normal((3, 3)))[0]
    u3 = rng.standard_normal((frames, k))
    centroids = rng.standard_normal((frames, 3))
    u1 = residual.ExactU1.of(q1, steps)
    basis = residual.exact_basis(core, u2)
    exponent = residual.choose_exponent(
        u1, float(np.abs(residual.scaled_weights(u1, basis, u3)).max())
    )
    got = residual.exact_frames(u1, basis, u3, centroids, exponent)
    for f in range(frames):
        weights = []
        for a in range(i):
            row = []
            for x in range(3):

                def b_of(b: int, a: int = a, x: int = x) -> float:
                    terms = [float(core[a, c, b]) * float(u2[x, c]) for c in range(3)]
                    return (terms[0] + terms[1]) + terms[2]

                w = b_of(0) * float(u3[f, 0])
                for b in range(1, k):
                    w = w + b_of(b) * float(u3[f, b])
                y = float(steps[a]) * w
                row.append(round(y * 2.0**-exponent))  # Python's round: half to even
            weights.append(row)
        for v in range(vertices):
            for x in range(3):
                total = sum(int(q1[v, a]) * weights[a][x] for a in range(i))
                assert got[f, v, x] == float(total) * 2.0**exponent + float(centroids[f, x])


def test_an_exponent_too_small_for_an_exact_product_is_r41():
    u1 = residual.ExactU1.of(np.full((2, 2), 2**20), np.ones(2, np.float32))
    basis = np.ones((2, 3, 1))
    with pytest.raises(FormatError) as caught:
        residual.exact_frames(u1, basis, np.ones((1, 1)), np.zeros((1, 3)), exponent=-40)
    assert caught.value.rule == "R41-residual-value"


# -- the promises, measured -------------------------------------------------------------------


@pytest.mark.parametrize("fraction", ["0.1%", "0.01%"])
def test_every_vertex_of_the_cloth_is_within_the_bound(cloth, fraction):
    result = Encoder(EncodeOptions(max_error=fraction)).encode_with_report(cloth)
    bound = float(fraction[:-1]) / 100 * _diagonal(cloth.vertices)
    decoded = tc.decode(result.data).vertices
    worst = _worst(decoded, cloth.vertices)
    assert worst <= bound
    assert result.report.max_distance == pytest.approx(worst, rel=1e-12)
    assert result.report.max_error == pytest.approx(bound)
    # corrections (1.3), adaptive coding (1.6), 1.7 where the corrections are adaptive, and
    # 1.9 for the new vertices of the cloth's random vertex order, the newest of them
    container = parse_container(result.data, DEFAULT_LIMITS)
    assert container.corrections and container.uniform_ranks
    assert container.adaptive_corrections == (_resd_coder(result.data) == 1)
    assert tc.info(result.data).format_version == "1.9"


def _resd_coder(data: bytes) -> int:
    """The RESD section's ``coder`` (0 when absent)."""
    container = parse_container(data, DEFAULT_LIMITS)
    entry = container.section("RESD")
    assert entry is not None
    return int(entry.params.get("coder", 0))


def test_a_bound_the_tucker_part_already_meets_writes_the_file_of_before(cloth):
    """With D above the plain file's worst vertex, no corrections: the KG file, same bytes."""
    plain = Encoder(EncodeOptions(target_kg=0.1)).encode_with_report(cloth)
    assert plain.report.max_distance is not None
    bounded = Encoder(
        EncodeOptions(target_kg=0.1, max_error=2 * plain.report.max_distance)
    ).encode_with_report(cloth)
    assert tc.info(bounded.data).format_version == tc.info(plain.data).format_version
    assert bounded.report.corrections is None
    assert abs(bounded.report.total_bytes - plain.report.total_bytes) < 200  # the claims only
    assert _worst(tc.decode(bounded.data).vertices, cloth.vertices) <= 2 * plain.report.max_distance


def test_kg_and_a_bound_both_hold(cloth):
    plain = Encoder(EncodeOptions(target_kg=0.1)).encode_with_report(cloth)
    assert plain.report.max_distance is not None
    bound = 0.4 * plain.report.max_distance
    result = Encoder(EncodeOptions(target_kg=0.1, max_error=bound)).encode_with_report(cloth)
    decoded = tc.decode(result.data).vertices
    assert _worst(decoded, cloth.vertices) <= bound
    assert tc.kg_error(cloth.vertices, decoded) <= 0.1
    assert result.report.total_bytes <= 1.1 * plain.report.total_bytes


def test_lossless_gives_back_every_bit_of_float32_values(cloth):
    result = Encoder(EncodeOptions(lossless=True)).encode_with_report(cloth)
    decoder = Decoder(result.data)
    assert decoder.corrections == "float32"
    assert _same_bits(decoder.positions(), cloth.vertices)
    assert result.report.lossless and result.report.max_distance == 0.0
    # any frame alone, and frames out of order, give the same bits
    frames = [45, 3, 59]
    assert _same_bits(Decoder(result.data).positions(frames), cloth.vertices[frames])


def test_lossless_keeps_negative_zero_subnormals_and_huge_values(rough):
    values = rough.vertices.copy()
    values[0, 0] = [-0.0, 5e-324, -1.5e20]
    values[4, 7] = [1e-310, -0.0, 2.0**60]
    sequence = MeshSequence(values, rough.faces)
    data = Encoder(EncodeOptions(lossless=True)).encode(sequence)
    assert _same_bits(tc.decode(data).vertices, values)


@pytest.mark.parametrize(
    ("style", "domain"), [("{:.6g}", "decimal-digits"), ("{:.4f}", "decimal-places")]
)
def test_lossless_decimals_read_from_text(rough, style, domain):
    shifted = rough.vertices + (5.0 if "f" in style else 0.0)  # no "-0.0000" for places
    values = np.array([float(style.format(v)) for v in shifted.reshape(-1)])
    sequence = MeshSequence(values.reshape(shifted.shape), rough.faces)
    data = Encoder(EncodeOptions(lossless=True)).encode(sequence)
    decoder = Decoder(data)
    assert decoder.corrections == domain
    assert _same_bits(decoder.positions(), sequence.vertices)


def test_lossless_float32_values_read_from_text(rough):
    """A float32 cache written from %g text: counted in the text's last digit, not in float32's."""
    texts = [f"{v:.6g}" for v in rough.vertices.reshape(-1)]
    values = np.array(texts, dtype=np.float32).astype(np.float64).reshape(rough.vertices.shape)
    sequence = MeshSequence(values, rough.faces)
    data = Encoder(EncodeOptions(lossless=True)).encode(sequence)
    decoder = Decoder(data)
    assert decoder.corrections == "decimal-digits-float32"
    assert _same_bits(decoder.positions(), values)


def test_segmented_files_keep_the_promise_in_every_segment(cloth):
    bound = 0.001 * _diagonal(cloth.vertices)
    bounded = Encoder(EncodeOptions(max_error=bound, segment_frames=20)).encode(cloth)
    decoder = Decoder(bounded)
    assert decoder.segmented and len(decoder.segments) == 3
    for segment in decoder.segments:
        frames = list(range(segment.start, segment.stop))
        assert _worst(decoder.positions(frames), cloth.vertices[frames]) <= bound
    lossless = Encoder(EncodeOptions(lossless=True, segment_frames=20, basis="own")).encode(cloth)
    assert _same_bits(tc.decode(lossless).vertices, cloth.vertices)


def test_chunks_decode_alone(cloth, monkeypatch):
    """Many small chunks: a frame needs only its own, and every frame is right."""
    monkeypatch.setattr(residual, "CHUNK_VALUES", 3 * cloth.vertex_count * 7)
    data = Encoder(EncodeOptions(lossless=True)).encode(cloth)
    decoder = Decoder(data)
    layout = decoder.segment_factors(0).corrections
    assert layout is not None and layout.chunk_frames == 7
    for frame in (59, 0, 34, 35, 6, 7):
        assert _same_bits(decoder.frame(frame), cloth.vertices[frame])
    decoder.check()


def test_a_bound_float64_cannot_resolve_is_refused(cloth):
    with pytest.raises(UnreachableTargetError, match="float64 itself resolves"):
        Encoder(EncodeOptions(max_error=1e-300)).encode(cloth)


def test_options_refuse_what_cannot_be_promised():
    with pytest.raises(ValueError, match="max_error or target_bpfv"):
        EncodeOptions(max_error=0.1, target_bpfv=2.0)
    with pytest.raises(ValueError, match="lossless stands alone"):
        EncodeOptions(lossless=True, target_kg=0.1)
    for bad in ("-1%", "abc", 0, float("nan"), "%"):
        with pytest.raises(ValueError, match="max_error"):
            EncodeOptions(max_error=bad)
    assert EncodeOptions(max_error=" 0.5 % ").max_error == "0.5%"
    assert EncodeOptions.from_config(EncodeOptions(lossless=True).to_config()).lossless


def test_a_corrected_value_out_of_range_is_r41(cloth):
    data = Encoder(EncodeOptions(lossless=True)).encode(cloth)
    decoder = Decoder(data)
    part = decoder.segment_factors(0)
    assert part.corrections is not None
    with pytest.raises(FormatError) as caught:
        residual.correct(
            np.zeros((1, 2, 3)), np.full((1, 2, 3), 2**40), part.corrections.kind, "section RESD"
        )
    assert caught.value.rule == "R41-residual-value"


# -- the command line -------------------------------------------------------------------------


def test_cli_encodes_with_a_bound_and_lossless(tmp_path, capsys):
    source = tmp_path / "wave.npz"
    np.savez(source, V=wave_sequence(20, 8), F=grid_faces(8))
    bounded = tmp_path / "bounded.tkc"
    assert main(["encode", str(source), "-o", str(bounded), "--max-error", "0.05%"]) == 0
    out = capsys.readouterr().out
    assert "worst vertex" in out
    lossless = tmp_path / "lossless.tkc"
    assert main(["encode", str(source), "-o", str(lossless), "--lossless"]) == 0
    capsys.readouterr()
    original = np.load(source)["V"]
    assert _same_bits(tc.decode(lossless).vertices, original)
    assert main(["info", str(lossless)]) == 0
    assert "lossless" in capsys.readouterr().out


def test_cli_refuses_an_unreachable_bound_with_exit_5(tmp_path, capsys):
    source = tmp_path / "wave.npz"
    np.savez(source, V=wave_sequence(20, 8) + 1e6, F=grid_faces(8))
    code = main(["encode", str(source), "-o", str(tmp_path / "out.tkc"), "--max-error", "1e-12"])
    assert code == 5
    err = capsys.readouterr().err
    assert "float64 itself resolves" in err and "Traceback" not in err
    assert not (tmp_path / "out.tkc").exists()


def test_cli_refuses_lossless_with_a_kg_target(tmp_path, capsys):
    source = tmp_path / "wave.npz"
    np.savez(source, V=wave_sequence(20, 8), F=grid_faces(8))
    code = main(["encode", str(source), "-o", str(tmp_path / "o.tkc"), "--lossless", "--kg", "0.1"])
    assert code != 0
    assert "lossless" in capsys.readouterr().err


# -- the real sequences -----------------------------------------------------------------------


@pytest.mark.parametrize("name", ["chicken.npz", "samba.npz"])
def test_real_sequences_meet_the_bound(name):
    vertices, faces = load_shared_npz(name)
    sequence = MeshSequence(vertices[:60].astype(np.float64), faces)
    bound = 1e-3 * _diagonal(sequence.vertices)
    data = Encoder(EncodeOptions(max_error=bound)).encode(sequence)
    assert _worst(tc.decode(data).vertices, sequence.vertices) <= bound


def test_horse_gallop_obj_files_round_trip_bit_for_bit():
    whole = tc.load_sequence(shared_file("horse-gallop"))
    sequence = MeshSequence(whole.vertices[:12], whole.faces)
    data = Encoder(EncodeOptions(lossless=True)).encode(sequence)
    decoder = Decoder(data)
    assert decoder.corrections == "decimal-digits"
    assert _same_bits(decoder.positions(), sequence.vertices)
