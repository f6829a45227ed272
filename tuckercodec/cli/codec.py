"""The codec's verbs: ``encode`` a sequence into a file, ``decode`` it into frames (or a glTF
animation), and ``info`` on its header."""

from __future__ import annotations

import argparse
import json
import sys
import time
import unicodedata
from pathlib import Path

import numpy as np

from ..decoder import Decoder, FileInfo
from ..decoder import info as read_info
from ..encoder import EncodeOptions, Encoder, EncodeReport, resolve_options
from ..errors import EXIT_OK, InputError
from ..files import decode_file, decoded_output_path, is_gltf_output, write_encoded
from ..gltf_export import DEFAULT_COMPRESSION, write_decomposition_gltf
from ..measures.distortion import (
    KG_DEFINITION,
    MAX_DISTANCE_DEFINITION,
    Displacement,
    ErrorAccumulator,
)
from ..model.sequence import MeshSequence
from ..reports.text import worst_vertex
from ..system import native
from .inputs import check_precision, load_input, read_options, sequence_source


def _print_encode_report(report: EncodeReport, format_version: str) -> None:
    i, k = report.ranks
    if report.basis is not None:  # a segmented file
        basis = "one shared U1" if report.basis == "shared" else "a U1 each"
        print(
            f"{report.segments} segments of frames with {basis} (format {format_version}), read in "
            f"{report.trials} passes and trials; largest ranks (i, 3, k) = ({i}, 3, {k})"
        )
    print(
        f"ranks (i, 3, k) = ({i}, 3, {k}); decoded KG error {report.kg:.5f} "
        f"(truncation alone {report.truncation_kg:.5f}; {KG_DEFINITION})"
        if report.basis is None
        else f"decoded KG error {report.kg:.5f} of the whole sequence (truncation alone "
        f"{report.truncation_kg:.5f}; {KG_DEFINITION})"
    )
    _print_encode_bounds(report)
    print(
        f"format {format_version}; size {report.total_bytes} bytes = {report.bpfv:.4f} bpfv "
        f"(whole file; connectivity {report.connectivity_bpfv:.4f} bpfv of it"
        + (
            f", attributes and fields {report.attachments_bpfv:.4f}"
            if report.attachments_bpfv
            else ""
        )
        + f"), {report.ratio:.1f}x smaller than raw float32"
    )
    if report.exact_ranks is not None:
        print(
            f"cheapest truncation for the target: exact table {report.exact_ranks}, the paper's "
            f"bound {report.bound_ranks}; chosen by '{report.select}' with quantization"
        )
    print(f"time {report.seconds:.2f} s")


def _print_encode_bounds(report: EncodeReport) -> None:
    """The worst vertex the encoder measured, beside its KG error, and the bound or the
    lossless check it was asked for."""
    if report.max_distance is not None:
        where = worst_vertex(report.max_distance, report.max_distance_at)
        print(f"decoded worst vertex {where} ({MAX_DISTANCE_DEFINITION})")
    corrections = (
        f"corrections (spec §6.9) in the {report.corrections} domain"
        if report.corrections is not None
        else "no corrections needed"
    )
    if report.max_error is not None:
        print(
            f"bound on every vertex {report.max_error:.6g} (--max-error, as a length in the "
            f"sequence's units); {corrections}"
        )
    if report.lossless:
        print(f"lossless: the decoded values checked to be the input's, bit for bit; {corrections}")


def run_encode(args: argparse.Namespace) -> int:
    start = time.perf_counter()
    encoder = Encoder(encode_options(args), progress=_say)
    encoded = write_encoded(
        encoder,
        sequence_source(args.input),
        args.output,
        overwrite=args.force,
        **read_options(args),
    )
    print(
        f"{args.input}: {encoded.frame_count} frames, {encoded.vertex_count} vertices "
        f"-> {args.output}"
    )
    written = read_info(encoded.data)
    _print_encode_report(encoded.report, written.format_version)
    _print_attachments(written)
    elapsed = time.perf_counter() - start
    megabytes = encoded.frame_count * encoded.vertex_count * 12 / 1e6
    print(
        f"total time with reading and writing {elapsed:.2f} s "
        f"({megabytes / elapsed:.1f} MB/s of float32 positions)"
    )
    return EXIT_OK


def encode_options(args: argparse.Namespace, *, passes: bool = True) -> EncodeOptions:
    """The encoder's options from ``encode``'s or ``batch``'s arguments; what is not given on
    the command line takes :class:`EncodeOptions`' default (no mode: its default target).
    ``passes``: whether ``--jobs`` and ``--scheduler`` say where a segmented encode's passes run
    (``batch``'s say where its tasks run)."""
    given = {
        "target_kg": args.kg,
        "ranks": args.ranks,
        "target_bpfv": args.bpfv,
        "select": args.select,
        "segment_frames": getattr(args, "segment_frames", None),
        "max_memory": getattr(args, "max_memory", None),
        "basis": getattr(args, "basis", None),
        "jobs": args.jobs if passes else None,
        "scheduler": args.scheduler if passes else None,
        "max_error": getattr(args, "max_error", None),
        "lossless": getattr(args, "lossless", None),
        "face_order": getattr(args, "face_order", None),
        "field_targets": getattr(args, "field", None),
        "field_target": getattr(args, "fields", None),
        "attachments": False if getattr(args, "no_attributes", None) else None,
        "format_version": getattr(args, "format_version", None),
    }
    return resolve_options(**{name: value for name, value in given.items() if value is not None})


def _print_attachments(header: FileInfo) -> None:
    """What the file carries beside positions and faces (format 1.5), one line each: the
    encoder's claims from the section table, as ``info`` reads it (nothing decoded)."""
    for item in header.attachments:
        label = f"{item.kind} {_text(item.name)!r}" if item.name else item.kind
        claim = ""
        if item.error is not None:
            definition, value, target = item.error
            target_text = "none" if target is None else f"{target:g}"
            claim = f"; error {_number(value)} ({_text(definition)}), target {target_text}"
        print(f"  {label}: {_text(item.description)}, {item.bytes} bytes{claim}")


def _say(line: str) -> None:
    """A segmented encode's progress, one line per pass, on standard error."""
    print(line, file=sys.stderr, flush=True)


def run_decode(args: argparse.Namespace) -> int:
    header = read_info(args.input)
    reference = load_input(args.reference, args) if args.reference else None
    if reference is not None and (reference.frame_count, reference.vertex_count) != (
        header.frames,
        header.vertices,
    ):
        raise InputError(  # before anything is written
            f"the reference has {reference.frame_count} frames of {reference.vertex_count} "
            f"vertices, the file {header.frames} of {header.vertices}",
            path=args.reference,
        )
    output = decoded_output_path(args.output, args.format)
    check_precision(args.precision, output)
    if is_gltf_output(output) and not header.segments:
        return _decode_gltf(args, header, reference, output)
    if args.glb_compress is not None:
        raise ValueError(
            f"{output}: --glb-compress applies only to the decomposition of a file of one "
            "segment written as .glb or .gltf"
        )
    if is_gltf_output(output):
        print(
            "note: a segmented file has one decomposition per segment; the glTF holds the "
            "decoded frames as morph targets (frame 0 the mesh, each other frame a target)",
            file=sys.stderr,
        )
    start = time.perf_counter()
    decoded = decode_file(
        args.input,
        output,
        frames=args.frames,
        output_format=args.format,
        overwrite=args.force,
        precision=args.precision,
        progress=True,
    )
    elapsed = time.perf_counter() - start
    print(
        f"{args.input}: {decoded.frame_count} of {header.frames} frames, "
        f"{decoded.vertex_count} vertices -> {output} in {elapsed:.2f} s"
    )
    _print_recorded(header)
    if reference is not None:
        chosen = args.frames if args.frames is not None else slice(None)
        measured = ErrorAccumulator()  # the KG error and the worst vertex in one pass
        measured.add(
            reference.vertices[chosen], decoded.vertices, frames=np.arange(header.frames)[chosen]
        )
        scope = (
            ""
            if args.frames is None
            else (
                f" (of the {decoded.frame_count} frames decoded, with their own KG denominator; "
                "the target applies to the whole sequence)"
            )
        )
        print(
            f"actual KG error against {args.reference}: {measured.kg:.5f}{scope} ({KG_DEFINITION})"
        )
        _print_actual_worst(args, measured.worst, decoded.frame_count)
    return EXIT_OK


def _print_recorded(header: FileInfo) -> None:
    """What the file says the encoder measured: its KG error, and its worst vertex if the file
    records one (files encoded with --max-error or --lossless)."""
    recorded = ""
    if header.max_distance is not None:
        recorded = (
            f"; worst vertex {worst_vertex(header.max_distance, header.max_distance_at)}"
            f"{_bound(header)}"
        )
    print(
        f"file: {header.total_bytes} bytes = {header.bpfv:.4f} bpfv; KG error recorded by the "
        f"encoder {_number(header.kg)} ({_text(header.kg_definition) or 'no definition recorded'})"
        f"{recorded}"
    )


def _print_actual_worst(args: argparse.Namespace, worst: Displacement, frames: int) -> None:
    """The worst vertex measured against ``--reference``, its frame numbered as in the file."""
    scope = "" if args.frames is None else f"of the {frames} frames decoded; "
    print(
        f"actual worst vertex against {args.reference}: {worst_vertex(worst.distance, worst.at)}"
        f" ({scope}{MAX_DISTANCE_DEFINITION})"
    )


def _bound(header: FileInfo) -> str:
    if header.target_max_distance is None:
        return ""
    return f", bound {header.target_max_distance:.6g}"


def _decode_gltf(
    args: argparse.Namespace, header: FileInfo, reference: MeshSequence | None, output: Path
) -> int:
    """decode to .glb/.gltf: the decomposition as a morph animation, and the KG error a
    viewer shows beside the file's."""
    start = time.perf_counter()
    output.parent.mkdir(parents=True, exist_ok=True)  # as for every other output
    decoder = Decoder(args.input)
    selected = None
    if reference is not None:
        selected = reference.vertices[args.frames if args.frames is not None else slice(None)]
    report = write_decomposition_gltf(
        decoder,
        output,
        frames=args.frames,
        compress=args.glb_compress or DEFAULT_COMPRESSION,
        overwrite=args.force,
        reference=selected,
    )
    print(
        f"{args.input}: {report.frames} of {header.frames} frames, {header.vertices} vertices "
        f"-> {output} (glTF morph animation: {report.targets} targets, {report.compression}, "
        f"{report.frame_rate:g} fps) in {time.perf_counter() - start:.2f} s"
    )
    _print_recorded(header)
    print(f"glTF: {report.size} bytes; {report.summary()}")
    if report.tkc_worst_reference is not None:
        _print_actual_worst(args, report.tkc_worst_reference, report.frames)
    return EXIT_OK


#: Unicode categories never printed raw from a file: control characters (a terminal's escape
#: sequences start with one), format characters (bidirectional overrides reorder the line) and
#: line or paragraph separators.
_UNPRINTED = frozenset({"Cc", "Cf", "Zl", "Zp"})


def _text(value: str | None) -> str | None:
    """A string read from a file, safe to print to a terminal: every control or format
    character escaped as Python writes it (``\\x1b``, ``\\u202e``), a backslash doubled so the
    escapes cannot be forged."""
    if value is None:
        return None
    return "".join(
        "\\\\" if c == "\\" else repr(c)[1:-1] if unicodedata.category(c) in _UNPRINTED else c
        for c in value
    )


def _number(value: float | None) -> str:
    return "unknown" if value is None else f"{value:.5f}"


def run_info(args: argparse.Namespace) -> int:
    header = read_info(args.input)
    if args.json:
        print(json.dumps(header.to_dict(), indent=2))
        return EXIT_OK
    i, k = header.ranks
    print(f"{args.input}: tuckercodec format {header.format_version}")
    print(
        f"  {header.frames} frames, {header.vertices} vertices, {header.faces} faces of up to "
        f"{header.face_width} corners"
    )
    if header.segments:
        shared = sum(segment.basis == "shared" for segment in header.segments)
        basis = "one shared U1" if shared == len(header.segments) else "a U1 each"
        print(
            f"  {len(header.segments)} segments with {basis}; largest ranks (i, 3, k) = "
            f"({i}, 3, {k})"
        )
        for segment in header.segments:
            si, sk = segment.ranks
            print(
                f"    segment {segment.index}: frames {segment.start}..{segment.stop - 1}, "
                f"ranks ({si}, 3, {sk}), {segment.basis} basis"
            )
    else:
        print(f"  ranks (i, 3, k) = ({i}, 3, {k})")
    print(f"  {header.total_bytes} bytes = {header.bpfv:.4f} bpfv (whole file)")
    target = (
        "none (fixed ranks or a size target)"
        if header.target_kg is None
        else f"{header.target_kg:g}"
    )
    print(
        f"  KG error {_number(header.kg)} "
        f"({_text(header.kg_definition) or 'no definition recorded'}), target {target}"
    )
    if header.max_distance is None:
        print(
            "  worst vertex not recorded in the file (only files encoded with --max-error or "
            f"--lossless carry it; 'tuckercodec eval ORIGINAL {args.input}' measures it)"
            f"{_bound(header)}"
        )
    else:
        print(
            f"  worst vertex {worst_vertex(header.max_distance, header.max_distance_at)} "
            f"({MAX_DISTANCE_DEFINITION}){_bound(header)}"
        )
    if header.lossless:
        print("  lossless: the encoder checked the decoded values to be the input's, bit for bit")
    if header.frame_rate is not None:
        print(f"  {header.frame_rate:g} frames per second")
    if header.time_codes is not None:
        codes = header.time_codes
        print(f"  time codes {codes[0]:g} to {codes[-1]:g}")
    if header.meters_per_unit is not None:
        print(f"  {header.meters_per_unit:g} metres per unit")
    if header.up_axis is not None:
        print(f"  {_text(header.up_axis)} up")
    print(f"  written by {_text(header.encoder) or 'an unnamed encoder'}")
    _print_attachments(header)
    for section_id, length, codec, critical in header.sections:
        kind = "" if critical else " (ancillary)"
        print(f"  section {_text(section_id):<8} {length:>10} bytes  {_text(codec)}{kind}")
    print(f"  decoded here by tuckercodec's {native.describe()}")
    return EXIT_OK
