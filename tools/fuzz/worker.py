"""The fuzzing process itself: libFuzzer (atheris) calling one target's oracle.

Started by the driver (:mod:`.driver`) as ``python -m tools.fuzz --worker --target NAME``;
it fuzzes until libFuzzer stops, which exits the process.
"""

from __future__ import annotations

import contextlib
import hashlib
import os
import sys
import traceback
import warnings
from pathlib import Path

from .container import signature_of
from .targets import Target

# ------------------------------------------------------------------------------------------
# the worker (inside libFuzzer)


def _limit_address_space(memory_mb: int) -> None:
    """Cap the address space at what the process holds now plus ``memory_mb``: a huge
    allocation then fails (and is reported) even if the pages would never be touched, which
    libFuzzer's RSS limit cannot see."""
    from tools.common import MIB, proc_status_kib

    vm = proc_status_kib("VmSize")
    try:
        import resource
    except ImportError:
        return  # not Unix: the RSS limit alone
    if vm is None:
        return  # not Linux: the RSS limit alone
    limit = vm * 1024 + memory_mb * MIB
    with contextlib.suppress(OSError, ValueError):
        resource.setrlimit(resource.RLIMIT_AS, (limit, limit))


def quiet_check(target: Target, data: bytes) -> None:
    """The target's oracle with its outcome, warnings and exceptions ignored: for what it
    allocates or executes, judged elsewhere."""
    with warnings.catch_warnings(), contextlib.suppress(Exception):
        warnings.simplefilter("ignore")
        target.check(data)


def _traced_peak_mb(target: Target, data: bytes) -> float:
    """What one input allocates at its peak under tracemalloc (numpy's buffers included), MiB."""
    from tools.common import MIB, traced_peak

    return traced_peak(lambda: quiet_check(target, data)) / MIB


def run_worker(
    target: Target, crashes: Path, memory_mb: int, report_mb: int, libfuzzer_args: list[str]
) -> None:
    """Fuzz in this process until libFuzzer stops (it exits the process).

    Besides crashes, an input that itself allocates more than ``report_mb`` is saved
    (``bigmem-``): libFuzzer's own RSS limit only stops the run at ``memory_mb``. To stay cheap,
    an input is measured (under tracemalloc) only when the process's peak RSS reaches a new
    height, ``report_mb`` above the start and then each quarter of it.

    A target read through the isolated child (USD, Alembic) gets no address-space cap, which
    the child would inherit below what it sets itself: the child's own limits guard it
    (``TUCKERCODEC_READ_MEMORY_GIB``, 1 GiB here, and ``TUCKERCODEC_READ_TIMEOUT``, 30 s).
    """
    import atheris

    if "tuckercodec" in sys.modules:  # see the module's docstring
        raise RuntimeError("tuckercodec was imported before atheris could instrument it")
    with atheris.instrument_imports(include=["tuckercodec"]):
        import tuckercodec  # noqa: F401 - instrumented for coverage

    import numpy  # noqa: F401 - imported before the address-space cap

    for module in () if target.isolated else target.needs:  # the readers' libraries, before
        __import__(module)  # the cap too (the isolated child imports its own)

    from tools.common import lifetime_peak_rss_mib

    crashes.mkdir(parents=True, exist_ok=True)
    seen = {path.name.rsplit("-", 1)[0] for path in crashes.iterdir()}
    if target.isolated:
        os.environ.setdefault("TUCKERCODEC_READ_MEMORY_GIB", "1")
        os.environ.setdefault("TUCKERCODEC_READ_TIMEOUT", "30")
    else:
        _limit_address_space(memory_mb)
    memory_alarm = [lifetime_peak_rss_mib() + report_mb]

    def save(name: str, data: bytes, notes: str) -> None:
        path = crashes / f"{name}-{hashlib.sha1(data).hexdigest()[:12]}"
        path.write_bytes(data)
        path.with_suffix(".txt").write_text(notes)
        print(f"\n=== new crash {name}: saved to {path}\n{notes}", file=sys.stderr, flush=True)

    def test_one_input(data: bytes) -> None:
        failure = None
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # as the test suite does (pyproject: filterwarnings)
            try:
                target.check(data)
            except Exception as error:  # anything here is the finding
                failure = error
        peak = lifetime_peak_rss_mib()
        if peak > memory_alarm[0]:  # the high-water mark only rises: look at each new height once
            memory_alarm[0] = peak + report_mb / 4
            # libFuzzer's own tables grow the process by ~64 MiB steps over millions of runs
            # (replaying the corpus outside libFuzzer stays flat): blame the input only if it
            # allocates that much itself
            traced = _traced_peak_mb(target, data)
            if traced > report_mb:
                save(
                    f"bigmem-{int(traced)}MiB",
                    data,
                    f"this input alone allocates {traced:.0f} MiB (traced)\n",
                )
            else:
                print(
                    f"(peak RSS {peak:.0f} MiB: growth over the run; the input at hand allocates "
                    f"{traced:.1f} MiB)",
                    file=sys.stderr,
                    flush=True,
                )
        if failure is None:
            return
        name = f"crash-{signature_of(failure)}"
        if name not in seen:
            seen.add(name)
            save(name, data, "".join(traceback.format_exception(failure)))

    atheris.Setup([sys.argv[0], *libfuzzer_args], test_one_input, custom_mutator=target.mutate)
    atheris.Fuzz()
