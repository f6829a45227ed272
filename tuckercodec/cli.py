"""The ``tuckercodec`` command line.

Exit codes: 0 success; 1 an output that exists (without --force) or another I/O failure;
2 a usage error; 3 an invalid or corrupt compressed file; 4 a bad input mesh sequence.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from collections.abc import Sequence
from pathlib import Path

from ._version import __version__
from .analysis import analyze
from .atomic import refuse_existing, write_atomic
from .errors import DependencyError, InputError, TuckerCodecError
from .metrics import KG_DEFINITION
from .report import DEFAULT_TARGETS, curves_csv, targets_table
from .samples import SAMPLE_NAME, sample_path
from .seqio import load_sequence

EXIT_OK, EXIT_FAILURE, EXIT_USAGE, EXIT_CORRUPT, EXIT_BAD_INPUT = 0, 1, 2, 3, 4


def _targets(text: str) -> list[float]:
    try:
        values = [float(part) for part in text.split(",") if part.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a comma-separated list of numbers: {text!r}") from None
    if not values or any(not (v > 0 and v < float("inf")) for v in values):
        raise argparse.ArgumentTypeError(f"targets must be positive numbers, got {text!r}")
    return values


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="tuckercodec",
        description="Compression of animated meshes (fixed connectivity) by truncated HOSVD.",
        epilog=f"Errors are KG errors in percent: {KG_DEFINITION}.",
    )
    parser.add_argument("--version", action="version", version=f"tuckercodec {__version__}")
    verbs = parser.add_subparsers(dest="verb", metavar="VERB")
    verbs.required = True

    rd = verbs.add_parser(
        "rd",
        help="rate-distortion analysis: exact error of every truncation (i, 3, k)",
        description=(
            "Decompose the sequence once and print, for each target KG error, the cheapest "
            "ranks (i, 3, k) by the exact table and by the seed paper's bound alone."
        ),
    )
    rd.add_argument("input", help="a folder of OBJ frames, a glob, an .npz, or 'sample'")
    _add_rd_options(rd)

    demo = verbs.add_parser(
        "demo",
        help="run the analysis on the built-in sample (a simulated cloth, 60 frames)",
        description="The rate-distortion analysis of the built-in cloth sample.",
    )
    _add_rd_options(demo)
    return parser


def _add_rd_options(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--targets",
        type=_targets,
        default=list(DEFAULT_TARGETS),
        metavar="KG,KG,...",
        help="target KG errors in percent (default: %(default)s)",
    )
    parser.add_argument("--csv", type=Path, metavar="FILE", help="write the whole curves as CSV")
    parser.add_argument("--plot", type=Path, metavar="FILE.png", help="draw Θ against KG (paper's Fig. 1)")
    parser.add_argument(
        "--heatmap", type=Path, metavar="FILE.png", help="draw log KG and log ψ over (i, k) (Fig. 3)"
    )
    parser.add_argument("--force", action="store_true", help="replace output files that exist")


PLOT_FORMATS = (".png", ".svg", ".pdf")


def _run_rd(args: argparse.Namespace, source: str | Path) -> int:
    for option, path in (("--plot", args.plot), ("--heatmap", args.heatmap)):
        if path is not None and path.suffix.lower() not in PLOT_FORMATS:
            raise ValueError(f"{option} {path}: the file name must end in {', '.join(PLOT_FORMATS)}")
    outputs = [p for p in (args.csv, args.plot, args.heatmap) if p is not None]
    refuse_existing(outputs, args.force)  # before the work, not after it

    start = time.perf_counter()
    sequence = load_sequence(source)
    loaded = time.perf_counter()
    analysis = analyze(sequence)
    analysed = time.perf_counter()

    r1, r3 = analysis.max_ranks
    label = f"built-in sample ({SAMPLE_NAME})" if source == sample_path() else source
    print(f"{label}: {sequence.frame_count} frames, {sequence.vertex_count} vertices, "
          f"{sequence.faces.shape[0]} faces")
    print(f"read in {loaded - start:.2f} s; HOSVD and exact table of {r1} x {r3} ranks in "
          f"{analysed - loaded:.2f} s")
    print(f"errors: {KG_DEFINITION}; 'est.' is the paper's bound; rate Θ = S/(3KF)")
    print()
    print(targets_table(analysis, args.targets))

    if args.csv is not None:
        write_atomic(args.csv, curves_csv(analysis).encode(), overwrite=args.force)
        print(f"\nwrote {args.csv}")
    if args.plot is not None or args.heatmap is not None:
        from .plots import plot_heatmaps, plot_rd_curve  # matplotlib only when asked for

        name = Path(str(source)).stem
        if args.plot is not None:
            plot_rd_curve(analysis, args.plot, title=f"{name}: rate-distortion", overwrite=args.force)
            print(f"wrote {args.plot}")
        if args.heatmap is not None:
            plot_heatmaps(analysis, args.heatmap, title=f"{name}: error over ranks", overwrite=args.force)
            print(f"wrote {args.heatmap}")
    return EXIT_OK


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; returns the exit code."""
    parser = _parser()
    args = parser.parse_args(argv)
    try:
        if args.verb == "demo":
            return _run_rd(args, sample_path())
        source = sample_path() if args.input == "sample" else args.input
        return _run_rd(args, source)
    except InputError as error:
        print(f"tuckercodec: bad input: {error}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except DependencyError as error:
        print(f"tuckercodec: {error}", file=sys.stderr)
        return EXIT_FAILURE
    except TuckerCodecError as error:
        print(f"tuckercodec: error: {error}", file=sys.stderr)
        return EXIT_CORRUPT
    except FileExistsError as error:
        print(f"tuckercodec: {error}", file=sys.stderr)
        return EXIT_FAILURE
    except ValueError as error:  # a target that cannot be met, a rank out of range
        print(f"tuckercodec: {error}", file=sys.stderr)
        return EXIT_USAGE
    except BrokenPipeError:  # the reader went away (`| head`): stop quietly, like other tools
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return EXIT_FAILURE
    except OSError as error:
        print(f"tuckercodec: {error.filename or ''}: {error.strerror or error}", file=sys.stderr)
        return EXIT_FAILURE
    except KeyboardInterrupt:
        print("tuckercodec: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
