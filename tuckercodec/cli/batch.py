"""The ``batch`` verb: encode many sequences the same way, each into ``OUTDIR/<name>.tkc``, in
parallel over an executor (:mod:`tuckercodec.system.parallel`: this process, ``--jobs N`` worker
processes, or a Dask cluster with ``--scheduler``).

Everything that can be checked is checked before any work: the output names (one per input,
from its file or folder name; two inputs giving the same name are a usage error) and the outputs
that exist (never replaced without ``--force``). Each input is then one task, encoded in
process by whoever runs it, exactly as ``encode`` would; the task sends back the file's bytes
and this process writes them (atomically), so a remote cluster needs to read the inputs (by the
same absolute paths) but not to write anywhere. A failing input is reported in one line, as the
command line reports any error, and the others go on; the exit code is 0 when every input was
written, else :data:`EXIT_SOME_FAILED`.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
import traceback
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, TextIO

from ..encoder import EncodeOptions, Encoder, EncodeReport
from ..errors import EXIT_OK
from ..files import SUFFIX
from ..io import format_of, load_sequence
from ..measures.distortion import KG_DEFINITION
from ..system.atomic import write_atomic
from ..system.parallel import open_executor
from .codec import encode_options
from .failures import describe_failure
from .inputs import read_options, sequence_source

#: The exit code when some inputs failed (each has its line on standard error) and the others
#: were written.
EXIT_SOME_FAILED = 7
_GLOB = frozenset("*?[")


@dataclass(frozen=True)
class Job:
    """One input's task: what to read and how to encode it (picklable, sent to a worker)."""

    source: str
    reading: dict[str, Any]  # the reading options of tuckercodec.io.load_sequence
    encoding: dict[str, Any]  # EncodeOptions.to_config(): plain data, for any worker


@dataclass(frozen=True)
class Encoded:
    """What a task sends back: the file's bytes, the encoder's report, the seconds it took."""

    data: bytes
    report: EncodeReport
    seconds: float


def encode_job(job: Job) -> Encoded:
    """Read and encode one input in this process (a worker's task)."""
    start = time.perf_counter()
    sequence = load_sequence(sequence_source(job.source), progress=False, **job.reading)
    result = Encoder(EncodeOptions.from_config(job.encoding)).encode_with_report(sequence)
    return Encoded(result.data, result.report, time.perf_counter() - start)


def output_name(source: str) -> str:
    """The name of an input's output, without the suffix: the file's or folder's name (the
    format's suffix dropped), for a glob the last folder before the pattern."""
    if source == "sample":
        return "sample"
    parts = [part for part in Path(os.path.abspath(source)).parts if part != os.sep]
    plain = [part for part in parts if not _GLOB & set(part)]
    if not plain:
        raise ValueError(f"cannot name the output of {source!r}: give a file or a folder")
    name = plain[-1]
    return Path(name).stem if format_of(Path(name)) is not None else name


@dataclass
class _Row:
    """One input in the summary: its output, and the outcome once known."""

    source: str
    output: Path
    encoded: Encoded | None = None
    error: str | None = None  # the one-line message (without "tuckercodec: ")

    @property
    def status(self) -> str:
        if self.encoded is not None:
            return "ok"
        return self.error if self.error is not None else "not run (interrupted)"


def run_batch(args: argparse.Namespace) -> int:
    """Encode every input into OUTDIR; see the module docstring."""
    rows = _plan(args.inputs, args.output)
    existing = [row.output for row in rows if row.output.exists()]
    if existing and not args.force:
        more = f" (and {len(existing) - 1} more)" if len(existing) > 1 else ""
        raise FileExistsError(
            f"{existing[0]} already exists{more} (pass --force to replace outputs)"
        )
    args.output.mkdir(parents=True, exist_ok=True)
    remote = args.scheduler is not None  # workers with another working folder
    options = read_options(args)
    if remote and "faces" in options:
        options["faces"] = os.path.abspath(options["faces"])
    encoding = encode_options(args, passes=False).to_config()
    jobs = [Job(_task_source(row.source, remote), options, encoding) for row in rows]
    workers = None if args.jobs is None else min(args.jobs, len(rows))  # no idle process
    display = _Display(len(rows))
    display.start("starting workers" if workers or args.scheduler else "in this process")
    started = False
    try:
        with open_executor(workers, args.scheduler) as executor:
            started = True
            display.start(f"{executor.workers} at a time")
            for completed in executor.as_completed(encode_job, jobs):
                row = rows[completed.index]
                if completed.error is None:
                    try:
                        write_atomic(row.output, completed.value.data, overwrite=args.force)
                        row.encoded = completed.value
                    except OSError as error:  # a full disk, a file made meanwhile
                        display.failed(row, error)
                else:
                    display.failed(row, completed.error)
                display.finished(row)
    finally:
        display.close()
        if started:  # else nothing ran: the error says why
            _print_summary(rows, args.output)
    return EXIT_OK if all(row.encoded is not None for row in rows) else EXIT_SOME_FAILED


def _plan(inputs: Sequence[str], folder: Path) -> list[_Row]:
    """One row per input with its output path; a usage error if two outputs coincide."""
    if folder.exists() and not folder.is_dir():
        raise ValueError(f"{folder}: -o names a folder for the outputs, and this is a file")
    rows: list[_Row] = []
    taken: dict[str, str] = {}
    for source in inputs:
        name = output_name(source)
        key = os.path.normcase(name)  # the same file where names ignore case
        if key in taken:
            raise ValueError(
                f"{taken[key]} and {source} would both be written to {folder / (name + SUFFIX)}: "
                "encode them in separate batches, or rename one"
            )
        taken[key] = source
        rows.append(_Row(source, folder / f"{name}{SUFFIX}"))
    return rows


def _task_source(source: str, remote: bool) -> str:
    """What a task reads: the input, absolute for a remote cluster, whose workers do not share
    this working folder ("sample" stays "sample": each worker has its own)."""
    return os.path.abspath(source) if remote and source != "sample" else source


class _Display:
    """Progress: on a terminal one live line on standard error; otherwise a line per finished
    input on standard output. Errors are one line each on standard error, as they happen."""

    def __init__(self, total: int, stream: TextIO | None = None) -> None:
        self.total = total
        self.stream = sys.stderr if stream is None else stream
        self.live = bool(getattr(self.stream, "isatty", lambda: False)())
        self.done = 0
        self.failures = 0
        self.started = time.perf_counter()
        self.where = ""

    def start(self, where: str) -> None:
        """Say where the work runs (or that the workers are starting)."""
        self.where = where
        self._draw()

    def failed(self, row: _Row, error: BaseException) -> None:
        failure = describe_failure(error)
        if failure is None:  # a bug, reported as encode would (a traceback), then the rest go on
            self._clear()
            traceback.print_exception(error, file=sys.stderr)
            message = f"internal error: {type(error).__name__}: {error}"
        else:
            kind, text, _ = failure
            where = "" if row.source in text else f"{row.source}: "
            message = f"{kind}{where}{text}"
        row.error = message
        self._clear()
        print(f"tuckercodec: {message}", file=sys.stderr, flush=True)

    def finished(self, row: _Row) -> None:
        self.done += 1
        self.failures += row.encoded is None
        if self.live:
            self._draw()
            return
        counter = f"[{self.done}/{self.total}]"
        if row.encoded is None:
            print(f"{counter} {row.source}: failed", flush=True)
            return
        report = row.encoded.report
        print(
            f"{counter} {row.source} -> {row.output}: {report.frames} frames, "
            f"{report.vertices} vertices, KG {report.kg:.5f}, {report.total_bytes} bytes, "
            f"{row.encoded.seconds:.2f} s",
            flush=True,
        )

    def close(self) -> None:
        self._clear()

    def _draw(self) -> None:
        if not self.live:
            return
        failed = f", {self.failures} failed" if self.failures else ""
        elapsed = time.perf_counter() - self.started
        self.stream.write(
            f"\r\x1b[Kbatch: {self.done}/{self.total} done{failed}, {self.where}, {elapsed:.0f} s"
        )
        self.stream.flush()

    def _clear(self) -> None:
        if self.live:
            self.stream.write("\r\x1b[K")
            self.stream.flush()


def _print_summary(rows: list[_Row], folder: Path) -> None:
    """The table of every input, then what the KG column means and the totals."""
    header = ["input", "frames", "vertices", "ranks", "KG", "bpfv", "bytes", "seconds", "status"]
    table = [header]
    for row in rows:
        if row.encoded is None:
            table.append([row.source, *["-"] * 7, row.status])
            continue
        report, seconds = row.encoded.report, row.encoded.seconds
        i, k = report.ranks
        table.append(
            [
                row.source,
                str(report.frames),
                str(report.vertices),
                f"({i}, 3, {k})",
                f"{report.kg:.5f}",
                f"{report.bpfv:.4f}",
                str(report.total_bytes),
                f"{seconds:.2f}",
                row.status,
            ]
        )
    widths = [max(len(line[column]) for line in table) for column in range(len(header) - 1)]
    for line in table:
        cells = [
            cell.ljust(width) if column == 0 else cell.rjust(width)
            for column, (cell, width) in enumerate(zip(line, widths, strict=False))
        ]
        print("  ".join([*cells, line[-1]]))
    written = sum(row.encoded is not None for row in rows)
    failed = sum(row.error is not None for row in rows)
    print(f"KG: {KG_DEFINITION}")
    print(
        f"{written} of {len(rows)} written to {folder}"
        + (f", {failed} failed" if failed else "")
        + (f", {len(rows) - written - failed} not run" if written + failed < len(rows) else "")
    )
