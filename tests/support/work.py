"""Work counted in lines of Python, not seconds: a test that a cost does not grow with some
size holds on any machine, however slow or busy (wall-clock limits failed on a loaded one)."""

from __future__ import annotations

import sys
from collections.abc import Callable, Iterable
from types import FrameType
from typing import Any


class OverBudget(AssertionError):
    """The function ran more lines than the budget allowed (stopped there)."""


def lines_run(function: Callable[[], object], files: Iterable[str], budget: int) -> int:
    """How many lines of the source ``files`` (their ``__file__``) ``function()`` runs;
    :class:`OverBudget` as soon as it passes ``budget``, so a quadratic loop stops early."""
    sources = set(files)
    lines = 0

    def in_source(frame: FrameType, event: str, arg: object) -> Any:
        nonlocal lines
        if event == "line":
            lines += 1
            if lines > budget:
                raise OverBudget(f"more than {budget} lines")
        return in_source

    def calls(frame: FrameType, event: str, arg: object) -> Any:
        return in_source if frame.f_code.co_filename in sources else None

    previous = sys.gettrace()
    sys.settrace(calls)
    try:
        function()
    finally:
        sys.settrace(previous)
    return lines
