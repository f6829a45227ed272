"""The options several suites share, each declared once: the sequences measured, how many timed
runs, and where results are written. A suite adds the ones it takes, with its own default."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable, Iterable
from pathlib import Path

from tools import common


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


def sequences_and_folder(args: argparse.Namespace, marker: str) -> tuple[list[str], Path] | None:
    """The sequences a suite measures (``--sequences``, or every one of ../shared/data) and its
    output folder, made; ``None``, the reason printed, when there is no sequence or the folder
    holds earlier results (its ``marker`` file) and ``--force`` is not given: refused before
    the run, not after it."""
    paths = args.sequences or common.shared_sequences()
    if not paths:
        print(f"no sequences given and none found in {common.SHARED_DATA}", file=sys.stderr)
        return None
    out = Path(args.out)
    if (out / marker).exists() and not args.force:
        print(f"{out} holds earlier results; give --force to replace them", file=sys.stderr)
        return None
    out.mkdir(parents=True, exist_ok=True)
    return paths, out


def available_coders(
    names: str, known: Iterable[str], missing: Callable[[str], str | None]
) -> tuple[list[str], dict[str, str]]:
    """The coders of ``--coders`` (comma-separated) that can run here, and those skipped with
    why (their library is ``missing``; the reason is printed too). An unknown name is a
    UsageError."""
    wanted = [name for name in names.split(",") if name]
    unknown = set(wanted) - set(known)
    if unknown:
        raise UsageError(f"unknown coders: {', '.join(sorted(unknown))}")
    skipped = {name: why for name in wanted if (why := missing(name))}
    for name, why in skipped.items():
        print(f"{name}: skipped, {why}", file=sys.stderr)
    return [name for name in wanted if name not in skipped], skipped
