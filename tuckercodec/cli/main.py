"""The ``tuckercodec`` command line: parse, run one verb, turn failures into exit codes.

Exit codes (also in the README): 0 success; 1 an output that exists (without --force; with it, a
folder tuckercodec did not write) or another I/O failure; 2 a usage error; 3 an invalid or
corrupt compressed file; 4 a bad input mesh sequence; 5 a target no file can meet; 6 a missing
optional dependency; 7 some inputs of a batch failed (the others were written); 130 or 143
interrupted by Ctrl-C or SIGTERM (but ``view`` exits 0 on Ctrl-C, the way its server is meant to
stop). Every failure is one line on standard error.
"""

from __future__ import annotations

import argparse
import os
import signal
import sys
import threading
from collections.abc import Callable, Sequence

from ..errors import EXIT_FAILURE
from . import addon, batch, codec, commands, convert, view
from .arguments import build_parser
from .failures import describe_failure

_VERBS: dict[str, Callable[[argparse.Namespace], int]] = {
    "demo": commands.run_demo,
    "encode": codec.run_encode,
    "decode": codec.run_decode,
    "info": codec.run_info,
    "eval": commands.run_eval,
    "render": commands.run_render,
    "rd": commands.run_rd,
    "convert": convert.run_convert,
    "formats": convert.run_formats,
    "batch": batch.run_batch,
    "view": view.run_view,
    "blender-addon": addon.run_blender_addon,
}


class _Terminated(KeyboardInterrupt):
    """SIGTERM, raised like Ctrl-C so that every half-written output is removed on the way out."""


def _raise_terminated(signum: int, frame: object) -> None:
    raise _Terminated()


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; returns the exit code."""
    args = build_parser().parse_args(argv)
    if threading.current_thread() is not threading.main_thread():
        return _run(args)
    # Python's default for SIGTERM ends the process without running any cleanup.
    previous = signal.signal(signal.SIGTERM, _raise_terminated)
    try:
        return _run(args)
    finally:
        signal.signal(signal.SIGTERM, previous)


def _fail(message: str) -> None:
    print(f"tuckercodec: {message}", file=sys.stderr)


def _run(args: argparse.Namespace) -> int:
    """Run one verb, turning every expected failure into a one-line message and exit code."""
    try:
        return _VERBS[args.verb](args)
    except BrokenPipeError:  # the reader went away (`| head`): stop quietly, like other tools
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return EXIT_FAILURE
    except Exception as error:
        failure = describe_failure(error)
        if failure is None:  # a bug: its traceback
            raise
        kind, message, code = failure
        _fail(f"{kind}{message}")
        return code
    except KeyboardInterrupt as interrupt:
        _fail("interrupted")
        return 128 + (signal.SIGTERM if isinstance(interrupt, _Terminated) else signal.SIGINT)
