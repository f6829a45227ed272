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

#: What the worker prints when a module of the package is first imported after the instrumented
#: block (the driver counts these lines): libFuzzer cannot see that module's coverage.
LATE_IMPORT = "=== uninstrumented module imported late:"
#: How many of the corpus' inputs are run inside the instrumented block, to import what the
#: target's checks import lazily (the package imports its modules when first used).
WARM_UP_INPUTS = 64


def package_modules() -> list[str]:
    return [
        name for name in sys.modules if name == "tuckercodec" or name.startswith("tuckercodec.")
    ]


def _import_tree(name: str) -> None:
    """Import a module, and every module below it if it is a package. A module whose optional
    library is missing (a reader's) is left out: its door cannot run here either."""
    import importlib
    import pkgutil

    try:
        module = importlib.import_module(name)
    except ImportError as error:
        print(f"(not instrumented: {name}: {error})", file=sys.stderr)
        return
    for info in pkgutil.iter_modules(getattr(module, "__path__", None) or []):
        _import_tree(f"{name}.{info.name}")


def corpus_of(libfuzzer_args: list[str]) -> Path | None:
    """The corpus folder among libFuzzer's arguments (the one that is not a flag)."""
    folders = [Path(a) for a in libfuzzer_args if not a.startswith("-") and Path(a).is_dir()]
    return folders[0] if folders else None


def instrument_target(target: Target, corpus: Path | None) -> set[str]:
    """Import, under atheris' instrumentation, the modules the target exercises: its
    ``modules`` (each package with every module below it), then whatever its check imports on
    the first inputs of its corpus. ``import tuckercodec`` alone loads only the package's
    ``__init__`` and ``_version`` (every other module is imported when first used): a worker
    that instrumented that alone fuzzed blind, its corpus never growing past one input.
    Returns the names of the package's modules so instrumented."""
    import atheris

    if "tuckercodec" in sys.modules:  # see the package's docstring
        raise RuntimeError("tuckercodec was imported before atheris could instrument it")
    with atheris.instrument_imports(include=["tuckercodec"]):
        import tuckercodec  # noqa: F401 - instrumented for coverage

        for name in target.modules:
            _import_tree(name)
        count = 4 if target.isolated else WARM_UP_INPUTS  # a process per input
        inputs = sorted(corpus.iterdir())[:count] if corpus else []
        for path in inputs:
            if path.is_file():
                quiet_check(target, path.read_bytes())
    names = set(package_modules())
    print(f"(instrumented {len(names)} modules of tuckercodec)", file=sys.stderr, flush=True)
    return names


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

    instrumented = instrument_target(target, corpus_of(libfuzzer_args))

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
    modules_seen = [len(sys.modules)]
    late: set[str] = set()

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
        if len(sys.modules) != modules_seen[0]:  # cheap: only when something was imported
            modules_seen[0] = len(sys.modules)
            for name in sorted(set(package_modules()) - instrumented - late):
                late.add(name)
                print(f"{LATE_IMPORT} {name}", file=sys.stderr, flush=True)
        if failure is None:
            return
        name = f"crash-{signature_of(failure)}"
        if name not in seen:
            seen.add(name)
            save(name, data, "".join(traceback.format_exception(failure)))

    atheris.Setup([sys.argv[0], *libfuzzer_args], test_one_input, custom_mutator=target.mutate)
    atheris.Fuzz()
