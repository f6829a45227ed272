"""Segmented files (format 1.1, spec/FORMAT.md §6.7): the streaming encoder's guarantee, random
access from disk, and the segment index's checks."""

from __future__ import annotations

import numpy as np
import pytest

import tuckercodec
from tests.support.compressed import assert_same_faces
from tests.support.sequences import shared_encoded, shared_sequence
from tools.generate import vectors as make_vectors
from tuckercodec import Decoder, FormatError, LimitError, Limits, MeshSequence, encode_with_report
from tuckercodec.encoder.plan import (
    PROCESS_BASELINE,
    needs_segments,
    parse_size,
    plan_segments,
    whole_encode_bytes,
)
from tuckercodec.format.segments import SEGMENTED
from tuckercodec.internal import HEAD_SIZE
from tuckercodec.io.samples import sample_path
from tuckercodec.measures.distortion import kg_error


@pytest.fixture(scope="module")
def cloth() -> MeshSequence:
    return tuckercodec.load_sequence(sample_path(), progress=False)


@pytest.fixture(scope="module")
def shared_file(cloth) -> bytes:
    return encode_with_report(cloth, target_kg=0.1, segment_frames=20).data


@pytest.mark.parametrize("basis", ["shared", "own"])
@pytest.mark.parametrize("target", [1.0, 0.1, 0.01])
def test_the_whole_sequence_meets_the_target(cloth, basis, target):
    result = encode_with_report(cloth, target_kg=target, segment_frames=16, basis=basis)
    decoder = Decoder(result.data)
    assert decoder.segmented and len(decoder.segments) == 4  # 16, 16, 16, 12 frames
    assert [s.basis for s in decoder.segments] == [basis] * 4
    measured = kg_error(cloth.vertices, decoder.positions())
    assert measured <= target
    assert measured == pytest.approx(result.report.kg, rel=1e-9)
    assert measured > 0.5 * target  # the budget is used, not wasted
    # segments (1.1), coding tools, adaptive coding, the cloth's new vertices in a uniform stream
    assert decoder.info.format_version == "1.9"


def test_segments_decode_alone_to_the_frames_of_the_whole(shared_file, cloth):
    decoder = Decoder(shared_file)
    whole = decoder.positions()
    tolerance = 1e-9 * np.abs(whole).max() + 1e-12  # §8: the grouping may change the rounding
    for segment in decoder.segments:
        alone = Decoder(shared_file).positions(range(segment.start, segment.stop))
        np.testing.assert_allclose(alone, whole[segment.start : segment.stop], atol=tolerance)
    picked = [59, 0, 31, 30, 7]  # across segments, in any order
    np.testing.assert_allclose(
        Decoder(shared_file).positions(picked), whole[picked], atol=tolerance
    )
    assert decoder.sequence().frame_names == cloth.frame_names


def test_a_frame_from_disk_reads_only_its_segment(shared_file, tmp_path):
    path = tmp_path / "cloth.tkc"
    path.write_bytes(shared_file)
    decoder = Decoder(path)
    sizes = {section_id: size for section_id, size, _, _ in decoder.info.sections}
    header_end = HEAD_SIZE + int.from_bytes(shared_file[16:20], "little") + 4
    opened = header_end + sizes["FACE"] + sizes.get("NAME", 0)
    assert decoder.bytes_read == opened  # preamble, header, faces (and names): no segment
    decoder.frame(45)  # segment 2 of frames 40..59
    segment_bytes = sum(sizes[f"{stem}.2"] for stem in ("U3", "CORE", "CENT"))
    assert decoder.bytes_read == opened + sizes["U1"] + segment_bytes
    decoder.frame(50)  # the same segment: nothing more is read
    assert decoder.bytes_read == opened + sizes["U1"] + segment_bytes
    decoder.frame(3)  # another segment: its sections only (the shared U1 is kept)
    more = sum(sizes[f"{stem}.0"] for stem in ("U3", "CORE", "CENT"))
    assert decoder.bytes_read == opened + sizes["U1"] + segment_bytes + more
    assert decoder.bytes_read < len(shared_file)


def test_without_segments_the_file_is_todays(cloth):
    plain = encode_with_report(cloth, target_kg=0.1).data
    # minor 9: walked faces (§6.8), adaptive coding (§6.14), the new vertices' uniform stream
    assert plain[10:12] == b"\x09\x00"
    assert int.from_bytes(plain[12:16], "little") & SEGMENTED == 0
    assert not Decoder(plain).segmented


def test_segments_when_the_whole_encode_would_not_fit(cloth):
    frames, vertices = cloth.frame_count, cloth.vertex_count
    whole = PROCESS_BASELINE + 7 * frames * vertices * 24
    assert whole_encode_bytes(frames, vertices) == whole
    assert needs_segments(frames, vertices, segment_frames=None, max_memory=whole - 1)
    assert not needs_segments(frames, vertices, segment_frames=None, max_memory=2 * whole)
    # below the whole encode's peak, above the segmented encode's least
    result = encode_with_report(cloth, target_kg=0.5, max_memory=whole - 1)
    assert result.report.segments >= 1 and Decoder(result.data).segmented


def test_plans_and_sizes():
    plan = plan_segments(1030, 1000, segment_frames=100, max_memory=10**9)
    assert plan.bounds[-1] == (900, 1030)  # the 30-frame tail joins the segment before
    assert len(plan.bounds) == 10
    assert plan_segments(1060, 1000, segment_frames=100, max_memory=10**9).bounds[-1] == (
        1000,
        1060,
    )
    assert parse_size("2GB") == 2 * 10**9 and parse_size("512MiB") == 512 * 2**20
    assert parse_size("1.5g") == 1_500_000_000 and parse_size("1000") == 1000
    for bad in ("", "GB", "-1GB", "2 parsecs", "0"):
        with pytest.raises(ValueError, match="size"):
            parse_size(bad)


def test_fixed_ranks_and_size_targets_with_segments(cloth):
    ranked = encode_with_report(cloth, ranks=(10, 5), segment_frames=20).report
    assert ranked.ranks == (10, 5) and ranked.segments == 3
    assert ranked.kg <= 1.05 * ranked.truncation_kg + 1e-9
    sized = encode_with_report(cloth, target_bpfv=2.0, segment_frames=20)
    assert sized.report.bpfv <= 2.0
    assert len(sized.data) * 8 / (cloth.frame_count * cloth.vertex_count) <= 2.0


def test_decoding_more_positions_than_the_limit_at_once_is_refused(shared_file):
    limits = Limits(max_positions=3101 * 20)  # one segment's frames
    decoder = Decoder(shared_file, limits=limits)
    assert decoder.positions(range(40, 60)).shape == (20, 3101, 3)
    with pytest.raises(LimitError) as raised:
        decoder.positions()
    assert raised.value.rule == "R21-header-limit"


def _with_segments(data: bytes, change) -> bytes:
    parts = make_vectors.Parts(data)
    segments = [dict(entry) for entry in parts.header["segments"]]
    change(segments)
    parts.header["segments"] = segments
    return parts.pack()


@pytest.mark.parametrize(
    ("change", "rule"),
    [
        (lambda s: s.pop(), "R37-segment-index"),  # truncated: frames missing
        (lambda s: s.clear(), "R37-segment-index"),
        (lambda s: s.append(dict(s[-1])), "R37-segment-index"),  # past the last frame
        (lambda s: s.__setitem__(0, 7), "R37-segment-index"),
        (lambda s: s[0].__setitem__("frames", 0), "R37-segment-index"),
        (lambda s: s[0].__setitem__("frames", True), "R37-segment-index"),
        (lambda s: s[0].__setitem__("basis", "mine"), "R37-segment-index"),
        (lambda s: s[1].__setitem__("ranks", [1]), "R38-segment-ranks"),
        (lambda s: s[1].__setitem__("ranks", [0, 1]), "R38-segment-ranks"),
        (lambda s: s[1].__setitem__("ranks", [s[1]["ranks"][0] + 1, 1]), "R38-segment-ranks"),
        (lambda s: s[2].__setitem__("u2", [1.0] * 8), "R23-u2"),
        (lambda s: s[2].__setitem__("basis", "own"), "R26-required-section-missing"),
    ],
)
def test_a_corrupt_segment_index_is_refused_by_rule(shared_file, change, rule):
    data = _with_segments(shared_file, change)
    with pytest.raises(FormatError) as raised:
        tuckercodec.decode(data)
    assert raised.value.rule == rule
    with pytest.raises(FormatError):
        tuckercodec.info(data)  # the header alone shows it


def test_a_damaged_segment_is_found_when_its_frames_are_decoded(shared_file):
    parts = make_vectors.Parts(shared_file)
    n = parts.index("U3.1")
    damaged = bytearray(parts.payloads[n])
    damaged[-1] ^= 1
    parts.fill_table()
    parts.payloads[n] = bytes(damaged)
    data = parts.pack(fix_table=False)
    decoder = Decoder(data)
    decoder.positions(range(20))  # segment 0 is fine
    with pytest.raises(tuckercodec.ChecksumError) as raised:
        decoder.positions([25])
    assert raised.value.rule == "R19-section-crc" and "U3.1" in str(raised.value)
    with pytest.raises(tuckercodec.ChecksumError):
        Decoder(data).check()


@pytest.mark.xdist_group("chicken.npz")  # with the other tests of shared_encoded("chicken.npz")
def test_chicken_in_segments_of_100_frames():
    chicken = shared_sequence("chicken.npz")
    whole = shared_encoded("chicken.npz").report  # the same sequence, whole, at KG 0.1
    result = encode_with_report(chicken, target_kg=0.1, segment_frames=100)
    assert result.report.segments == 4
    assert result.report.total_bytes <= 1.3 * whole.total_bytes
    assert kg_error(chicken.vertices, Decoder(result.data).positions()) <= 0.1


# ------------------------------------------------------------------------------------------
# where the passes run, and the command line


def test_the_bytes_do_not_depend_on_the_workers(cloth):
    """One worker and two workers of a LocalCluster (loopback only) write the same file: the
    blocks and the order of every sum are the plan's, not the executor's. (In process, BLAS may
    run on several threads and round its products differently, so that file may differ in its
    last bits; it meets the same target.)"""
    pytest.importorskip("distributed", reason="the LocalCluster needs the extra [dask]")
    from tuckercodec.system.parallel import open_executor

    written = []
    for jobs in (1, 2):
        with open_executor(jobs) as executor:
            result = encode_with_report(cloth, target_kg=0.1, segment_frames=20, executor=executor)
        written.append(result.data)
        assert kg_error(cloth.vertices, Decoder(result.data).positions()) <= 0.1
    assert written[0] == written[1], "--jobs 1 and --jobs 2 wrote other bytes"


def test_the_file_is_packed_once_beside_the_last_measuring_pass(cloth, shared_file, monkeypatch):
    """Each measure begins packing its quantization's sections (in a thread, beside the pass);
    the file takes them rather than packing again, and is the same bytes as a pack made after
    the search."""
    import threading

    from tuckercodec.encoder.segmented.workspace import SegmentedWorkspace

    levels: list[tuple[int, bool]] = []  # each packing's level, and whether in a thread
    measures: list[object] = []
    sections, measure = SegmentedWorkspace.sections, SegmentedWorkspace.measured_error2

    def counted_sections(self, quantized, level):
        levels.append((level, threading.current_thread() is not threading.main_thread()))
        return sections(self, quantized, level)

    def counted_measure(self, quantized):
        measures.append(quantized)
        return measure(self, quantized)

    monkeypatch.setattr(SegmentedWorkspace, "sections", counted_sections)
    monkeypatch.setattr(SegmentedWorkspace, "measured_error2", counted_measure)
    data = encode_with_report(cloth, target_kg=0.1, segment_frames=20).data
    final = tuckercodec.EncodeOptions().level
    # one packing per measure, beside it; none after the search
    assert measures and levels.count((final, True)) == len(measures)
    assert (final, False) not in levels
    assert data == shared_file

    def after_the_search(self, quantized, level, *, wait=True):
        return sections(self, quantized, level) if wait else []

    monkeypatch.setattr(SegmentedWorkspace, "_packed_sections", after_the_search)
    assert encode_with_report(cloth, target_kg=0.1, segment_frames=20).data == data


def test_encode_in_segments_on_the_command_line(tmp_path, capsys):
    from tuckercodec.cli import main

    out = tmp_path / "cloth.tkc"
    assert main(["encode", str(sample_path()), "-o", str(out), "--segment-frames", "20"]) == 0
    printed = capsys.readouterr().out
    assert "3 segments of frames with one shared U1 (format 1.9)" in printed
    assert "of the whole sequence" in printed
    assert main(["info", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "format 1.9" in printed and "segment 2: frames 40..59" in printed
    decoded = tmp_path / "back.npz"
    assert main(["decode", str(out), "-o", str(decoded), "--frames", "45:50"]) == 0
    assert tuckercodec.load_sequence(decoded, progress=False).frame_count == 5
    # glTF: one decomposition per segment, so the decoded frames as morph targets
    animation = tmp_path / "back.glb"
    assert main(["decode", str(out), "-o", str(animation)]) == 0
    assert "decoded frames as morph targets" in capsys.readouterr().err
    shown = tuckercodec.load_sequence(animation, progress=False).vertices
    np.testing.assert_allclose(shown, Decoder(out).positions(), atol=1e-5)
    # without segments asked for, the sample fits memory: a file of format 1.0
    plain = tmp_path / "plain.tkc"
    assert main(["encode", str(sample_path()), "-o", str(plain), "--max-memory", "4GB"]) == 0
    assert not Decoder(plain).segmented
    # a size the encode cannot work in is a usage error
    with pytest.raises(SystemExit) as raised:
        main(["encode", str(sample_path()), "-o", str(plain), "--max-memory", "lots"])
    assert raised.value.code == 2


# ------------------------------------------------------------------------------------------
# a basis fitted once, shared by files encoded apart (the zarr codec's chunks)


def test_a_fitted_basis_serves_every_segment_on_its_own(cloth):
    from tuckercodec.encoder import encode_frames
    from tuckercodec.encoder.segmented import fit_basis, shared_basis_of
    from tuckercodec.model.sources import SequenceFrames

    basis = fit_basis(SequenceFrames(cloth), target_kg=0.1, segment_frames=20)
    for start in range(0, 60, 20):
        part = MeshSequence(cloth.vertices[start : start + 20], cloth.faces)
        data = encode_frames(
            SequenceFrames(part), target_kg=0.1, segment_frames=20, shared_basis=basis
        ).data
        assert shared_basis_of(data) == basis  # the basis's section, byte for byte
        assert kg_error(part.vertices, Decoder(data).positions()) <= 0.1
    with pytest.raises(ValueError, match="no shared basis"):
        shared_basis_of(encode_with_report(cloth, target_kg=0.1).data)


def test_encode_file_streams_a_npy_with_its_faces(cloth, tmp_path):
    """encode_file reads a positions-only cache a range at a time, with faces from a mesh."""
    cache = tmp_path / "cloth.npy"
    tuckercodec.save_sequence(cloth, cache)
    rest = tmp_path / "rest"
    tuckercodec.save_sequence(MeshSequence(cloth.vertices[:1], cloth.faces), rest)
    out = tmp_path / "cloth.tkc"
    report = tuckercodec.encode_file(
        cache, out, faces=next(rest.glob("*.obj")), target_kg=0.1, segment_frames=20
    )
    assert report.segments == 3
    decoder = Decoder(out)
    assert_same_faces(decoder.faces, cloth.faces)
    assert kg_error(cloth.vertices, decoder.positions()) <= 0.1
