"""What the tools share: where the data is, reading a sequence by name, timing, peak memory,
the machine, the command line, and writing results that refuse to overwrite without --force.

Like every tool, this imports only :mod:`tuckercodec` and :mod:`tuckercodec.internal`.
``tools.fuzz`` imports it only inside the functions that need it: its worker must import
tuckercodec for the first time under atheris' instrumentation.
"""

from __future__ import annotations

import gc
import os
import platform
import statistics
import sys
import time
import tracemalloc
from collections.abc import Callable, Iterable, Iterator
from contextlib import contextmanager, suppress
from pathlib import Path

import numpy as np

from tuckercodec import MeshSequence, load_sequence
from tuckercodec.internal import sample_path, write_atomic

REPO = Path(__file__).resolve().parents[1]
#: The real test sequences, beside the repository (never committed).
SHARED_DATA = REPO.parent / "shared" / "data"
#: The real sequences the benchmarks measure by default, in this order (absent ones skipped).
REAL_SEQUENCES = ("samba.npz", "chicken.npz", "horse-gallop", "cloth-vellum.npz")
#: The name that stands for the built-in sample (the cloth shipped inside the package).
SAMPLE = "sample"
MIB = 1 << 20


# ------------------------------------------------------------------------------------------
# sequences


def package_environment(folder: str | Path) -> dict[str, str]:
    """The environment of a child that runs the package in ``folder`` (first on its
    ``PYTHONPATH``). A revision extracted with ``git archive`` holds sources only, no compiled
    core, so it runs in pure Python, said explicitly (``TUCKERCODEC_NATIVE=0``): an editable
    install's import hook would otherwise hand it this checkout's core, whose functions are not
    its own. The working tree's package, run with ``folder`` the repository itself, keeps the
    setting."""
    environment = {**os.environ, "PYTHONPATH": str(folder)}
    if Path(folder).resolve() != REPO:
        environment["TUCKERCODEC_NATIVE"] = "0"
    return environment


def in_shared_data(names: Iterable[str]) -> tuple[list[Path], list[Path]]:
    """The paths of ``names`` in :data:`SHARED_DATA`: ``(present, absent)``, each in order."""
    paths = [SHARED_DATA / name for name in names]
    return [p for p in paths if p.exists()], [p for p in paths if not p.exists()]


def shared_sequences() -> list[str]:
    """Every sequence in :data:`SHARED_DATA`: its .npz files and its folders of OBJ files."""
    if not SHARED_DATA.is_dir():
        return []
    return [
        str(p)
        for p in sorted(SHARED_DATA.iterdir())
        if (p.suffix == ".npz" and p.is_file()) or (p.is_dir() and any(p.glob("*.obj")))
    ]


def load(source: str | Path) -> MeshSequence:
    """The sequence at ``source`` (an .npz, a folder of OBJ files...), or the built-in sample
    for ``"sample"``; no progress bar."""
    return load_sequence(sample_path() if str(source) == SAMPLE else source, progress=False)


def unique_name(name: str, taken: set[str]) -> str:
    """``name``, or ``name-2``, ``name-3``... so that two inputs never share result files; the
    name returned is added to ``taken``."""
    candidate, number = name, 1
    while candidate in taken:
        number += 1
        candidate = f"{name}-{number}"
    taken.add(candidate)
    return candidate


# ------------------------------------------------------------------------------------------
# time


def timed(function: Callable[[], object], repeat: int, warmup: int = 1) -> list[float]:
    """Wall times of ``repeat`` calls of ``function()``, after ``warmup`` untimed calls."""
    for _ in range(warmup):
        function()
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        function()
        times.append(time.perf_counter() - start)
    return times


def spread(times: list[float], scale: float = 1.0, digits: int = 3) -> str:
    """``median [min-max]`` of ``times`` multiplied by ``scale`` (the median alone for one)."""
    median = statistics.median(times) * scale
    if len(times) == 1:
        return f"{median:.{digits}f}"
    return f"{median:.{digits}f} [{min(times) * scale:.{digits}f}-{max(times) * scale:.{digits}f}]"


# ------------------------------------------------------------------------------------------
# memory: three measures, for three questions


def traced_peak(function: Callable[[], object]) -> int:
    """Bytes that Python and numpy allocate at the peak of one ``function()`` call, beyond what
    existed before (tracemalloc: C libraries' own allocations, zstd's, are invisible)."""
    tracemalloc.start()
    try:
        tracemalloc.reset_peak()
        before = tracemalloc.get_traced_memory()[0]
        result = function()
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    del result
    return peak - before


def proc_status_kib(field_name: str) -> int | None:
    """A field of Linux's /proc/self/status in KiB (VmRSS, VmHWM, VmSize...), None elsewhere."""
    try:
        with open("/proc/self/status", encoding="ascii") as handle:
            for line in handle:
                if line.startswith(field_name + ":"):
                    return int(line.split()[1])
    except OSError:
        return None
    return None


def _release_free_memory() -> None:
    """Hand freed heap back to the system, so that the next block's allocations show up as new
    resident memory instead of reusing pages an earlier block left resident."""
    gc.collect()
    import ctypes

    # not glibc: the figure may then be an underestimate
    with suppress(OSError, AttributeError):
        ctypes.CDLL("libc.so.6").malloc_trim(0)


@contextmanager
def resident_peak() -> Iterator[dict[str, int | None]]:
    """Measure the peak resident memory of the block above the resident memory at its start,
    in bytes, as ``result["peak"]``.

    Linux's high-water mark (VmHWM) is reset by writing 5 to /proc/self/clear_refs, so native
    allocations (Draco, SZ3, zstd) are counted too, which tracemalloc cannot see. Elsewhere the
    result is None.
    """
    result: dict[str, int | None] = {"peak": None}
    _release_free_memory()
    try:
        with open("/proc/self/clear_refs", "w", encoding="ascii") as handle:
            handle.write("5")
        start = proc_status_kib("VmRSS")
    except OSError:
        start = None
    try:
        yield result
    finally:
        high = proc_status_kib("VmHWM")
        if start is not None and high is not None:
            result["peak"] = max(0, high - start) * 1024


def lifetime_peak_rss_mib() -> float:
    """The process's high-water resident memory since it started, MiB (0 without getrusage)."""
    try:
        import resource
    except ImportError:
        return 0.0
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return peak / 1024 if sys.platform != "darwin" else peak / MIB  # KiB on Linux, bytes on macOS


# ------------------------------------------------------------------------------------------
# what ran where


def machine() -> str:
    """CPU model, cores, OS, Python and numpy versions."""
    model = platform.processor() or platform.machine()
    with suppress(OSError), open("/proc/cpuinfo", encoding="utf-8") as handle:
        for line in handle:
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    return (
        f"{model}, {os.cpu_count()} cores, {platform.system()} {platform.release()}, "
        f"Python {platform.python_version()}, numpy {np.__version__}"
    )


def command(module: str, argv: list[str] | None) -> str:
    """The command line that runs ``module`` with ``argv`` (None: this process's arguments)."""
    arguments = sys.argv[1:] if argv is None else argv
    return f"python -m {module} {' '.join(arguments)}".rstrip()


# ------------------------------------------------------------------------------------------
# results


def write_text(path: Path, text: str, force: bool) -> None:
    """Write ``text`` (UTF-8) to ``path`` atomically; an existing file is replaced only with
    ``force`` (FileExistsError otherwise)."""
    write_atomic(path, text.encode("utf-8"), overwrite=force)
