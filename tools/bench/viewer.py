"""Benchmark of the viewer page (``tuckercodec view``) in headless Chromium: opening, each
frame's reconstruction, and playback at the file's rate, all measured by the page itself.

Each sequence is encoded at the target KG error into a temporary folder (never into the
repository), served by ``python -m tuckercodec view FILE.tkc`` (the command a user runs, on a
free port of 127.0.0.1) and opened in Chromium with the browser tests' driver
(tests/support/browser.py: the page measured is the one those tests check, driven the same way):

- open: ``tkcViewer.info.openMs``, the page's time from the file fetched to frame 0 drawn
  (openTkc, the scene, framing the camera, the first render), over ``--loads`` page loads in
  one browser (the first is the coldest); its parts are the medians of ``info.openParts``;
- frame: ``stats().frameMs`` after stepping once through every frame (``setFrame``): the
  reconstruction alone (``file.frameFloat32``), the first frame of each segment included;
  ``page`` is all the page's work for a frame (``stats().updateMs``: reconstruction, normals,
  the original's positions and colours with ``--reference``);
- frame alone: every frame reconstructed again, three passes, with nothing drawn meanwhile
  (``decodedPositions(t, out)``, the decoder's binary64 frame into one buffer): the decoder's
  own time, apart from the renderer that shares the machine's cores while the page plays;
- both frame columns also count the frames over the 2 ms target;
- playback: ``play()`` for ``--play-seconds`` from frame 0; the frames shown and dropped (a
  frame the clock passed without it being shown) the page counts.

Prints Markdown ready to paste into BENCHMARKS.md, with the machine, Chromium's version and the
command. Chromium coarsens ``performance.now()`` to 0.1 ms on a page that is not cross-origin
isolated, so a frame's time is a multiple of about 0.1 ms.

    python -m tools.bench viewer                          # samba (../shared/data), the sample
    python -m tools.bench viewer sample --loads 3 --play-seconds 2 --reference
"""

from __future__ import annotations

import argparse
import contextlib
import os
import select
import signal
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

from tests.support.browser import Browser, BrowserError, find_chromium
from tools import common
from tools.bench import arguments
from tools.bench.arguments import UsageError
from tuckercodec import encode

DEFAULT_SEQUENCES = ("samba.npz", common.SAMPLE)
#: Seconds the server may take to check the file and print its URL.
SERVE_SECONDS = 120.0


@dataclass(frozen=True)
class Result:
    """One sequence's measurements (milliseconds unless said)."""

    name: str
    vertices: int
    frames: int
    size: int
    open_ms: list[float]
    open_parts: dict[str, float]
    frame_ms: list[float]
    update_ms: list[float]
    alone_ms: list[float]
    rate: float | None
    seconds: float
    shown: int
    dropped: int
    renderer: str


@contextlib.contextmanager
def served(path: Path, reference: str | None) -> Iterator[str]:
    """``python -m tuckercodec view path`` running; yields the URL it prints. Stopped with
    Ctrl-C (SIGINT) as a user stops it, killed if it does not stop."""
    command = [sys.executable, "-m", "tuckercodec", "view", str(path)]
    if reference is not None:
        command += ["--reference", reference]
    process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    assert process.stdout is not None and process.stderr is not None
    try:
        yield _printed_url(process)
    finally:
        process.send_signal(signal.SIGINT)
        try:
            process.wait(timeout=10)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait()
        process.stdout.close()
        process.stderr.close()


def _printed_url(process: subprocess.Popen[bytes]) -> str:
    assert process.stdout is not None and process.stderr is not None
    deadline = time.monotonic() + SERVE_SECONDS
    seen = b""
    while time.monotonic() < deadline:
        ready, _, _ = select.select([process.stdout], [], [], 0.2)
        if ready:
            chunk = os.read(process.stdout.fileno(), 65536)
            seen += chunk
            for line in seen.decode("utf-8", "replace").splitlines():
                if line.startswith("http://127.0.0.1:") and "?file=" in line:
                    return line.strip()
            if not chunk:
                break
        elif process.poll() is not None:
            break
    error = process.stderr.read().decode("utf-8", "replace") if process.poll() is not None else ""
    raise RuntimeError(f"tuckercodec view printed no URL:\n{seen.decode()}\n{error}")


#: Steps through every frame in the page; the reconstruction times and the page's per frame.
STEP_ALL = """(async () => {
  const v = window.tkcViewer; await v.ready;
  const before = v.stats().frameMs.length;
  for (let t = 0; t < v.info.frames; t++) await v.setFrame(t);
  const s = v.stats();
  return {frameMs: s.frameMs.slice(before), updateMs: s.updateMs.slice(before)};
})()"""

#: Every frame reconstructed again, three passes, with nothing drawn meanwhile: the decoder's
#: own time per frame (decodedPositions is file.frame(t), binary64, into one buffer), apart from
#: the renderer, which shares this machine's two cores with the page while it plays.
RECONSTRUCT_ONLY = """(async () => {
  const v = window.tkcViewer; await v.ready; v.pause();
  const times = [];
  const out = new Float64Array(3 * v.info.vertices);
  for (let pass = 0; pass < 3; pass++) {
    for (let t = 0; t < v.info.frames; t++) {
      const started = performance.now();
      v.decodedPositions(t, out);
      times.push(performance.now() - started);
    }
  }
  return times;
})()"""

#: Plays from frame 0 for SECONDS; the frames shown and dropped meanwhile.
PLAY = """(async () => {
  const v = window.tkcViewer; await v.ready; await v.setFrame(0);
  const before = v.stats(); v.play();
  await new Promise((resolve) => setTimeout(resolve, SECONDS * 1000));
  v.pause(); const after = v.stats();
  return {shown: after.played - before.played, dropped: after.dropped - before.dropped};
})()"""


def measure(
    browser: Browser, url: str, name: str, size: int, loads: int, play_seconds: float
) -> Result:
    """Open the page ``loads`` times, then step through every frame and play."""
    opens: list[float] = []
    parts: dict[str, list[float]] = {}
    page = None
    for _ in range(loads):
        if page is not None:
            page.close()
        page = browser.new_page(url, timeout=120)
        info = page.evaluate("window.tkcViewer.ready.then(() => window.tkcViewer.info)", 120)
        opens.append(float(info["openMs"]))
        for part, value in (info.get("openParts") or {}).items():
            parts.setdefault(part, []).append(float(value))
    assert page is not None
    steps = page.evaluate(STEP_ALL, timeout=300)
    alone = page.evaluate(RECONSTRUCT_ONLY, timeout=300)
    played = page.evaluate(PLAY.replace("SECONDS", repr(play_seconds)), play_seconds + 60)
    renderer = page.evaluate("document.getElementById('renderer').textContent")
    problems = page.problems()
    page.close()
    if problems:
        raise BrowserError(f"the page reported errors: {problems}")
    return Result(
        name=name,
        vertices=int(info["vertices"]),
        frames=int(info["frames"]),
        size=size,
        open_ms=opens,
        open_parts={part: statistics.median(values) for part, values in parts.items()},
        frame_ms=[float(x) for x in steps["frameMs"]],
        update_ms=[float(x) for x in steps["updateMs"]],
        alone_ms=[float(x) for x in alone],
        rate=info["frameRate"],
        seconds=play_seconds,
        shown=int(played["shown"]),
        dropped=int(played["dropped"]),
        renderer=str(renderer),
    )


def table(results: list[Result], target_kg: float) -> str:
    """The results as Markdown."""
    lines = [
        f"| sequence (KG {target_kg}) | K | F | .tkc bytes | open ms: median [min-max] (loads) "
        "| open parts ms: decode / scene / framing / first frame "
        "| frame ms: median / p90 / max (> 2) "
        "| page per frame ms: median / max | frame alone ms: median / p90 / max (> 2) "
        "| playback: fps, s, shown / dropped |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in results:
        parts = " / ".join(
            f"{r.open_parts[key]:.1f}" if key in r.open_parts else "-"
            for key in ("decodeMs", "sceneMs", "framingMs", "firstFrameMs")
        )
        rate = f"{r.rate:g}" if r.rate else "none (page: 24)"
        frame = r.frame_ms
        lines.append(
            f"| {r.name} | {r.vertices} | {r.frames} | {r.size} "
            f"| {common.spread(r.open_ms, digits=1)} ({len(r.open_ms)}) | {parts} "
            f"| {_spread3(frame)} "
            f"| {statistics.median(r.update_ms):.2f} / {max(r.update_ms):.2f} "
            f"| {_spread3(r.alone_ms)} "
            f"| {rate}, {r.seconds:g}, {r.shown} / {r.dropped} |"
        )
    return "\n".join(lines)


#: The target bound on one frame's reconstruction, in milliseconds.
FRAME_TARGET_MS = 2.0


def _spread3(values: list[float]) -> str:
    over = sum(value > FRAME_TARGET_MS for value in values)
    return (
        f"{statistics.median(values):.2f} / {_p90(values):.2f} / {max(values):.2f} "
        f"({over} of {len(values)} > {FRAME_TARGET_MS:g})"
    )


def _p90(values: list[float]) -> float:
    return statistics.quantiles(values, n=10)[-1] if len(values) > 1 else values[0]


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The viewer suite's options."""
    arguments.sequences(parser, "samba, sample", initial=list(DEFAULT_SEQUENCES))
    parser.add_argument("--target-kg", type=float, default=0.1, help="encode at this KG error")
    parser.add_argument("--loads", type=int, default=5, help="page loads timed for opening")
    parser.add_argument("--play-seconds", type=float, default=5.0, help="seconds of playback")
    parser.add_argument(
        "--reference", action="store_true", help="serve with the original (view --reference)"
    )
    parser.add_argument("--chromium", help="the browser to run (default: found on PATH)")


def run(args: argparse.Namespace) -> int:
    """Measure and print; the exit status."""
    if args.loads < 1 or args.play_seconds <= 0:
        raise UsageError("--loads must be at least 1 and --play-seconds positive")
    chromium = args.chromium or find_chromium()
    if chromium is None:
        print("no chromium found (Debian: apt-get install chromium)", file=sys.stderr)
        return 2
    sources = []
    for name in args.sequences:
        path = name if name == common.SAMPLE else _source(name)
        if path is None:
            print(f"skipped {name}: not found (nor in {common.SHARED_DATA})", file=sys.stderr)
            continue
        sources.append((name, path))
    if not sources:
        return 2
    results = []
    with (
        tempfile.TemporaryDirectory(prefix="bench-viewer-") as folder,
        Browser.launch(chromium) as browser,
    ):
        version = browser.version()
        for name, path in sources:
            sequence = common.load(path)
            data = encode(sequence, target_kg=args.target_kg)
            file = Path(folder) / f"{Path(name).stem or 'sequence'}.tkc"
            file.write_bytes(data)
            with served(file, path if args.reference else None) as url:
                shown = Path(name).name + (" + reference" if args.reference else "")
                results.append(
                    measure(browser, url, shown, len(data), args.loads, args.play_seconds)
                )
    print(f"machine: {common.machine()}")
    print(f"browser: {version['product']}, headless; the page: {results[0].renderer}")
    print(f"command: {args.command}")
    print()
    print(table(results, args.target_kg))
    return 0


def _source(name: str) -> str | None:
    for candidate in (Path(name), common.SHARED_DATA / name):
        if candidate.exists():
            return str(candidate)
    return None
