"""The command line's arguments: the parser of every verb and the types of their options.

Every verb's options live here together, one function a verb, where a reader compares them (the
same mode, read and executor options recur across verbs).
"""

from __future__ import annotations

import argparse
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

from .._version import __version__
from ..blender.package import PLATFORM_TAGS
from ..decomposition.analysis import SELECTIONS
from ..encoder import DEFAULT_TARGET_KG
from ..encoder.options import BASES, FACE_ORDERS, parse_field_target, parse_max_error
from ..encoder.plan import DEFAULT_SEGMENT_FRAMES, parse_size
from ..encoder.versions import VERSIONS, parse_format_version
from ..errors import DependencyError
from ..files import SUFFIX
from ..gltf_export import COMPRESSIONS
from ..io.registry import writable_formats
from ..measures.distortion import KG_DEFINITION
from ..measures.perceptual import STED_DEFINITION
from ..reports.text import DEFAULT_TARGETS
from ..system import native

if TYPE_CHECKING:
    _Verbs = argparse._SubParsersAction[argparse.ArgumentParser]


def _targets(text: str) -> list[float]:
    try:
        values = [float(part) for part in text.split(",") if part.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"not a comma-separated list of numbers: {text!r}"
        ) from None
    if not values or any(not (v > 0 and v < float("inf")) for v in values):
        raise argparse.ArgumentTypeError(f"targets must be positive numbers, got {text!r}")
    return values


def _positive(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not (value > 0 and value < float("inf")):
        raise argparse.ArgumentTypeError(f"must be a positive number, got {text!r}")
    return value


def _at_least(low: int) -> Callable[[str], int]:
    """An argparse type: an integer no smaller than ``low``."""

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"not an integer: {text!r}") from None
        if value < low:
            raise argparse.ArgumentTypeError(f"must be at least {low}, got {text}")
        return value

    return parse


def _ranks(text: str) -> tuple[int, int]:
    parts = text.split(",")
    try:
        i, k = (int(part) for part in parts)
    except ValueError:
        raise argparse.ArgumentTypeError(f"ranks are two integers 'i,k', got {text!r}") from None
    return i, k


def _frames(text: str) -> slice | list[int]:
    """``a:b`` (either end may be left out; negative numbers count from the end, as in Python)
    or a single frame ``n``; frames count from 0."""
    try:
        if ":" not in text:
            return [int(text)]
        start, stop = text.split(":")
        selection = slice(int(start) if start else None, int(stop) if stop else None)
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"frames are 'a:b', 'a:', ':b' or 'n', got {text!r}"
        ) from None
    if (
        selection.start is not None
        and selection.stop is not None
        and (selection.start >= 0) == (selection.stop >= 0)
        and selection.start >= selection.stop
    ):
        raise argparse.ArgumentTypeError(f"the range {text} is empty: frames a to b-1 need a < b")
    return selection


def _size(text: str) -> int:
    try:
        return parse_size(text)
    except ValueError as error:
        raise argparse.ArgumentTypeError(str(error)) from None


def _port(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a port number: {text!r}") from None
    if not 0 <= value <= 65535:
        raise argparse.ArgumentTypeError(f"a port is 0 to 65535, got {text}")
    return value


class _VersionAction(argparse.Action):
    """``--version``: the package's version and the implementation that runs (the compiled core
    or pure Python, tuckercodec.system.native), which is looked for only when asked."""

    def __init__(self, option_strings: list[str], dest: str, **kwargs: Any) -> None:
        super().__init__(option_strings, dest, nargs=0, default=argparse.SUPPRESS, **kwargs)

    def __call__(
        self,
        parser: argparse.ArgumentParser,
        namespace: argparse.Namespace,
        values: Any,
        option_string: str | None = None,
    ) -> None:
        try:
            implementation = native.describe()
        except DependencyError as error:  # TUCKERCODEC_NATIVE misspelt, or =1 with no core
            parser.exit(error.exit_code, f"tuckercodec: error: {error}\n")
        print(f"tuckercodec {__version__}, {implementation}")
        parser.exit()


def build_parser() -> argparse.ArgumentParser:
    """The parser of every verb and option, the verbs in the order ``--help`` lists them."""
    parser = argparse.ArgumentParser(
        prog="tuckercodec",
        description="Compression of animated meshes (fixed connectivity) by truncated HOSVD.",
        epilog=f"Errors are KG errors in percent: {KG_DEFINITION}.",
    )
    parser.add_argument(
        "--version",
        action=_VersionAction,
        help="print the version, and whether the compiled core or pure Python runs, and exit",
    )
    verbs = parser.add_subparsers(dest="verb", metavar="VERB")
    verbs.required = True
    for add_verb in (
        _add_rd,
        _add_encode,
        _add_batch,
        _add_decode,
        _add_info,
        _add_eval,
        _add_render,
        _add_convert,
        _add_view,
        _add_formats,
        _add_demo,
        _add_blender_addon,
    ):
        add_verb(verbs)
    return parser


def _add_rd(verbs: _Verbs) -> None:
    """The ``rd`` verb (tuckercodec.cli.commands): the exact rate-distortion table."""
    rd = verbs.add_parser(
        "rd",
        help="rate-distortion analysis: exact error of every truncation (i, 3, k)",
        description=(
            "Decompose the sequence once and print, for each target KG error, the cheapest "
            "ranks (i, 3, k) by the exact table and by the seed paper's bound alone."
        ),
    )
    rd.add_argument("input", help=_SEQUENCE_HELP)
    rd.add_argument(
        "--targets",
        type=_targets,
        default=list(DEFAULT_TARGETS),
        metavar="KG,KG,...",
        help="target KG errors in percent (default: %(default)s)",
    )
    rd.add_argument("--csv", type=Path, metavar="FILE", help="write the whole curves as CSV")
    rd.add_argument(
        "--plot", type=Path, metavar="FILE.png", help="draw Θ against KG (paper's Fig. 1)"
    )
    rd.add_argument(
        "--heatmap",
        type=Path,
        metavar="FILE.png",
        help="draw log KG and log ψ over (i, k) (Fig. 3)",
    )
    rd.add_argument("--force", action="store_true", help="replace output files that exist")
    _add_read_options(rd)


def _add_encode(verbs: _Verbs) -> None:
    """The ``encode`` verb (tuckercodec.cli.codec): one sequence into one file."""
    encode = verbs.add_parser(
        "encode",
        help="compress a mesh sequence into one file",
        description=(
            "Compress a sequence. One mode: --kg (the decoded KG error never exceeds it; default "
            f"{DEFAULT_TARGET_KG}), --ranks i,k, or --bpfv (the smallest error that fits)."
        ),
    )
    encode.add_argument("input", help=_SEQUENCE_HELP)
    encode.add_argument("-o", "--output", type=Path, required=True, metavar=f"OUT{SUFFIX}")
    _add_mode_options(encode)
    encode.add_argument("--force", action="store_true", help="replace the output if it exists")
    _add_segment_options(encode)
    _add_read_options(encode, memory=None)  # --max-memory is among the large sequences


def _add_batch(verbs: _Verbs) -> None:
    """The ``batch`` verb (tuckercodec.cli.batch): encode's modes and reading options, many
    inputs, and where the work runs."""
    batch = verbs.add_parser(
        "batch",
        help="compress many mesh sequences the same way, in parallel",
        description=(
            f"Encode each INPUT into OUTDIR/<name>{SUFFIX} (name: the input's file or folder "
            "name), one input per task, as encode would (default: --kg "
            f"{DEFAULT_TARGET_KG}): in this process, on --jobs N worker processes, or on a Dask "
            "cluster (--scheduler). A failing input is reported and the others go on; the exit "
            "code is 0 if every input was written, 7 if some failed."
        ),
    )
    batch.add_argument("inputs", nargs="+", metavar="INPUT", help=_SEQUENCE_HELP)
    batch.add_argument(
        "-o", "--output", type=Path, required=True, metavar="OUTDIR", help="made if missing"
    )
    _add_mode_options(batch)
    _add_executor_options(
        batch,
        "encode N inputs at a time in worker processes on this machine (Dask; extra [dask])",
        "run on the Dask cluster of this scheduler (tcp://host:port); its workers need this "
        "tuckercodec and must read the inputs at the same absolute paths",
    )
    batch.add_argument("--force", action="store_true", help="replace outputs that exist")
    _add_read_options(batch, memory=_ENCODE_MEMORY_HELP)


def _add_decode(verbs: _Verbs) -> None:
    """The ``decode`` verb (tuckercodec.cli.codec): frames out of a file, in any written format."""
    decode = verbs.add_parser(
        "decode",
        help="rebuild the frames of a compressed file as OBJ files or a sequence file",
        description=(
            "Decode all frames, or a range, to a folder of OBJ files (with faces) or a "
            "sequence file chosen by its suffix (.npz, .usd, .abc, .pc2, .mdd, .pvd...); "
            ".glb/.gltf writes the decomposition as a playable morph-target animation."
        ),
    )
    decode.add_argument("input", help=f"a compressed file ({SUFFIX})")
    decode.add_argument("-o", "--output", type=Path, required=True, metavar="OUTDIR|OUTFILE")
    decode.add_argument(
        "--frames",
        type=_frames,
        metavar="A:B",
        help=(
            "frames a to b-1, counted from 0 (negative: from the end; clipped to the file, as "
            "Python slices)"
        ),
    )
    decode.add_argument(
        "--format",
        choices=writable_formats(),
        help="default: the format OUT's suffix names, else a folder of OBJ files",
    )
    decode.add_argument(
        "--reference", metavar="ORIGINAL", help="report the actual error against this sequence"
    )
    decode.add_argument(
        "--glb-compress",
        choices=COMPRESSIONS,
        help=(
            "glTF output: none (float32), quantize (KHR_mesh_quantization, the default: plays "
            "natively in three.js, Babylon.js, Blender, glTFast) or meshopt "
            "(EXT_meshopt_compression, smallest; three.js needs its MeshoptDecoder). Keyframes "
            "at the file's frame rate, 24 fps when it records none"
        ),
    )
    _add_precision(decode)
    decode.add_argument("--force", action="store_true", help="replace output files that exist")
    _add_read_options(decode, "--reference")


def _add_info(verbs: _Verbs) -> None:
    """The ``info`` verb (tuckercodec.cli.codec): a file's header."""
    info = verbs.add_parser(
        "info",
        help="show a compressed file's header",
        description="Read the header; decode nothing.",
    )
    info.add_argument("input", help=f"a compressed file ({SUFFIX})")
    info.add_argument("--json", action="store_true", help="print JSON")


def _add_eval(verbs: _Verbs) -> None:
    """The ``eval`` verb (tuckercodec.cli.commands): the error measures of B against A."""
    evaluate = verbs.add_parser(
        "eval",
        help="compare two sequences: KG error, STED, relative error, largest displacement",
        description=(
            "Compare B with the original A (sequences, or compressed files, which are decoded): "
            f"KG error, STED on A's faces ({STED_DEFINITION}), relative error, largest vertex "
            "displacement and the worst frame."
        ),
    )
    evaluate.add_argument("original", help="the original sequence A")
    evaluate.add_argument("approximation", help="the sequence B to judge")
    evaluate.add_argument("--json", action="store_true", help="print JSON")
    evaluate.add_argument(
        "--sted-width",
        type=_at_least(1),
        default=1,
        metavar="W",
        help="STED's neighbourhood: vertices within W edges (default: %(default)s)",
    )
    evaluate.add_argument(
        "--sted-window",
        type=_at_least(0),
        default=5,
        metavar="N",
        help="STED's temporal window: +-N frames (default: %(default)s)",
    )
    evaluate.add_argument(
        "--plot",
        type=Path,
        metavar="FILE.png",
        help="draw each frame's KG share and worst-vertex error over time",
    )
    evaluate.add_argument("--force", action="store_true", help="replace the plot if it exists")
    _add_read_options(evaluate, "A and B")


def _add_render(verbs: _Verbs) -> None:
    """The ``render`` verb (tuckercodec.cli.commands): one frame drawn in 3D."""
    render = verbs.add_parser(
        "render",
        help="draw one frame in 3D, coloured by its error against a reference",
        description=(
            "Draw frame n of SEQ (a compressed file decodes only that frame) with equal scaling "
            "on every axis: shaded, or with --reference coloured by each vertex's distance to "
            "the reference's frame n, in scene units."
        ),
    )
    render.add_argument("input", metavar="SEQ", help="a sequence, a compressed file, or 'sample'")
    render.add_argument(
        "--frame",
        type=int,
        required=True,
        metavar="N",
        help="the frame to draw, counted from 0 (negative: from the end)",
    )
    render.add_argument("-o", "--output", type=Path, required=True, metavar="IMG.png")
    render.add_argument(
        "--reference", metavar="ORIGINAL", help="colour by the error against this sequence"
    )
    render.add_argument(
        "--up",
        choices=("x", "y", "z"),
        default="y",
        help="the scene axis drawn upwards (default: %(default)s, as in most OBJ files)",
    )
    render.add_argument("--force", action="store_true", help="replace the image if it exists")
    _add_read_options(render, "SEQ and the reference")


def _add_convert(verbs: _Verbs) -> None:
    """The ``convert`` verb (tuckercodec.cli.convert): a sequence from one format to another."""
    convert = verbs.add_parser(
        "convert",
        help="convert a mesh sequence between file formats",
        description=(
            "Read a sequence (or decode a compressed file) and write it in the format OUT's "
            "suffix names; a name without one is a folder of OBJ files. Lossless where both "
            "formats carry the data: what OUT's format cannot hold is listed."
        ),
    )
    convert.add_argument("input", help=_SEQUENCE_HELP)
    convert.add_argument("output", type=Path, metavar="OUT", help="the file or folder to write")
    _add_precision(convert)
    convert.add_argument("--force", action="store_true", help="replace output files that exist")
    _add_read_options(convert)


def _add_view(verbs: _Verbs) -> None:
    """The ``view`` verb (tuckercodec.cli.view): serve the viewer page, or export it."""
    view = verbs.add_parser(
        "view",
        help="play a compressed file in a web browser (served on 127.0.0.1, or exported)",
        description=(
            "Check FILE with the Python decoder, then serve, on 127.0.0.1 only, a page that "
            "decodes it in the browser (the JavaScript decoder) and plays it: play/pause, frame "
            "slider, the file's frame rate, orbit camera, shading, wireframe. With --reference, "
            "the original beside it or overlaid, vertices coloured by their distance to it, and "
            "each frame's KG error. Ctrl-C stops the server (exit 0). Nothing is fetched from "
            "the network: three.js and the decoder ship with the package."
        ),
    )
    view.add_argument("input", metavar=f"FILE{SUFFIX}", help=f"a compressed file ({SUFFIX})")
    view.add_argument(
        "--reference",
        metavar="ORIGINAL",
        help="the original sequence (same frames and vertices), to compare with",
    )
    view.add_argument(
        "--port",
        type=_port,
        metavar="N",
        help="the port to listen on (default: a free one, chosen by the system)",
    )
    view.add_argument("--open", action="store_true", help="open the page in a web browser")
    view.add_argument(
        "--export-html",
        type=Path,
        metavar="DIR",
        help=(
            "write the page, its scripts, the file (and the reference) to the folder DIR, for "
            "any static web server, instead of serving"
        ),
    )
    view.add_argument(
        "--force",
        action="store_true",
        help="with --export-html: replace DIR if it is a previous export or empty",
    )
    _add_read_options(view, "the reference")


def _add_formats(verbs: _Verbs) -> None:
    """The ``formats`` verb (tuckercodec.cli.convert): what this installation reads and writes."""
    verbs.add_parser(
        "formats",
        help="list the sequence formats: suffixes, options, what each keeps, extras",
        description="List every sequence format this installation knows, and what it needs.",
    )


def _add_demo(verbs: _Verbs) -> None:
    """The ``demo`` verb (tuckercodec.cli.commands): the built-in sample at a few targets."""
    demo = verbs.add_parser(
        "demo",
        help="encode and decode the built-in sample (a simulated cloth, 60 frames)",
        description="Encode the built-in cloth sample at a few KG targets, decode it and measure.",
    )
    demo.add_argument(
        "--targets",
        type=_targets,
        default=[1.0, 0.1, 0.02],
        metavar="KG,KG,...",
        help="target KG errors in percent (default: %(default)s)",
    )


def _add_blender_addon(verbs: _Verbs) -> None:
    """The ``blender-addon`` verb (tuckercodec.cli.addon): the Blender add-on's zip."""
    addon = verbs.add_parser(
        "blender-addon",
        help="write the Blender add-on (import and export .tkc) as an installable zip",
        description=(
            "Write the Blender 4.2+ extension tuckercodec_blender (File > Import and Export of "
            ".tkc files) as one zip with the wheels it needs (tuckercodec's own, and scipy, "
            "msgpack and zstandard's for Blender's Python 3.11, fetched with pip download). "
            "Install it with Edit > Preferences > Get Extensions > Install from Disk."
        ),
    )
    addon.add_argument("output", type=Path, metavar="OUT.zip", help="the zip to write")
    addon.add_argument(
        "--platform",
        action="append",
        choices=sorted(PLATFORM_TAGS),
        help="a Blender platform to bundle wheels for (repeat for several; default: this "
        "machine's)",
    )
    addon.add_argument("--force", action="store_true", help="replace OUT.zip if it exists")


# ------------------------------------------------------------------------------------------
# option groups several verbs share


_SEQUENCE_HELP = (
    "a folder of OBJ frames, a glob, a sequence file (.npz, .usd, .abc, .pc2, .mdd, .glb, "
    ".pvd...), or 'sample'"
)


#: --max-memory's help where it bounds the reading only.
_READ_MEMORY_HELP = (
    "the most memory a read may fill from compressed data (a zlib block, a deflated .npz "
    "member, a filtered HDF5 dataset), e.g. 2GB or 512MiB (default: half the machine's)"
)


def _add_read_options(
    parser: argparse.ArgumentParser, applies_to: str = "INPUT", memory: str | None = ""
) -> None:
    """The options some sequence formats need to be read (tuckercodec.io.ReadOptions), and
    --max-memory (help ``memory``, or the reading's own if empty; ``None``: the verb has it
    among its own options)."""
    group = parser.add_argument_group(f"reading {applies_to}")
    if memory is not None:
        group.add_argument(
            "--max-memory", type=_size, metavar="SIZE", help=memory or _READ_MEMORY_HELP
        )
    group.add_argument("--prim", metavar="PATH", help="USD: the mesh prim, if several")
    group.add_argument(
        "--object", dest="object_path", metavar="PATH", help="Alembic: the mesh object, if several"
    )
    group.add_argument(
        "--faces",
        type=Path,
        metavar="MESH",
        help="PC2/MDD/.npy: take the faces from this mesh file",
    )
    group.add_argument(
        "--fps",
        type=_positive,
        metavar="RATE",
        help="glTF: sample the animation at this rate (default: at its keyframes)",
    )


def _add_precision(parser: argparse.ArgumentParser) -> None:
    """OBJ output's digits (decode and convert)."""
    parser.add_argument(
        "--precision",
        type=int,
        metavar="DIGITS",
        help="significant digits in OBJ files (default: exact)",
    )


#: --max-memory's help where it bounds an encode too.
_ENCODE_MEMORY_HELP = (
    "memory the encode may use, and the most its read may fill from compressed data, e.g. 2GB "
    "or 512MiB (default: half the machine's)"
)


def _add_segment_options(encode: argparse.ArgumentParser) -> None:
    """encode's options for sequences larger than memory (format 1.1's segments)."""
    large = encode.add_argument_group(
        "large sequences",
        "A sequence whose whole encode would not fit --max-memory is read in passes and written "
        "in segments of frames (format 1.1); otherwise the file is one decomposition (1.0). "
        "Either is 1.2 when it uses that version's coding tools.",
    )
    large.add_argument(
        "--segment-frames",
        type=_at_least(1),
        metavar="N",
        help="segments of N frames, each its own decomposition (default: only when needed, "
        f"then {DEFAULT_SEGMENT_FRAMES})",
    )
    large.add_argument("--max-memory", type=_size, metavar="SIZE", help=_ENCODE_MEMORY_HELP)
    large.add_argument(
        "--basis",
        choices=BASES,
        help="with segments: one U1 shared by all (default, smaller) or one per segment",
    )
    _add_executor_options(
        large,
        "with segments: run the passes on N worker processes (Dask; extra [dask]); the file is "
        "the same bytes",
        "with segments: run the passes on the Dask cluster of this scheduler (tcp://host:port); "
        "its workers must read the input at the same absolute path",
    )


def _max_error(text: str) -> float | str:
    """--max-error: a positive length or a percentage of the bounding-box diagonal."""
    try:
        return parse_max_error(text)
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected a positive length or a percentage such as 0.1%, got {text!r}"
        ) from None


def _field_target(text: str) -> tuple[str, str]:
    """--field NAME=TARGET: the name and its target, checked."""
    name, equals, target = text.rpartition("=")
    if not equals or not name:
        raise argparse.ArgumentTypeError(f"expected NAME=TARGET, got {text!r}")
    try:
        return name, parse_field_target(target, f"field {name!r}")
    except ValueError as error:
        raise argparse.ArgumentTypeError(str(error)) from None


def _format_version(text: str) -> str:
    """--format-version: 1.0 to the newest, checked."""
    try:
        return parse_format_version(text)
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected one of {', '.join(VERSIONS)}, got {text!r}"
        ) from None


def _add_mode_options(parser: argparse.ArgumentParser) -> None:
    """The encoder's three modes, one at a time, and how ranks are selected."""
    mode = parser.add_mutually_exclusive_group()
    mode.add_argument("--kg", type=_positive, metavar="KG", help="target KG error in percent")
    mode.add_argument("--ranks", type=_ranks, metavar="I,K", help="fixed ranks (i, 3, k)")
    mode.add_argument(
        "--bpfv", type=_positive, metavar="BPFV", help="target size, bits per frame per vertex"
    )
    parser.add_argument(
        "--max-error",
        type=_max_error,
        metavar="D",
        help="no decoded vertex farther than D from the input (a length, or P%% of the bounding "
        "box's diagonal); alone, with --kg or with --ranks (format 1.3 where corrections are "
        "needed)",
    )
    parser.add_argument(
        "--lossless",
        action="store_true",
        default=None,  # not given: EncodeOptions' default
        help="decode to the input's values bit for bit (format 1.3); alone",
    )
    parser.add_argument(
        "--select",
        choices=SELECTIONS,
        help="choose ranks by the exact error table (default) or by the seed paper's bound",
    )
    parser.add_argument(
        "--face-order",
        choices=FACE_ORDERS,
        help="keep the faces in their given order: when they carry data (auto, the default), "
        "always (given) or never (walk: smallest, the data follow the walk's order)",
    )
    parser.add_argument(
        "--field",
        action="append",
        type=_field_target,
        metavar="NAME=TARGET",
        help="the error target of an animated field: rel:P (P percent, the KG measure over its "
        "components), max:E (no value off by more than E) or lossless; repeat for each field",
    )
    parser.add_argument(
        "--fields",
        metavar="TARGET",
        help="the target of every field --field does not name (default: lossless with "
        "--lossless, else rel: the positions' KG target)",
    )
    parser.add_argument(
        "--no-attributes",
        action="store_true",
        default=None,
        help="write the positions and faces alone: no UVs, normals, colours, face sets or fields",
    )
    parser.add_argument(
        "--format-version",
        type=_format_version,
        metavar="1.N",
        help=f"the newest format version the file may be, for decoders that read only up to it "
        f"(default {VERSIONS[-1]}); below 1.6 no adaptive coding, below 1.2 neither "
        "faces-traverse nor the mesh predictors; an option or data that needs a later version "
        "(--lossless and --max-error 1.3, segments 1.1, time codes 1.4, attributes 1.5) is "
        "refused with exit 2",
    )


def _add_executor_options(
    parser: argparse.ArgumentParser | argparse._ArgumentGroup, jobs_help: str, scheduler_help: str
) -> None:
    """Where tasks run: --jobs N workers on this machine or a --scheduler's cluster."""
    where = parser.add_mutually_exclusive_group()
    where.add_argument("--jobs", type=_at_least(1), metavar="N", help=jobs_help)
    where.add_argument("--scheduler", metavar="ADDRESS", help=scheduler_help)
