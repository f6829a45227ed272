"""The driver: runs the worker until the time or run budget is spent, restarts it after a hang
or an out-of-memory, sums the inputs tried; merges a run's new coverage into the committed
corpus; replays saved inputs; writes the seeds."""

from __future__ import annotations

import argparse
import contextlib
import hashlib
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path
from typing import Any

from . import __doc__ as PACKAGE_DOC
from .container import signature_of
from .paths import CORPUS, CRASHES, NOT_INPUTS, REGRESSIONS, ROOT, saved_inputs
from .targets import SCRATCH_VARIABLE, TARGETS, Target, target_named
from .worker import LATE_IMPORT, quiet_check, run_worker


def seed_inputs(target: Target) -> list[Path]:
    """The committed seeds of a target: its corpus, and the vectors it takes."""
    paths: list[Path] = []
    for pattern in target.extra_seeds:
        paths += sorted(ROOT.glob(pattern))
    return paths + saved_inputs(CORPUS / target.name)


def write_seeds(target: Target, folder: Path | None = None) -> list[Path]:
    """Write the target's seeds (its ``seeds()``) into its corpus folder, or ``folder``."""
    folder = folder or CORPUS / target.name
    folder.mkdir(parents=True, exist_ok=True)
    written = []
    for name, data in target.seeds().items():
        (folder / name).write_bytes(data)
        written.append(folder / name)
    return written


def _stat(text: str, name: str) -> int:
    found = re.findall(rf"stat::{name}:\s+(\d+)", text)
    return int(found[-1]) if found else 0


_PROGRESS = re.compile(r"^#(\d+)\s+(\w+)\s+cov: (\d+) ft: (\d+) corp: (\d+)/", re.MULTILINE)


def coverage_lines(text: str) -> list[dict[str, int | str]]:
    """libFuzzer's progress lines that carry coverage (INITED, NEW, pulse, REDUCE, DONE...):
    ``cov`` is the number of distinct edges (atheris: bytecode branches) reached, ``ft`` the
    number of features (edges with hit counts, comparisons), ``corpus`` the inputs kept."""
    return [
        {"event": event, "inputs": int(n), "cov": int(c), "ft": int(f), "corpus": int(k)}
        for n, event, c, f, k in _PROGRESS.findall(text)
    ]


def judge_coverage(
    outputs: list[str], late: list[str], expect_growth: bool
) -> tuple[dict[str, Any], list[str]]:
    """The coverage at the start (libFuzzer's INITED line of the first worker: the seeds) and at
    the end (its last line of the last worker), and what makes the run a failure: no coverage at
    all, a corpus that never grew past its seeds, a module of the package imported after the
    instrumentation (its coverage unseen)."""
    lines = [line for text in outputs for line in coverage_lines(text)]
    inited = [line for line in lines if line["event"] == "INITED"]
    start = inited[0] if inited else (lines[0] if lines else None)
    end = lines[-1] if lines else None
    added = sum(_stat(text, "new_units_added") for text in outputs)
    coverage: dict[str, Any] = {
        "start": None if start is None else {k: start[k] for k in ("cov", "ft", "corpus")},
        "end": None if end is None else {k: end[k] for k in ("cov", "ft", "corpus")},
        "new_units_added": added,
    }
    failures = []
    if start is None or not int(start["cov"]):
        failures.append(
            "libFuzzer reported no coverage (no 'cov:' on its INITED line): the worker "
            "instruments nothing the target runs, the fuzzer is blind"
        )
    elif expect_growth and (not added or end is None or int(end["ft"]) <= int(start["ft"])):
        failures.append(
            f"the corpus did not grow past its seeds (cov {start['cov']}, ft {start['ft']}, "
            f"corpus {start['corpus']} at the start; {added} inputs added): the fuzzer "
            "found nothing new to reach, which a run of this length should"
        )
    if late:
        failures.append(
            "modules of tuckercodec were imported after the instrumented block, their coverage "
            f"unseen by libFuzzer: {', '.join(late)} (add them to the target's modules)"
        )
    return coverage, failures


def _worker_command(args: argparse.Namespace, crashes: Path, libfuzzer: list[str]) -> list[str]:
    command = [sys.executable, "-m", "tools.fuzz", "--worker", "--target", args.target]
    command += ["--crashes", str(crashes), "--memory-mb", str(args.memory_mb)]
    return [*command, "--report-mb", str(args.report_mb), "--", *libfuzzer]


def _run_worker_once(
    command: list[str], env: dict[str, str], limit: float | None, verbose: bool
) -> str:
    """One worker's run; its libFuzzer output (stderr)."""
    try:
        child = subprocess.run(
            command,
            env=env,
            cwd=ROOT,
            capture_output=True,
            text=True,
            check=False,
            timeout=limit,
        )
        output = child.stderr
    except subprocess.TimeoutExpired as expired:
        raw = expired.stderr or ""
        output = raw.decode(errors="replace") if isinstance(raw, bytes) else raw
        print("the worker overran its time and was stopped", file=sys.stderr)
    if verbose:
        sys.stderr.write(output)
    else:
        for line in output.splitlines():
            if (
                any(mark in line for mark in ("=== new crash", "ERROR: libFuzzer", LATE_IMPORT))
                or line.startswith("Done ")
                or re.match(r"#\d+\s+(INITED|DONE)", line)
            ):
                print(line, file=sys.stderr)
    return output


def fuzz(args: argparse.Namespace) -> dict[str, Any]:
    """Run the worker until the time or run budget is spent; restart it after a hang or an
    out-of-memory. Returns the summary."""
    target = target_named(args.target)
    # absolute: the worker runs from the repository's root (python -m tools.fuzz)
    work = Path(args.work).resolve() if args.work else Path(tempfile.mkdtemp(prefix="tkc-fuzz-"))
    work.mkdir(parents=True, exist_ok=True)
    if target.name == "all":  # made from the other doors' seeds, not committed
        for name, data in target.seeds().items():
            (work / f"seed-{name}").write_bytes(data)
    for path in seed_inputs(target):
        shutil.copy(path, work / f"seed-{path.name}")
    crashes = Path(args.crashes).resolve() / target.name
    crashes.mkdir(parents=True, exist_ok=True)
    before = set(crashes.iterdir())
    started = time.monotonic()
    runs = restarts = peak_rss = 0
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1"}
    env["MKL_NUM_THREADS"] = "1"
    memory = Path("/dev/shm")  # the readers' inputs are written there, once per input
    scratch = tempfile.mkdtemp(
        prefix="tkc-fuzz-", dir=memory if memory.is_dir() and os.access(memory, os.W_OK) else None
    )
    env[SCRATCH_VARIABLE] = scratch
    timeout = max(args.timeout, 120) if target.isolated else args.timeout
    seed = args.seed
    outputs: list[str] = []
    while True:
        left = args.seconds - (time.monotonic() - started) if args.seconds else None
        if (left is not None and left < 2) or (args.runs and runs >= args.runs):
            break
        libfuzzer = [
            f"-timeout={timeout}",
            f"-rss_limit_mb={args.memory_mb}",
            f"-max_len={args.max_len or target.max_len}",
            f"-artifact_prefix={crashes}{os.sep}",
            "-print_final_stats=1",
            f"-seed={seed}",
            "-reload=0",
        ]
        if left is not None:
            libfuzzer.append(f"-max_total_time={int(left)}")
        if args.runs:
            libfuzzer.append(f"-runs={args.runs - runs}")
        output = _run_worker_once(
            [*_worker_command(args, crashes, libfuzzer), str(work)],
            env,
            None if left is None else left + timeout + 60,
            args.verbose,
        )
        outputs.append(output)
        executed = _stat(output, "number_of_executed_units")
        if not executed:  # no final stats (killed): the last progress line
            progress = re.findall(r"^#(\d+)\s", output, flags=re.MULTILINE)
            executed = int(progress[-1]) if progress else 0
        runs += executed
        peak_rss = max(peak_rss, _stat(output, "peak_rss_mb"))
        if left is not None and "Done " in output and "ERROR" not in output:
            break  # finished its time normally
        if args.runs and runs >= args.runs:
            break
        restarts += 1
        seed += 1
        if restarts > 50:
            print("more than 50 restarts: stopping", file=sys.stderr)
            break
    shutil.rmtree(scratch, ignore_errors=True)
    new = sorted(str(p) for p in set(crashes.iterdir()) - before if p.suffix not in NOT_INPUTS)
    late = sorted(
        {
            line.split(LATE_IMPORT, 1)[1].strip()
            for t in outputs
            for line in t.splitlines()
            if LATE_IMPORT in line
        }
    )
    coverage, failures = judge_coverage(outputs, late, not args.no_growth_ok)
    summary = {
        "target": target.name,
        "inputs_tried": runs,
        "seconds": round(time.monotonic() - started, 1),
        "restarts": restarts,
        "peak_rss_mb": peak_rss,
        "coverage": coverage,
        "failures": failures,
        "new_crashes": new,
        "work_corpus": str(work),
        "work_corpus_files": sum(1 for _ in work.iterdir()),
    }
    if args.merge:
        summary["corpus_after_merge"] = merge_corpus(target, work, args.corpus_kb)
    if not args.work:  # a temporary scratch corpus: nothing to keep once merged
        shutil.rmtree(work, ignore_errors=True)
        summary["work_corpus"] = None
    return summary


def _arcs(target: Target, data: bytes) -> set[tuple[str, int, int]]:
    """The line-to-line transitions one input executes inside tuckercodec (a coverage
    signature, as coverage.py's branch mode counts them)."""
    import tuckercodec

    package = str(Path(tuckercodec.__file__).resolve().parent)
    arcs: set[tuple[str, int, int]] = set()

    def tracer(frame: Any, event: str, arg: Any) -> Any:
        if not frame.f_code.co_filename.startswith(package):
            return None
        last = [-frame.f_code.co_firstlineno]  # entry into the function

        def local(frame: Any, event: str, arg: Any) -> Any:
            if event == "line":
                arcs.add((frame.f_code.co_filename, last[0], frame.f_lineno))
                last[0] = frame.f_lineno
            return local

        return local

    previous = sys.gettrace()
    sys.settrace(tracer)
    try:
        quiet_check(target, data)  # a crash still has coverage; it is reported elsewhere
    finally:
        sys.settrace(previous)
    return arcs


def line_coverage(target: Target, work: Path) -> dict[str, int]:
    """Python's own count, independent of atheris: the line transitions inside tuckercodec
    (as coverage.py's branch mode counts them) and the lines that the target's seeds execute,
    and that the seeds and a run's scratch corpus ``work`` execute together."""
    if target.name == "all":  # its seeds are made, not committed
        with tempfile.TemporaryDirectory(prefix="tkc-fuzz-seeds-") as folder:
            return _line_coverage(target, write_seeds(target, Path(folder)), work)
    return _line_coverage(target, seed_inputs(target), work)


def _line_coverage(target: Target, seeds: list[Path], work: Path) -> dict[str, int]:
    known = {hashlib.sha1(p.read_bytes()).hexdigest() for p in seeds}
    start: set[tuple[str, int, int]] = set()
    for path in seeds:
        start |= _arcs(target, path.read_bytes())
    end = set(start)
    found = [p for p in saved_inputs(work) if hashlib.sha1(p.read_bytes()).hexdigest() not in known]
    for path in found:
        end |= _arcs(target, path.read_bytes())

    def lines(arcs: set[tuple[str, int, int]]) -> int:
        return len({(name, line) for name, _, line in arcs})

    return {
        "seeds": len(seeds),
        "inputs": len(found),
        "arcs_start": len(start),
        "arcs_end": len(end),
        "lines_start": lines(start),
        "lines_end": lines(end),
    }


def merge_corpus(target: Target, work: Path, budget_kb: int) -> dict[str, int]:
    """Add to the target's corpus the inputs of ``work`` that execute a line transition no
    seed and no input added before executes: smallest inputs first, until the corpus reaches
    ``budget_kb``. (libFuzzer's own -merge re-executes its binary, which an atheris script is
    not, so the merge is done here on Python line coverage.)"""
    corpus = CORPUS / target.name
    corpus.mkdir(parents=True, exist_ok=True)
    covered: set[tuple[str, int, int]] = set()
    for path in seed_inputs(target):
        covered |= _arcs(target, path.read_bytes())
    size = sum(p.stat().st_size for p in saved_inputs(corpus))
    known = {hashlib.sha1(p.read_bytes()).hexdigest() for p in seed_inputs(target)}
    added = 0
    for path in sorted(saved_inputs(work), key=lambda p: (p.stat().st_size, p.name)):
        data = path.read_bytes()
        digest = hashlib.sha1(data).hexdigest()
        if digest in known or size + len(data) > budget_kb * 1024:
            continue
        new = _arcs(target, data) - covered
        if new:
            covered |= new
            (corpus / f"cov-{digest[:16]}").write_bytes(data)
            size += len(data)
            added += 1
    files = saved_inputs(corpus)
    return {"added": added, "files": len(files), "bytes": sum(p.stat().st_size for p in files)}


def replay(target: Target, paths: list[Path]) -> int:
    """Check saved inputs outside libFuzzer; print one line each; the number that fail."""
    failures = 0
    for path in paths:
        started = time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            try:
                outcome = target.check(path.read_bytes())
            except Exception as error:  # reported, not raised
                outcome = f"CRASH {signature_of(error)}: {error!r}"
                failures += 1
        print(f"{path}: {outcome} ({time.perf_counter() - started:.3f} s)")
    return failures


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="python -m tools.fuzz",
        description=(PACKAGE_DOC or "").split("\n\n")[0],
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    add = parser.add_argument
    add("--target", default="decoder", help=f"the door to fuzz: {', '.join(TARGETS)}, all")
    add("--list", action="store_true", help="list the targets")
    add("--seconds", type=float, default=0, help="stop after this long (default: 60 unless --runs)")
    add("--runs", type=int, default=0, help="stop after this many inputs")
    add("--timeout", type=int, default=10, help="seconds one input may take (a hang beyond)")
    add("--memory-mb", type=int, default=2048, help="memory one process may use")
    add("--report-mb", type=int, default=256, help="save an input that allocates more than this")
    add("--max-len", type=int, default=0, help="largest input libFuzzer makes (default: target's)")
    add("--seed", type=int, default=1, help="libFuzzer's random seed")
    add("--work", help="scratch corpus folder (default: a new temporary folder)")
    add("--crashes", default=str(CRASHES), help="where crashing inputs go (a folder per target)")
    add("--merge", action="store_true", help="fold new coverage into the target's corpus")
    add("--merge-from", type=Path, help="only merge this scratch corpus into the corpus")
    add(
        "--line-coverage",
        type=Path,
        help="count the Python lines and line transitions the seeds reach, and the seeds with "
        "this scratch corpus",
    )
    add("--corpus-kb", type=int, default=32, help="size budget of the target's corpus")
    add(
        "--no-growth-ok",
        action="store_true",
        help="do not fail a run whose corpus does not grow past its seeds (a replay-like run)",
    )
    add("--json", help="also write the summary to this file")
    add("--verbose", action="store_true", help="show libFuzzer's whole output")
    add(
        "--replay",
        nargs="*",
        type=Path,
        help="check these inputs (default: the target's corpus, regressions and crashes)",
    )
    add(
        "--js-replay",
        nargs="*",
        type=Path,
        help="decode these .tkc inputs (files or folders; default: the decoders' committed "
        "inputs and the vectors) with the JavaScript decoder in node and the Python one; fail on "
        "a crash of node or a disagreement on accepting a file",
    )
    add("--js-mutations", type=int, default=0, help="with --js-replay: also this many mutations")
    add(
        "--differential",
        type=int,
        metavar="N",
        help="decode the vectors, the decoders' committed inputs and N mutations of them with "
        "the compiled core and in pure Python; fail unless both agree on every one",
    )
    add("--make-seeds", action="store_true", help="write the target's seeds into its corpus")
    add("--worker", action="store_true", help=argparse.SUPPRESS)
    return parser


def _js_replay(args: argparse.Namespace) -> int:
    from .javascript import js_replay

    return _report(js_replay(args.js_replay, args.js_mutations, args.seed), args.json)


def _differential(args: argparse.Namespace) -> int:
    from .differential import compare

    return _report(compare(args.differential, args.seed), args.json)


def _report(summary: dict[str, Any], json_path: str | None) -> int:
    """Print a check's summary (and write it to ``json_path``); exit 1 if it lists failures."""
    print(json.dumps(summary, indent=2))
    if json_path:
        Path(json_path).write_text(json.dumps(summary, indent=2) + "\n")
    for failure in summary["failures"]:
        print(f"FAILED: {failure}", file=sys.stderr)
    return 1 if summary["failures"] else 0


def main(argv: list[str] | None = None) -> int:
    parser = _parser()
    args, rest = parser.parse_known_args(argv)
    if args.list:
        for target in TARGETS.values():
            cost = " (a process per input)" if target.isolated else ""
            print(f"{target.name:12} {target.door}{cost}")
        return 0
    target = target_named(args.target)
    if args.worker:
        libfuzzer = [a for a in rest if a != "--"]
        run_worker(target, Path(args.crashes), args.memory_mb, args.report_mb, libfuzzer)
        return 0
    if args.make_seeds:
        for path in write_seeds(target):
            print(f"{path}: {path.stat().st_size} bytes")
        return 0
    if args.line_coverage:
        print(json.dumps(line_coverage(target, args.line_coverage)))
        return 0
    if args.merge_from:
        print(json.dumps(merge_corpus(target, args.merge_from, args.corpus_kb)))
        return 0
    if args.js_replay is not None:
        return _js_replay(args)
    if args.differential is not None:
        return _differential(args)
    if args.replay is not None:
        folders = [root / target.name for root in (CORPUS, REGRESSIONS, CRASHES)]
        return 1 if replay(target, args.replay or saved_inputs(*folders)) else 0
    if rest:
        parser.error(f"unknown arguments {rest}")
    if not args.seconds and not args.runs:
        args.seconds = 60
    summary = fuzz(args)
    print(json.dumps(summary, indent=2))
    if args.json:
        with contextlib.suppress(OSError):
            Path(args.json).write_text(json.dumps(summary, indent=2) + "\n")
    for failure in summary["failures"]:
        print(f"FAILED: {failure}", file=sys.stderr)
    return 1 if summary["new_crashes"] or summary["failures"] else 0
