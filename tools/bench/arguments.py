"""The options several suites share, each declared once: the sequences measured, how many timed
runs, and where results are written. A suite adds the ones it takes, with its own default."""

from __future__ import annotations

import argparse


class UsageError(Exception):
    """A suite's options do not fit together; the runner reports it as argparse reports its
    own errors (the suite's usage, exit status 2)."""


def positive_int(text: str) -> int:
    """An argparse type: an integer of at least 1."""
    value = int(text)
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be at least 1, not {value}")
    return value


SEQUENCE_HELP = "a sequence file, a folder of OBJ frames, or 'sample' (the built-in cloth)"


def sequences(
    parser: argparse.ArgumentParser, default: str, initial: list[str] | None = None
) -> None:
    """``SEQUENCE ...``: the sequences a suite measures, any number; ``default`` says which
    when none is given (``initial``, or what the suite finds itself)."""
    parser.add_argument(
        "sequences",
        nargs="*",
        metavar="SEQUENCE",
        default=initial if initial is not None else [],
        help=f"{SEQUENCE_HELP} (default: {default})",
    )


def sequence(parser: argparse.ArgumentParser, initial: str, default: str) -> None:
    """``[SEQUENCE]``: the one sequence a suite measures, ``initial`` when none is given."""
    parser.add_argument(
        "sequence", nargs="?", default=initial, help=f"{SEQUENCE_HELP} (default: {default})"
    )


def repeat(
    parser: argparse.ArgumentParser, default: int, what: str = "timed runs, the median reported"
) -> None:
    """``--repeat N``: how many times each measure is timed."""
    parser.add_argument(
        "--repeat", type=positive_int, default=default, help=f"{what} (default {default})"
    )


def output(parser: argparse.ArgumentParser, what: str, default: str | None = None) -> None:
    """``--out PATH`` and ``--force``: where the results are written besides the screen, never
    replacing earlier ones unless forced."""
    parser.add_argument("--out", default=default, help=what)
    parser.add_argument("--force", action="store_true", help="replace earlier results in --out")
