"""The analysis verbs of the command line (rd, eval, render, demo): each reads its arguments,
does its work and prints; the codec's verbs are in :mod:`.codec`, convert's in :mod:`.convert`.

Every verb returns the exit code of success; failures are exceptions, which
:func:`tuckercodec.cli.main.main` turns into a one-line message and an exit code.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

from ..decoder import Decoder, decode
from ..decomposition.analysis import analyze
from ..encoder import encode_with_report
from ..errors import EXIT_OK, InputError
from ..io import load_sequence
from ..io.samples import SAMPLE_NAME, sample_path
from ..measures.distortion import KG_DEFINITION, MAX_DISTANCE_DEFINITION, compare, kg_error
from ..measures.perceptual import STED_DEFINITION, sted
from ..model.sequence import MeshSequence
from ..reports.text import curves_csv, targets_table, worst_vertex
from ..system.atomic import refuse_existing, write_atomic
from .inputs import is_compressed, load_input, read_options, sequence_source

PLOT_FORMATS = (".png", ".svg", ".pdf")


def _check_plot_names(*named: tuple[str, Path | None]) -> None:
    """Refuse, before any work, an image name whose format matplotlib would not be asked for."""
    for option, path in named:
        if path is not None and path.suffix.lower() not in PLOT_FORMATS:
            raise ValueError(
                f"{option} {path}: the file name must end in {', '.join(PLOT_FORMATS)}"
            )


def run_rd(args: argparse.Namespace) -> int:
    source = sequence_source(args.input)
    _check_plot_names(("--plot", args.plot), ("--heatmap", args.heatmap))
    outputs = [p for p in (args.csv, args.plot, args.heatmap) if p is not None]
    refuse_existing(outputs, args.force)  # before the work, not after it

    start = time.perf_counter()
    sequence = load_sequence(source, **read_options(args))
    loaded = time.perf_counter()
    analysis = analyze(sequence)
    analysed = time.perf_counter()

    r1, r3 = analysis.max_ranks
    label = f"built-in sample ({SAMPLE_NAME})" if args.input == "sample" else source
    print(
        f"{label}: {sequence.frame_count} frames, {sequence.vertex_count} vertices, "
        f"{sequence.faces.shape[0]} faces"
    )
    print(
        f"read in {loaded - start:.2f} s; HOSVD and exact table of {r1} x {r3} ranks in "
        f"{analysed - loaded:.2f} s"
    )
    print(f"errors: {KG_DEFINITION}; 'est.' is the paper's bound; rate Θ = S/(3KF)")
    print()
    print(targets_table(analysis, args.targets))

    if args.csv is not None:
        write_atomic(args.csv, curves_csv(analysis).encode(), overwrite=args.force)
        print(f"\nwrote {args.csv}")
    if args.plot is not None or args.heatmap is not None:
        from ..reports.plots import plot_heatmaps, plot_rd_curve  # matplotlib only when asked for

        name = Path(str(source)).stem
        if args.plot is not None:
            plot_rd_curve(
                analysis, args.plot, title=f"{name}: rate-distortion", overwrite=args.force
            )
            print(f"wrote {args.plot}")
        if args.heatmap is not None:
            plot_heatmaps(
                analysis, args.heatmap, title=f"{name}: error over ranks", overwrite=args.force
            )
            print(f"wrote {args.heatmap}")
    return EXIT_OK


def run_eval(args: argparse.Namespace) -> int:
    _check_plot_names(("--plot", args.plot))
    if args.plot is not None:
        refuse_existing([args.plot], args.force)  # before the work, not after it
    original, approximation = load_input(args.original, args), load_input(args.approximation, args)
    if original.vertices.shape != approximation.vertices.shape:
        raise InputError(
            f"{args.original} has {original.frame_count} frames of {original.vertex_count} "
            f"vertices, {args.approximation} {approximation.frame_count} of "
            f"{approximation.vertex_count}"
        )
    measured = compare(original, approximation)  # KG, worst vertex, per frame: one pass
    per_frame = measured.per_frame_kg()
    worst_frame = int(per_frame.argmax())
    worst = measured.worst
    if original.faces.shape[0]:  # STED measures edges: on A's faces, the reference's
        perceptual = sted(original, approximation, width=args.sted_width, window=args.sted_window)
        sted_figures = perceptual.to_dict()
    else:
        perceptual, sted_figures = None, None
    figures = {
        "kg": measured.kg,
        "kg_definition": KG_DEFINITION,
        "max_distance": worst.distance,  # the worst vertex, in the sequence's units
        "max_distance_at": list(worst.at),  # [frame, vertex], as info --json has it
        "max_distance_definition": MAX_DISTANCE_DEFINITION,
        "sted": sted_figures,  # None where A has no faces: STED needs edges
        "relative_error": measured.relative_error,
        "worst_frame": worst_frame,
        "worst_frame_kg_share": float(per_frame[worst_frame]),
    }
    if args.plot is not None:
        from ..reports.plots import plot_frame_errors  # matplotlib only when asked for

        title = f"{Path(args.approximation).name} against {Path(args.original).name}"
        largest = measured.per_frame_max_distance()
        plot_frame_errors(per_frame, largest, args.plot, title=title, overwrite=args.force)
    if args.json:
        print(json.dumps(figures, indent=2))
        return EXIT_OK
    print(f"KG error {figures['kg']:.6f} ({KG_DEFINITION})")
    print(f"worst vertex {worst_vertex(worst.distance, worst.at)} ({MAX_DISTANCE_DEFINITION})")
    if perceptual is None:
        print(f"STED not measured: {args.original} has no faces, and STED compares edge lengths")
    else:
        p = perceptual
        print(
            f"STED {p.value:.6g} (spatial STED_s {p.spatial:.6g}, "
            f"temporal STED_t {p.temporal:.6g}; "
            f"width {p.width}, window {p.window}, dt {p.dt:g}, c {p.c:g}, s {p.scale:.6g} = "
            "1/diagonal of A's first-frame bounding box)"
        )
        print(f"  {STED_DEFINITION}")
    print(f"relative error ||A-B||/||A|| {figures['relative_error']:.3e} (uncentred)")
    print(
        f"worst frame {worst_frame}: {per_frame[worst_frame]:.6f} of the KG error "
        "(its share; the squares of all frames' shares sum to KG squared)"
    )
    if args.plot is not None:
        print(f"wrote {args.plot}")
    return EXIT_OK


class _Frames:
    """A sequence opened for drawing single frames: a compressed file decodes only the frame
    asked for; anything else is read whole. Errors in a compressed file name it."""

    def __init__(self, source: str, args: argparse.Namespace) -> None:
        self.source = source
        self._decoder: Decoder | None = None
        self._sequence: MeshSequence | None = None
        if is_compressed(source):
            self._decoder = Decoder(source)
            self.count, self.vertex_count = self._decoder.frame_count, self._decoder.info.vertices
        else:
            self._sequence = load_input(source, args)
            self.count, self.vertex_count = self._sequence.frame_count, self._sequence.vertex_count

    def frame(self, number: int) -> MeshSequence:
        """Frame ``number`` (negative: from the end) as a one-frame sequence with the faces."""
        if not -self.count <= number < self.count:
            raise ValueError(
                f"frame {number} does not exist: {self.source} has {self.count} frames "
                f"(0..{self.count - 1})"
            )
        if self._decoder is not None:
            return self._decoder.sequence([number])
        seq = self._sequence
        assert seq is not None
        index = number % self.count
        return MeshSequence(
            seq.vertices[index : index + 1], seq.faces, frame_names=[seq.frame_names[index]]
        )


def run_render(args: argparse.Namespace) -> int:
    _check_plot_names(("-o", args.output))
    refuse_existing([args.output], args.force)  # before the work, not after it
    frames = _Frames(args.input, args)
    shown = frames.frame(args.frame)
    errors = None
    if args.reference is not None:
        reference = _Frames(args.reference, args)
        if (reference.count, reference.vertex_count) != (frames.count, frames.vertex_count):
            raise InputError(  # frames must correspond one to one, as for decode --reference
                f"the reference has {reference.count} frames of {reference.vertex_count} vertices, "
                f"{args.input} {frames.count} of {frames.vertex_count}",
                path=args.reference,
            )
        errors = np.linalg.norm(shown.vertices[0] - reference.frame(args.frame).vertices[0], axis=1)

    from ..reports.plots import render_frame  # matplotlib only when asked for

    count = frames.count
    frame = args.frame % count
    name = "built-in sample" if args.input == "sample" else Path(args.input).name
    title = f"{name}, frame {frame} ({shown.frame_names[0]})"
    if errors is not None:
        title += (
            f"\nerror against {Path(args.reference).name}: max {errors.max():.4g}, "
            f"mean {errors.mean():.4g}"
        )
    render_frame(
        shown.vertices[0],
        shown.triangles(),
        args.output,
        errors=errors,
        title=title,
        up=args.up,
        overwrite=args.force,
    )
    print(
        f"wrote {args.output}: frame {frame} of {count}, {shown.vertex_count} vertices"
        + ("" if errors is None else f", vertex error up to {errors.max():.6g} scene units")
    )
    return EXIT_OK


def run_demo(args: argparse.Namespace) -> int:
    sequence = load_sequence(sample_path(), progress=False)
    print(
        f"built-in sample ({SAMPLE_NAME}): {sequence.frame_count} frames, "
        f"{sequence.vertex_count} vertices, {sequence.faces.shape[0]} faces"
    )
    print(f"errors: {KG_DEFINITION}; bpfv counts the whole file")
    print()
    header = (
        f"{'target KG':>9}  {'i':>3}  {'k':>3}  {'bytes':>8}  {'bpfv':>7}  {'ratio':>6}  "
        f"{'decoded KG':>10}  {'encode s':>8}  {'decode s':>8}"
    )
    print(header)
    print("-" * len(header))
    for target in args.targets:
        result = encode_with_report(sequence, target_kg=target)
        start = time.perf_counter()
        decoded = decode(result.data)
        decode_seconds = time.perf_counter() - start
        measured = kg_error(sequence, decoded)  # measured again here, not taken from the report
        r = result.report
        print(
            f"{target:>9g}  {r.ranks[0]:>3}  {r.ranks[1]:>3}  {r.total_bytes:>8}  {r.bpfv:>7.3f}  "
            f"{r.ratio:>5.0f}x  {measured:>10.5f}  {r.seconds:>8.2f}  {decode_seconds:>8.3f}"
        )
    print()
    print("Try: tuckercodec encode sample -o cloth.tkc && tuckercodec decode cloth.tkc -o frames/")
    return EXIT_OK
