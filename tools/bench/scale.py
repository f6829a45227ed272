"""Benchmark of the segmented encoder's scale targets: large encodes, one frame from disk,
1 or 2 workers.

It measures a sequence larger than memory, one frame read from disk, two workers against one,
and what forced segments cost on the real sequences; it prints Markdown for BENCHMARKS.md.

Every encode runs ``python -m tuckercodec encode`` in a child process, timed from start to
exit, while this process reads /proc every ``--interval`` seconds (50 ms) for the resident
memory of the child and of all its descendants (Dask's workers): the tables give the peak of
their sum (shared pages counted in each process, so an overestimate), the peak of its
anonymous part alone (resident memory less the pages of mapped files, such as a memory-mapped
input, which the kernel can drop at any time), and the main process's own peak. A tree whose
anonymous memory passes ``--kill-above`` (half the machine's memory) is killed and reported as
such, so that an encoder that does not stream cannot starve the machine. Each figure is the
median of ``--repeat`` runs (``--big-repeat`` for the large sequence), with [min-max].

1. **Encode** the generated sequence (``tools.generate.sequence``, by default a 200,000-vertex,
   2,000-frame body, 4.8 GB as float32 ``.npy``, made once and kept in ``--workdir``): wall
   time, MB/s of float32 input, peak memory, size, bpfv, the KG error the encoder reports
   (``info --json``) and the KG error measured here, independently, by streaming the ``.npy``
   (memory-mapped, block by block) against ``Decoder(path).positions(range)``, Karni-Gotsman
   (per-frame centroid) as in tuckercodec.measures.distortion. Targets: peak at most 1.5 GB, at
   least 25 MB/s, decoded KG at most the target.
2. **One frame from disk**, in a fresh process each run: resident memory after ``import
   tuckercodec``, the time to open ``Decoder(path)``, then to decode frame 0, the middle frame,
   the last frame and the frame after the middle one (in the middle one's segment), and the
   peak resident memory beyond the import's; then, opened again in the same process, what is
   left once one-time costs (lazy imports) are paid. Targets: open + one frame at most 20 ms,
   at most 64 MB beyond the import. The file is in the page cache (it was just written).
3. **--jobs 1 against --jobs 2**, and against the encode in process (BLAS on every core), on
   the same input: wall and CPU times (the tree's), their ratios, and whether the two workers'
   files are byte-identical. Target: at least 1.6 times faster.
4. **The real sequences** (chicken, samba, horse gallop, from ../shared/data; absent ones are
   skipped and named): at each ``--real-targets`` KG, the size with ``--segment-frames 100``
   against without (target: at most 1.3 times), the decoded KG of each, and whether the file
   written without forcing segments is byte-identical to the one the encoder of
   ``--baseline-ref`` writes (the last commit before segmented files changed the format, extracted
   with ``git archive``, never checked out).

The children run the working tree's package, or with ``--encoder-ref REF`` the package of a
git commit (extracted with ``git archive``), to measure an earlier encoder on the same input:
today's reads no ``.npy``, so give it ``--input-format npz`` (an uncompressed .npz made from the
same generator; the KG check still streams the .npy).

Linux only (/proc, wait4). The figures depend on the machine and on anything else it runs.

    python -m tools.bench scale                              # everything, 200,000 x 2,000
    python -m tools.bench scale --quick                      # 20,000 x 200, one run each
    python -m tools.bench scale --only encode frame --vertices 20000 --frames 200 \
        --input-format npz --encoder-ref ff92b12              # today's encoder, for comparison
"""

from __future__ import annotations

import argparse
import filecmp
import json
import math
import os
import shlex
import signal
import statistics
import subprocess
import sys
import tarfile
import tempfile
import time
from collections.abc import Callable, Iterator
from contextlib import ExitStack, contextmanager, suppress
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from tools import common
from tools.bench import arguments
from tools.bench.arguments import UsageError
from tools.generate import sequence as make_sequence
from tuckercodec import Decoder, kg_error, load_sequence
from tuckercodec.internal import default_max_memory

DEFAULT_WORKDIR = Path("~/.cache/tuckercodec-bench").expanduser()
#: The last commit before segmented files changed the format: "today's" encoder.
BASELINE_REF = "ff92b12ee4b1334dfa52e58ea87afa0f811c5d7d"
REAL = ("chicken.npz", "samba.npz", "horse-gallop")
SECTIONS = ("encode", "frame", "jobs", "real")
MB, MIB, GB = 1e6, 1 << 20, 1e9

TARGET_PEAK_BYTES = 1.5 * GB
TARGET_MB_S = 25.0
TARGET_FRAME_S = 0.020
TARGET_FRAME_MEMORY = 64 * MB
TARGET_JOBS_SPEEDUP = 1.6
TARGET_SEGMENT_RATIO = 1.3


# ------------------------------------------------------------------------------------------
# running an encoder and watching its memory


@dataclass
class Run:
    """One child process: how long it ran, how it ended, and its peak memory in bytes."""

    command: list[str]
    seconds: float
    returncode: int
    stdout: str
    stderr: str
    tree_rss: int = 0  # peak of the summed resident memory of the child and its descendants
    tree_anon: int = 0  # the same, anonymous memory only (no mapped file pages)
    main_rss: int = 0  # the child's own peak, polled
    largest_hwm: int = 0  # the kernel's high-water mark of the largest single process (wait4)
    killed_above: int | None = None  # set when it was stopped for passing this many bytes
    cpu_seconds: float = 0.0  # user + system time of the child and the descendants it reaped

    @property
    def ok(self) -> bool:
        return self.returncode == 0

    def failure(self) -> str:
        """The last lines the child printed to stderr, for a report."""
        if self.killed_above is not None:
            return (
                f"stopped: its anonymous memory passed {self.killed_above / GB:.1f} GB "
                f"after {self.seconds:.0f} s (--kill-above)"
            )
        lines = [line for line in self.stderr.strip().splitlines() if line.strip()]
        return f"exit {self.returncode}: " + (" / ".join(lines[-3:]) or "(nothing on stderr)")


def _status(pid: int) -> tuple[int, int]:
    """(VmRSS, RssAnon) of process ``pid`` in bytes, (0, 0) once it has gone."""
    rss = anon = 0
    try:
        with open(f"/proc/{pid}/status", encoding="ascii") as handle:
            for line in handle:
                if line.startswith("VmRSS:"):
                    rss = int(line.split()[1]) * 1024
                elif line.startswith("RssAnon:"):
                    anon = int(line.split()[1]) * 1024
    except (OSError, ValueError):
        pass
    return rss, anon


def _descendants(pid: int) -> list[int]:
    """The process ids below ``pid``, from /proc's children lists (every thread's)."""
    found, queue = [], [pid]
    while queue:
        parent = queue.pop()
        try:
            tasks = os.listdir(f"/proc/{parent}/task")
        except OSError:
            continue
        for task in tasks:
            try:
                with open(f"/proc/{parent}/task/{task}/children", encoding="ascii") as handle:
                    children = [int(c) for c in handle.read().split()]
            except (OSError, ValueError):  # the thread ended meanwhile
                continue
            found += children
            queue += children
    return found


def run_measured(
    command: list[str],
    *,
    cwd: Path,
    env: dict[str, str] | None = None,
    interval: float = 0.05,
    limit: int | None = None,
) -> Run:
    """Run ``command``, polling the memory of its process tree every ``interval`` seconds; the
    tree is killed if its anonymous memory passes ``limit`` bytes, before it takes the
    machine's memory from everything else."""
    with tempfile.TemporaryFile() as out, tempfile.TemporaryFile() as err:
        start = time.perf_counter()
        process = subprocess.Popen(command, cwd=cwd, env=env, stdout=out, stderr=err)
        tree_rss = tree_anon = main_rss = 0
        killed = None
        while True:
            pid, status, usage = os.wait4(process.pid, os.WNOHANG)
            if pid:
                break
            main, main_anon = _status(process.pid)
            children = _descendants(process.pid)
            others = [_status(child) for child in children]
            main_rss = max(main_rss, main)
            tree_rss = max(tree_rss, main + sum(r for r, _ in others))
            tree_anon = max(tree_anon, main_anon + sum(a for _, a in others))
            if limit is not None and tree_anon > limit and killed is None:
                killed = limit
                for child in [*children, process.pid]:  # only the processes this run started
                    with suppress(ProcessLookupError):
                        os.kill(child, signal.SIGKILL)
            time.sleep(interval)
        seconds = time.perf_counter() - start
        process.returncode = os.waitstatus_to_exitcode(status)  # reaped here, not by Popen
        out.seek(0)
        err.seek(0)
        return Run(
            command,
            seconds,
            process.returncode,
            out.read().decode("utf-8", "replace"),
            err.read().decode("utf-8", "replace"),
            tree_rss,
            tree_anon,
            main_rss,
            usage.ru_maxrss * 1024,
            killed,
            usage.ru_utime + usage.ru_stime,
        )


@dataclass(frozen=True)
class Package:
    """The tuckercodec a child process runs: the working tree's (``folder`` None, run from
    ``workdir``) or one extracted from git into ``folder`` (first on its PYTHONPATH)."""

    workdir: Path
    folder: Path | None = None

    @property
    def cwd(self) -> Path:
        return self.folder or self.workdir

    @property
    def env(self) -> dict[str, str] | None:
        return None if self.folder is None else common.package_environment(self.folder)


def encode_command(
    source: Path, output: Path, target: float, faces: Path | None, options: list[str]
) -> list[str]:
    """``python -m tuckercodec encode`` of ``source`` to ``output`` at KG ``target``."""
    command = [sys.executable, "-m", "tuckercodec", "encode", str(source), "-o", str(output)]
    command += ["--kg", f"{target:g}", "--force"]
    if faces is not None:
        command += ["--faces", str(faces)]
    return command + options


def file_info(path: Path, package: Package) -> dict[str, Any]:
    """``tuckercodec info PATH --json`` of a written file."""
    command = [sys.executable, "-m", "tuckercodec", "info", str(path), "--json"]
    done = subprocess.run(
        command, cwd=package.cwd, env=package.env, capture_output=True, text=True, check=False
    )
    if done.returncode != 0:
        return {"error": done.stderr.strip()}
    info: dict[str, Any] = json.loads(done.stdout)
    return info


def streamed_kg(original: Path, compressed: Path, block_values: int = 1 << 23) -> float:
    """The KG error (Karni-Gotsman, per-frame centroid) of the file ``compressed`` against the
    ``.npy`` ``original``, block of frames by block: neither is ever whole in memory."""
    positions = np.load(original, mmap_mode="r")
    frames, vertices, _ = positions.shape
    decoder = Decoder(compressed)
    step = max(1, block_values // (3 * vertices))
    error = spread = 0.0
    for start in range(0, frames, step):
        stop = min(frames, start + step)
        a = np.asarray(positions[start:stop], dtype=np.float64)
        b = decoder.positions(range(start, stop))
        error += float(np.sum((a - b) ** 2))
        spread += float(np.sum((a - a.mean(axis=1, keepdims=True)) ** 2))
    return 100.0 * math.sqrt(error / spread)


# ------------------------------------------------------------------------------------------
# the input


@dataclass
class Input:
    """The generated sequence on disk: the .npy (the reference), its faces, and what to feed
    the encoder (the .npy, or an .npz made from the same generator)."""

    npy: Path
    faces: Path
    source: Path
    frames: int
    vertices: int
    made_seconds: float | None = None  # None: found in the work folder

    @property
    def float32_bytes(self) -> int:
        return self.frames * self.vertices * 12

    def describe(self) -> str:
        return f"{self.source.name}: {self.frames} frames x {self.vertices} vertices"


def prepare_input(args: argparse.Namespace) -> Input:
    """The sequence in ``--workdir``, made now unless an earlier run left it there."""
    args.workdir.mkdir(parents=True, exist_ok=True)
    stem = f"{args.kind}-{args.vertices}x{args.frames}-seed{args.seed}"
    npy = args.workdir / f"{stem}.npy"
    faces = make_sequence.faces_path(npy)
    made = None
    if not (npy.exists() and faces.exists()):
        print(f"making {npy} (kept for later runs)...", file=sys.stderr, flush=True)
        start = time.perf_counter()
        sequence = make_sequence.make(args.kind, args.vertices, args.frames, args.seed)
        make_sequence.write(npy, sequence, force=True)
        made = time.perf_counter() - start
    shape = np.load(npy, mmap_mode="r").shape
    if shape != (args.frames, args.vertices, 3):
        raise SystemExit(f"{npy} holds {shape}, not what its name says: remove it")
    source = npy
    if args.input_format == "npz":
        source = npy.with_suffix(".npz")
        if not source.exists():
            sequence = make_sequence.make(args.kind, args.vertices, args.frames, args.seed)
            make_sequence.write(source, sequence, npz=True, force=True)
    return Input(npy, faces, source, args.frames, args.vertices, made)


# ------------------------------------------------------------------------------------------
# the four measures


@dataclass
class EncodeResult:
    label: str
    runs: list[Run] = field(default_factory=list)
    output: Path | None = None
    info: dict[str, Any] = field(default_factory=dict)
    measured_kg: float | None = None
    check_seconds: float | None = None

    @property
    def failed(self) -> Run | None:
        return next((run for run in self.runs if not run.ok), None)


def encode_runs(
    data: Input,
    args: argparse.Namespace,
    package: Package,
    label: str,
    options: list[str],
    runs: int,
) -> EncodeResult:
    """``runs`` encodes of the input with ``options``; stops at the first failure."""
    result = EncodeResult(label)
    name = "".join(c if c.isalnum() else "-" for c in label).strip("-")
    result.output = args.workdir / f"{data.npy.stem}.kg{args.kg:g}.{name}.tkc"
    faces = data.faces if data.source.suffix == ".npy" else None
    command = encode_command(data.source, result.output, args.kg, faces, options)
    for number in range(runs):
        print(f"  {label}: run {number + 1}/{runs}...", file=sys.stderr, flush=True)
        run = run_measured(
            command,
            cwd=package.cwd,
            env=package.env,
            interval=args.interval,
            limit=args.kill_above,
        )
        result.runs.append(run)
        if not run.ok:
            return result
    result.info = file_info(result.output, package)
    return result


def check_kg(result: EncodeResult, data: Input) -> None:
    """Measure the decoded KG error of ``result``'s file here, streaming."""
    if result.failed is None and result.output is not None:
        start = time.perf_counter()
        result.measured_kg = streamed_kg(data.npy, result.output)
        result.check_seconds = time.perf_counter() - start


_FRAME_CHILD = r"""
import gc, json, sys, time
def status(name):
    with open("/proc/self/status") as handle:
        for line in handle:
            if line.startswith(name + ":"):
                return int(line.split()[1]) * 1024
start = time.perf_counter()
import tuckercodec
imported = time.perf_counter() - start
gc.collect()
after_import = status("VmRSS")
with open("/proc/self/clear_refs", "w") as handle:  # the high-water mark starts again here
    handle.write("5")
start = time.perf_counter()
decoder = tuckercodec.Decoder(sys.argv[1])
opened = time.perf_counter() - start
times = []
for frame in json.loads(sys.argv[2]):
    start = time.perf_counter()
    decoder.frame(frame)
    times.append(time.perf_counter() - start)
peak = status("VmHWM")
# again in the same process: what is left once one-time costs (lazy imports) are paid
start = time.perf_counter()
again = tuckercodec.Decoder(sys.argv[1])
reopened = time.perf_counter() - start
start = time.perf_counter()
again.frame(json.loads(sys.argv[2])[1])
print(json.dumps({"import": imported, "after_import": after_import, "open": opened,
                  "frames": times, "peak": peak, "reopen": reopened,
                  "reframe": time.perf_counter() - start}))
"""


@dataclass
class FrameResult:
    frames: list[int]
    samples: list[dict[str, Any]] = field(default_factory=list)
    error: str | None = None


def frame_runs(path: Path, frame_count: int, runs: int, package: Package) -> FrameResult:
    """Decode a few frames from ``path`` in a fresh process, ``runs`` times."""
    middle = frame_count // 2
    frames = [0, middle, frame_count - 1, min(middle + 1, frame_count - 1)]
    result = FrameResult(frames)
    for _ in range(runs):
        command = [sys.executable, "-c", _FRAME_CHILD, str(path), json.dumps(frames)]
        done = subprocess.run(
            command, cwd=package.cwd, env=package.env, capture_output=True, text=True, check=False
        )
        if done.returncode != 0:
            lines = done.stderr.strip().splitlines()
            result.error = f"exit {done.returncode}: {lines[-1] if lines else ''}"
            return result
        result.samples.append(json.loads(done.stdout))
    return result


@dataclass
class RealResult:
    name: str
    target: float
    single: Path
    segmented: dict[str, Path] = field(default_factory=dict)
    baseline: Path | None = None
    kg: dict[str, float] = field(default_factory=dict)
    errors: list[str] = field(default_factory=list)


@contextmanager
def git_package(ref: str) -> Iterator[Path | None]:
    """A folder holding the package as it was at ``ref`` (from ``git archive``; the working
    tree and the index are never touched), or None if git cannot give it."""
    with tempfile.TemporaryDirectory(prefix="tuckercodec-baseline-") as folder:
        archive = Path(folder) / "package.tar"
        done = subprocess.run(
            ["git", "-C", str(common.REPO), "archive", "-o", str(archive), ref, "tuckercodec"],
            capture_output=True,
            text=True,
            check=False,
        )
        if done.returncode != 0:
            print(f"no baseline: git archive {ref}: {done.stderr.strip()}", file=sys.stderr)
            yield None
            return
        with tarfile.open(archive) as tar:
            tar.extractall(folder, filter="data")
        yield Path(folder)


def real_runs(
    args: argparse.Namespace, package: Package, baseline: Path | None
) -> list[RealResult]:
    """Single-segment, forced-segment and baseline files of each real sequence present."""
    present, _ = common.in_shared_data(REAL)
    out = args.workdir / "real"
    out.mkdir(exist_ok=True)
    results = []
    for path in present:
        name = path.name.removesuffix(".npz")
        sequence = load_sequence(path, progress=False)
        for target in args.real_targets:
            result = RealResult(name, target, out / f"{name}.kg{target:g}.single.tkc")
            variants: list[tuple[str, Path, list[str], Package]] = [
                ("single", result.single, [], package)
            ]
            for basis in args.bases:
                label = f"seg{args.segment_frames}" + (f"-{basis}" if basis else "")
                options = ["--segment-frames", str(args.segment_frames)]
                options += ["--basis", basis] if basis else []
                result.segmented[label] = out / f"{name}.kg{target:g}.{label}.tkc"
                variants.append((label, result.segmented[label], options, package))
            if baseline is not None:
                result.baseline = out / f"{name}.kg{target:g}.baseline.tkc"
                variants.append(("baseline", result.baseline, [], Package(args.workdir, baseline)))
            for label, output, options, runner in variants:
                command = encode_command(path.resolve(), output, target, None, options)
                done = subprocess.run(
                    command, cwd=runner.cwd, env=runner.env, capture_output=True, check=False
                )
                if done.returncode != 0:
                    lines = done.stderr.decode("utf-8", "replace").strip().splitlines()
                    result.errors.append(
                        f"{label}: exit {done.returncode}: {' / '.join(lines[-2:])}"
                    )
                    output.unlink(missing_ok=True)
                    continue
                if label != "baseline":
                    result.kg[label] = kg_error(sequence, Decoder(output).positions())
            results.append(result)
    return results


# ------------------------------------------------------------------------------------------
# the tables


def _mib(value: float) -> str:
    return f"{value / MIB:.0f}"


def _spread(values: list[float], format_: Callable[[float], str]) -> str:
    """``median [min-max]`` (the median alone for one value)."""
    median = format_(statistics.median(values))
    if len(values) == 1:
        return median
    return f"{median} [{format_(min(values))}-{format_(max(values))}]"


def _verdict(met: bool) -> str:
    return "met" if met else "NOT met"


def _ranks(info: dict[str, object]) -> str:
    ranks = info.get("ranks")
    segments = info.get("segments")
    text = str(tuple(ranks)) if isinstance(ranks, list) and len(ranks) == 2 else "?"
    if isinstance(segments, list):
        text += f", {len(segments)} segments"
    elif isinstance(segments, int):
        text += f", {segments} segments"
    return text


def encode_table(results: list[EncodeResult], data: Input, target: float) -> list[str]:
    """The encode table: one row per configuration."""
    lines = [
        f"Encode of {data.describe()} ({data.float32_bytes / GB:.2f} GB as float32), "
        f"target KG {target:g}:",
        "",
        "| encode | runs | wall s | MB/s | peak RSS, tree (MiB) | peak anonymous, tree (MiB) "
        "| peak RSS, main (MiB) | bytes | bpfv | ranks | KG (encoder) | KG (measured) |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    verdicts = []
    for result in results:
        failed = result.failed
        if failed is not None:
            lines.append(f"| {result.label} | failed: {failed.failure()} |" + " |" * 10)
            continue
        runs = result.runs
        seconds = [run.seconds for run in runs]
        size = int(result.info.get("total_bytes") or 0)
        bpfv = 8 * size / (data.frames * data.vertices)
        encoder_kg = result.info.get("kg")
        measured = result.measured_kg
        lines.append(
            f"| {result.label} | {len(runs)} | {_spread(seconds, lambda s: f'{s:.1f}')} | "
            f"{data.float32_bytes / MB / statistics.median(seconds):.1f} | "
            f"{_spread([r.tree_rss for r in runs], _mib)} | "
            f"{_spread([r.tree_anon for r in runs], _mib)} | "
            f"{_spread([r.main_rss for r in runs], _mib)} | {size} | {bpfv:.4f} | "
            f"{_ranks(result.info)} | "
            f"{encoder_kg if not isinstance(encoder_kg, float) else f'{encoder_kg:.5f}'} | "
            f"{'-' if measured is None else f'{measured:.5f}'} |"
        )
        peak = statistics.median(run.tree_rss for run in runs)
        speed = data.float32_bytes / MB / statistics.median(seconds)
        verdicts.append(
            f"{result.label}: peak at most {TARGET_PEAK_BYTES / GB:g} GB: "
            f"{_verdict(peak <= TARGET_PEAK_BYTES)} ({peak / GB:.2f} GB); at least "
            f"{TARGET_MB_S:g} MB/s: {_verdict(speed >= TARGET_MB_S)} ({speed:.1f}); decoded KG "
            f"at most {target:g}: "
            + ("not measured" if measured is None else _verdict(measured <= target))
        )
    return [*lines, "", *verdicts]


def frame_table(result: FrameResult, path: Path) -> list[str]:
    """The one-frame table (milliseconds, MiB)."""
    head = f"One frame of {path.name} decoded from disk, a fresh process per run:"
    if result.error is not None or not result.samples:
        return [head, "", f"failed: {result.error}"]
    samples = result.samples

    def ms(values: list[float]) -> str:
        return _spread([v * 1000 for v in values], lambda v: f"{v:.2f}")

    opened = [float(s["open"]) for s in samples]
    per_frame = [[float(s["frames"][i]) for s in samples] for i in range(len(result.frames))]
    after = [float(s["after_import"]) for s in samples]
    growth = [float(s["peak"]) - float(s["after_import"]) for s in samples]
    first = [o + f for o, f in zip(opened, per_frame[0], strict=True)]
    labels = ["frame 0", f"frame {result.frames[1]}", f"frame {result.frames[2]}"]
    labels.append(f"then frame {result.frames[3]}")
    lines = [
        head,
        "",
        "| runs | RSS after import (MiB) | open (ms) | "
        + " | ".join(f"{label} (ms)" for label in labels)
        + " | open + frame 0 (ms) | peak RSS beyond the import (MiB) |",
        "|---|---|---|" + "---|" * len(labels) + "---|---|",
        f"| {len(samples)} | {_spread(after, _mib)} | {ms(opened)} | "
        + " | ".join(ms(times) for times in per_frame)
        + f" | {ms(first)} | {_spread(growth, lambda v: f'{v / MIB:.1f}')} |",
        "",
        "Opened again in the same process (one-time costs such as lazy imports paid): open "
        f"{ms([float(s['reopen']) for s in samples])} ms, frame {result.frames[1]} "
        f"{ms([float(s['reframe']) for s in samples])} ms.",
    ]
    worst = max(o + max(f) for o, f in zip(opened, zip(*per_frame, strict=True), strict=True))
    peak = statistics.median(growth)
    lines += [
        "",
        f"open + any one frame at most {TARGET_FRAME_S * 1000:g} ms: "
        f"{_verdict(statistics.median(first) <= TARGET_FRAME_S)} (median of open + frame 0; "
        f"worst open + slowest frame of any run {worst * 1000:.1f} ms); at most "
        f"{TARGET_FRAME_MEMORY / MB:g} MB beyond the import: "
        f"{_verdict(peak <= TARGET_FRAME_MEMORY)} ({peak / MB:.1f} MB)",
    ]
    return lines


def jobs_table(results: list[EncodeResult], data: Input) -> list[str]:
    """In process (BLAS on every core) against --jobs 1 and --jobs 2 (the first result is
    --jobs 1, the second --jobs 2, any third in process)."""
    lines = [
        f"In process against --jobs 1 and --jobs 2, {data.describe()}:",
        "",
        "| jobs | runs | wall s | CPU s (tree) | MB/s | peak RSS, tree (MiB) |",
        "|---|---|---|---|---|---|",
    ]
    for result in results:
        if result.failed is not None:
            lines.append(f"| {result.label} | failed: {result.failed.failure()} | | | | |")
            continue
        seconds = [run.seconds for run in result.runs]
        lines.append(
            f"| {result.label} | {len(seconds)} | {_spread(seconds, lambda s: f'{s:.1f}')} | "
            f"{_spread([r.cpu_seconds for r in result.runs], lambda s: f'{s:.1f}')} | "
            f"{data.float32_bytes / MB / statistics.median(seconds):.1f} | "
            f"{_spread([r.tree_rss for r in result.runs], _mib)} |"
        )
    outputs = [r.output for r in results if r.failed is None and r.output is not None]
    if len(outputs) == len(results) >= 2:
        median = [statistics.median(r.seconds for r in result.runs) for result in results]
        same = filecmp.cmp(outputs[0], outputs[1], shallow=False)
        lines += [
            "",
            f"speed-up of --jobs 2 over --jobs 1 {median[0] / median[1]:.2f}, at least "
            f"{TARGET_JOBS_SPEEDUP:g}: {_verdict(median[0] / median[1] >= TARGET_JOBS_SPEEDUP)}; "
            f"byte-identical files: {'yes' if same else 'NO'}",
        ]
        if len(results) > 2:
            lines.append(f"--jobs 2 against in process: {median[2] / median[1]:.2f} times as fast")
    return lines


def real_table(results: list[RealResult], absent: list[Path], segment_frames: int) -> list[str]:
    """Forced segments against one, on the real sequences."""
    labels = sorted({label for r in results for label in r.segmented})
    lines = [
        f"The real sequences, one segment against forced segments of {segment_frames} frames:",
        "",
        "| sequence | KG target | single (bytes) | "
        + " | ".join(f"{label} (bytes) | ratio" for label in labels)
        + " | KG single | "
        + " | ".join(f"KG {label}" for label in labels)
        + " | single = baseline's bytes |",
        "|---|---|---|" + "---|---|" * len(labels) + "---|" + "---|" * len(labels) + "---|",
    ]
    worst = 0.0
    for r in results:
        single = r.single.stat().st_size if r.single.exists() else None
        cells = [r.name, f"{r.target:g}", str(single or "failed")]
        for label in labels:
            path = r.segmented.get(label)
            size = path.stat().st_size if path is not None and path.exists() else None
            ratio = size / single if size and single else None
            if "own" not in label:  # the target is the default (shared) basis's; "own" compares
                worst = max(worst, ratio or 0.0)
            cells += [str(size or "failed"), "-" if ratio is None else f"{ratio:.3f}"]
        kgs = [r.kg.get(label) for label in ("single", *labels)]
        cells += ["-" if kg is None else f"{kg:.5f}" for kg in kgs]
        if r.baseline is None or not r.baseline.exists() or single is None:
            cells.append("not compared")
        else:
            cells.append("yes" if filecmp.cmp(r.single, r.baseline, shallow=False) else "NO")
        lines.append("| " + " | ".join(cells) + " |")
    lines.append("")
    if absent:
        lines.append("skipped, not in ../shared/data: " + ", ".join(p.name for p in absent))
    errors = [f"{r.name} KG {r.target:g}: {e}" for r in results for e in r.errors]
    lines += [f"failed: {error}" for error in errors]
    if results and labels:
        verdict = "not measured"
        if worst > 0:
            verdict = f"{_verdict(worst <= TARGET_SEGMENT_RATIO)} (worst {worst:.3f})"
        lines.append(
            f"forced segments (shared basis, the default) at most {TARGET_SEGMENT_RATIO:g} times "
            "the single-segment size: " + verdict
        )
    return lines


# ------------------------------------------------------------------------------------------
# the command line


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The scale suite's options."""
    parser.add_argument("--kind", choices=make_sequence.KINDS, default="body")
    parser.add_argument("--vertices", type=int, help="K (default 200000; --quick 20000)")
    parser.add_argument("--frames", type=int, help="F (default 2000; --quick 200)")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--kg", type=float, default=0.1, help="target of the large encodes")
    parser.add_argument(
        "--repeat", type=arguments.positive_int, help="runs per measure (default 3; --quick 1)"
    )
    parser.add_argument(
        "--big-repeat",
        type=arguments.positive_int,
        help="runs of each large encode (default --repeat)",
    )
    parser.add_argument("--quick", action="store_true", help="small sizes, one run: a smoke run")
    parser.add_argument("--only", nargs="+", choices=SECTIONS, default=list(SECTIONS))
    parser.add_argument("--input-format", choices=("npy", "npz"), default="npy")
    parser.add_argument(
        "--encode-options",
        default="",
        help="more options for the large encode, one string given with '=' "
        "(--encode-options='--max-memory 1GB --jobs 2')",
    )
    parser.add_argument("--real-targets", type=float, nargs="+", default=[0.1, 1.0])
    parser.add_argument("--segment-frames", type=int, default=100)
    parser.add_argument(
        "--bases",
        nargs="+",
        default=[""],
        help="--basis values to try with forced segments ('' for the encoder's default)",
    )
    parser.add_argument(
        "--baseline-ref", default=BASELINE_REF, help="today's encoder, for the real sequences"
    )
    parser.add_argument(
        "--encoder-ref",
        help="measure the encoder of this git ref instead of the working tree's",
    )
    parser.add_argument("--workdir", type=Path, default=DEFAULT_WORKDIR)
    parser.add_argument("--interval", type=float, default=0.05, help="memory polling, seconds")
    parser.add_argument(
        "--kill-above",
        type=float,
        default=default_max_memory() / GB,
        help="stop an encode whose anonymous memory passes this many GB (default: half of "
        "this machine's memory), so that an encoder that does not stream cannot starve the "
        "machine",
    )
    arguments.output(parser, "also write the Markdown to this file")


def settle(args: argparse.Namespace) -> None:
    """The defaults that depend on other options, and the checks of what was given."""
    args.vertices = args.vertices or (20_000 if args.quick else 200_000)
    args.frames = args.frames or (200 if args.quick else 2_000)
    args.repeat = args.repeat or (1 if args.quick else 3)
    args.big_repeat = args.big_repeat or args.repeat
    args.kill_above = int(args.kill_above * GB)
    args.workdir = args.workdir.expanduser().resolve()  # children run from other folders
    if sys.platform != "linux":
        raise UsageError("this benchmark reads /proc: Linux only")
    args.out = None if args.out is None else Path(args.out)
    if args.out is not None and args.out.exists() and not args.force:
        raise UsageError(f"{args.out} exists; give --force to replace it")


def run(args: argparse.Namespace) -> int:
    """Run the chosen measures and print their tables; returns the exit status."""
    settle(args)
    with ExitStack() as stack:
        package = Package(args.workdir)
        if args.encoder_ref:
            folder = stack.enter_context(git_package(args.encoder_ref))
            if folder is None:
                return 1
            package = Package(args.workdir, folder)
        report = "\n".join(measure(args, package)).rstrip() + "\n"
    print(report, end="")
    if args.out is not None:
        common.write_text(args.out, report, args.force)
    return 0


def measure(args: argparse.Namespace, package: Package) -> list[str]:
    """Every measure ``--only`` names, as lines of Markdown."""
    text = [f"machine: {common.machine()}", f"command: {args.command}"]
    if package.folder is not None:
        text.append(f"encoder: tuckercodec of {args.encoder_ref} (git archive)")
    data = prepare_input(args) if {"encode", "frame", "jobs"} & set(args.only) else None
    if data is not None:
        made = "found in the work folder"
        if data.made_seconds is not None:
            made = f"made now in {data.made_seconds:.1f} s"
        text.append(f"input: {data.source} ({made}; faces {data.faces.name})")
    text.append("")
    if data is not None and {"encode", "frame"} & set(args.only):
        options = shlex.split(args.encode_options)
        label = " ".join(["encode", *options])
        result = encode_runs(data, args, package, label, options, args.big_repeat)
        check_kg(result, data)
        if "encode" in args.only:
            text += [*encode_table([result], data, args.kg), ""]
        if "frame" in args.only:
            if result.failed is None and result.output is not None:
                frames = frame_runs(result.output, data.frames, args.repeat, package)
                text += [*frame_table(frames, result.output), ""]
            else:
                text += ["One frame from disk: not measured, the encode failed", ""]
    if data is not None and "jobs" in args.only:
        one = encode_runs(data, args, package, "--jobs 1", ["--jobs", "1"], args.big_repeat)
        two = encode_runs(data, args, package, "--jobs 2", ["--jobs", "2"], args.big_repeat)
        alone = encode_runs(data, args, package, "in process", [], args.big_repeat)
        text += [*jobs_table([one, two, alone], data), ""]
    if "real" in args.only:
        _, absent = common.in_shared_data(REAL)
        with git_package(args.baseline_ref) as baseline:
            results = real_runs(args, package, baseline)
        text += real_table(results, absent, args.segment_frames)
        text.append(f"baseline: the encoder of {args.baseline_ref[:12]}")
    return text
