"""A minimal progress bar on standard error, shown only when stderr is a terminal."""

from __future__ import annotations

import sys
import time
from collections.abc import Iterable, Iterator
from typing import TextIO, TypeVar

T = TypeVar("T")


def progress(
    items: Iterable[T],
    total: int,
    label: str,
    *,
    stream: TextIO | None = None,
    min_seconds: float = 0.5,
) -> Iterator[T]:
    """Yield ``items``, drawing a bar for ``total`` steps once the work has lasted ``min_seconds``.

    Nothing is drawn when the stream is not a terminal (pipes, CI logs, tests), so output that
    other programs read stays clean.
    """
    stream = sys.stderr if stream is None else stream
    show = bool(getattr(stream, "isatty", lambda: False)()) and total > 1
    start = time.monotonic()
    drawn = False
    for done, item in enumerate(items, start=1):
        yield item
        if show and (drawn or time.monotonic() - start >= min_seconds):
            width = 30
            filled = width * done // total
            stream.write(f"\r{label} [{'#' * filled}{'.' * (width - filled)}] {done}/{total}")
            stream.flush()
            drawn = True
    if drawn:
        stream.write("\n")
        stream.flush()
