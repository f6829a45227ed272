"""Size against a bound on every vertex: tuckercodec's ``max_error`` against SZ3 and
zfp with the same guarantee, and what a bound costs beside a KG target.

For each sequence (default: every one of ../shared/data present) and each bound D, given as a
fraction of the bounding-box diagonal of the whole sequence (every vertex of every frame):
``--bounds`` (default 1e-3 and 1e-4, the target bounds) in the tables, and those with
``--plot-bounds`` (default 3e-3, 1e-3, 3e-4, 1e-4) in the plot. The coders (``--coders``):

* ``tuckercodec``: ``Encoder(EncodeOptions(max_error=D)).encode_with_report``, D as a length;
* ``sz3``: SZ3 in absolute mode at D / sqrt(3) per coordinate, which bounds every vertex's
  Euclidean distance by D;
* ``zfp``: zfp in fixed-accuracy mode at tolerance D / sqrt(3).

The peers code the positions in the sequence's own precision (float32 where every value is a
float32 exactly, else float64). Sizes are whole files in bytes and bpfv, the connectivity
included: tuckercodec's own, and the faces with zstd 19 for the peers (as the peers suite
counts them). Every file is decoded again and its worst vertex measured here, with numpy in
float64 against the input (never taken from a coder's report): "yes" when it is within D.
Where tuckercodec reports a worst vertex of its own, a report that disagrees with the measure is
listed. An encode that raises (an unreachable bound) is a row saying so.

Then the bound beside a KG target: the plain ``target_kg=0.1`` file, its worst vertex W
measured here, and the file of ``target_kg=0.1, max_error=2 W`` (``--combined-kg``,
``--combined-factor``): both sizes and their ratio, the second file's worst vertex and KG.

Last, the misses against the targets: every vertex within D; tuckercodec's file at most
half of SZ3's (``TARGET_SZ3_RATIO``); the combined file at most 10 % above the plain one.

Times (encode, decode) are medians of ``--repeat`` runs, for the bounds of the tables. Output:
bounds.md (what is printed), results.json (every entry) and bounds.png (bpfv against D, a panel
per sequence; skipped with a message without matplotlib) in ``--out``.

    python -m tools.bench bounds                              # everything present
    python -m tools.bench bounds --repeat 3                   # medians of 3 (BENCHMARKS.md)
    python -m tools.bench bounds sample --bounds 1e-3 --coders sz3,zfp
"""

from __future__ import annotations

import argparse
import datetime
import json
import math
import sys
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

import tuckercodec
from tools import common
from tools.bench import arguments
from tools.bench.arguments import UsageError
from tools.bench.peers import base
from tools.bench.peers.sz3 import run_sz3_abs
from tools.bench.peers.tkc import run_with_options
from tools.bench.peers.zfp import run_zfp_accuracy
from tuckercodec import EncodeOptions, MeshSequence, TuckerCodecError, bpfv, kg_error
from tuckercodec.internal import KG_DEFINITION

DEFAULT_BOUNDS = [1e-3, 1e-4]
DEFAULT_PLOT_BOUNDS = [3e-3, 1e-3, 3e-4, 1e-4]
#: Target: tuckercodec's file at most this fraction of SZ3's with the same guarantee.
TARGET_SZ3_RATIO = 0.5
#: Target: ``--kg 0.1 --max-error 2W`` at most this much larger than the plain KG 0.1 file.
TARGET_COMBINED_RATIO = 1.10
#: tuckercodec's report of its worst vertex may differ from the measure here by this much
#: (relative): both are float64 sums of three squares, perhaps in another order.
REPORT_TOLERANCE = 1e-9


def _tuckercodec(sequence: MeshSequence, values: np.ndarray, bound: float) -> base.Trial:
    trial, report = run_with_options(
        sequence, EncodeOptions(max_error=bound), f"max_error {bound:.4g}"
    )
    trial.metrics["reported_worst"] = (
        math.nan if report.max_distance is None else report.max_distance
    )
    return trial


#: The coders, by name: what each needs (for the skip message) and its run at a bound D.
CODERS: dict[str, tuple[str, Callable[[MeshSequence, np.ndarray, float], base.Trial]]] = {
    "tuckercodec": ("", _tuckercodec),
    "sz3": ("pysz", run_sz3_abs),
    "zfp": ("zfpy", run_zfp_accuracy),
}


@dataclass
class Entry:
    """One coder at one bound on one sequence, measured."""

    sequence: str
    relative: float  # the bound over the bounding-box diagonal
    bound: float  # D, in the sequence's units
    coder: str
    setting: str = ""
    bytes: int | None = None
    connectivity_bpfv: float | None = None
    bpfv: float | None = None
    worst: float | None = None  # measured here
    worst_at: tuple[int, int] | None = None  # (frame, vertex)
    reported_worst: float | None = None  # tuckercodec's own report, if it gives one
    within: bool | None = None
    encode_seconds: float | None = None
    decode_seconds: float | None = None
    error: str | None = None  # why there is no file

    @property
    def ratio(self) -> float | None:
        """The worst vertex over D."""
        return None if self.worst is None else self.worst / self.bound


@dataclass
class Combined:
    """The plain KG file against the same KG with a bound at ``factor`` times its worst vertex."""

    sequence: str
    kg: float
    factor: float
    plain_bytes: int
    plain_bpfv: float
    plain_worst: float
    bound: float
    bytes: int | None = None
    bpfv: float | None = None
    worst: float | None = None
    measured_kg: float | None = None
    error: str | None = None

    @property
    def ratio(self) -> float | None:
        return None if self.bytes is None else self.bytes / self.plain_bytes


def sequence_name(path: str) -> str:
    """The name of a sequence in the tables: its file or folder name without ``.npz``."""
    return (
        common.SAMPLE if path == common.SAMPLE else Path(path.rstrip("/")).name.removesuffix(".npz")
    )


def measure(
    name: str,
    coder: str,
    run: Callable[[MeshSequence, np.ndarray, float], base.Trial],
    sequence: MeshSequence,
    values: np.ndarray,
    relative: float,
    diagonal: float,
    repeat: int,
) -> Entry:
    """Run one coder at one bound, decode, and measure its worst vertex here."""
    bound = relative * diagonal
    entry = Entry(name, relative, bound, coder)
    try:
        trial = run(sequence, values, bound)
    except (TuckerCodecError, NotImplementedError, ValueError) as error:
        # a bound the coder cannot meet (UnreachableTargetError) is a row, not the run's end
        entry.error = f"{type(error).__name__}: {error}"
        return entry
    assert trial.decoded is not None  # timed_trial keeps what it decoded
    worst, frame, vertex = base.worst_vertex(sequence.vertices, trial.decoded)
    trial.decoded = None
    base.retime_median(trial, repeat)
    reported = trial.metrics.get("reported_worst")
    entry.setting = trial.setting
    entry.bytes = trial.total_bytes
    frames, vertices = sequence.frame_count, sequence.vertex_count
    entry.connectivity_bpfv = bpfv(trial.connectivity_bytes or 0, frames, vertices)
    entry.bpfv = bpfv(trial.total_bytes, frames, vertices)
    entry.worst, entry.worst_at = worst, (frame, vertex)
    entry.reported_worst = None if reported is None or math.isnan(reported) else reported
    entry.within = worst <= bound
    entry.encode_seconds, entry.decode_seconds = trial.encode_seconds, trial.decode_seconds
    return entry


def combined(name: str, sequence: MeshSequence, kg: float, factor: float) -> Combined:
    """The plain ``target_kg=kg`` file, then the same with ``max_error`` at ``factor`` times
    its worst vertex (measured here)."""
    frames, vertices = sequence.frame_count, sequence.vertex_count
    plain, _ = run_with_options(sequence, EncodeOptions(target_kg=kg), f"KG<={kg:g}")
    assert plain.decoded is not None
    worst, _, _ = base.worst_vertex(sequence.vertices, plain.decoded)
    row = Combined(
        name,
        kg,
        factor,
        plain.total_bytes,
        bpfv(plain.total_bytes, frames, vertices),
        worst,
        factor * worst,
    )
    try:
        both, _ = run_with_options(
            sequence,
            EncodeOptions(target_kg=kg, max_error=row.bound),
            f"KG<={kg:g}, max_error {row.bound:.4g}",
        )
    except (TuckerCodecError, NotImplementedError, ValueError) as error:
        row.error = f"{type(error).__name__}: {error}"
        return row
    assert both.decoded is not None
    row.bytes = both.total_bytes
    row.bpfv = bpfv(both.total_bytes, frames, vertices)
    row.worst = base.worst_vertex(sequence.vertices, both.decoded)[0]
    row.measured_kg = kg_error(sequence.vertices, both.decoded)
    return row


# ------------------------------------------------------------------------------------------
# tables


def _g(value: float | None, digits: int = 3) -> str:
    return "n/a" if value is None else f"{value:.{digits}g}"


def entry_rows(entries: list[Entry], relatives: list[float]) -> list[str]:
    lines = [
        "| sequence | D / diagonal | D | coder | setting | bytes | bpfv (conn.) | worst vertex "
        "(frame, vertex) | worst / D | within D | enc s | dec s |",
        "|" + "---|" * 12,
    ]
    for e in entries:
        if e.relative not in relatives:
            continue
        head = f"| {e.sequence} | {e.relative:g} | {e.bound:.4g} | {e.coder} |"
        if e.error is not None:
            lines.append(f"{head} {e.error} | | | | | | | |")
            continue
        assert e.bytes is not None and e.bpfv is not None and e.worst_at is not None
        lines.append(
            f"{head} {e.setting} | {e.bytes} | {e.bpfv:.3f} ({e.connectivity_bpfv:.3f}) | "
            f"{_g(e.worst, 4)} ({e.worst_at[0]}, {e.worst_at[1]}) | {e.ratio:.3f} | "
            f"{'yes' if e.within else '**NO**'} | {e.encode_seconds:.2f} | "
            f"{e.decode_seconds:.3f} |"
        )
    return lines


def _find(entries: list[Entry], sequence: str, relative: float, coder: str) -> Entry | None:
    return next(
        (
            e
            for e in entries
            if e.sequence == sequence and e.relative == relative and e.coder == coder
        ),
        None,
    )


def summary_rows(entries: list[Entry], names: list[str], relatives: list[float]) -> list[str]:
    """bpfv of each coder per sequence and bound, and tuckercodec's size over SZ3's."""
    coders = [c for c in CODERS if any(e.coder == c for e in entries)]
    lines = [
        "| sequence | D / diagonal | "
        + " | ".join(f"{c} bpfv" for c in coders)
        + " | tuckercodec / sz3 | every vertex within D |",
        "|" + "---|" * (len(coders) + 4),
    ]
    for name in names:
        for relative in relatives:
            found = {c: _find(entries, name, relative, c) for c in coders}
            cells = []
            for coder in coders:
                e = found[coder]
                if e is None or e.bpfv is None:
                    cells.append("n/a" if e is None else "no file")
                else:
                    cells.append(f"{e.bpfv:.3f}" + ("" if e.within else " (**over D**)"))
            ours, sz3 = found.get("tuckercodec"), found.get("sz3")
            if ours is not None and sz3 is not None and ours.bytes and sz3.bytes:
                ratio = ours.bytes / sz3.bytes
                verdict = "" if ratio <= TARGET_SZ3_RATIO else " **over 0.5**"
                ratio_text = f"{ratio:.3f}{verdict}"
            else:
                ratio_text = "n/a"
            every = all(e is not None and e.within for e in found.values())
            lines.append(
                f"| {name} | {relative:g} | "
                + " | ".join(cells)
                + f" | {ratio_text} | {'yes' if every else '**NO**'} |"
            )
    return lines


def plot_rows(entries: list[Entry], names: list[str], plotted: list[float]) -> list[str]:
    """The plot's points as a table: each coder's bpfv at every bound measured."""
    coders = [c for c in CODERS if any(e.coder == c for e in entries)]
    lines = [
        "| sequence | coder | " + " | ".join(f"{r:g}" for r in plotted) + " |",
        "|" + "---|" * (len(plotted) + 2),
    ]
    for name in names:
        for coder in coders:
            cells = []
            for relative in plotted:
                e = _find(entries, name, relative, coder)
                if e is None or e.bpfv is None:
                    cells.append("no file")
                else:
                    cells.append(f"{e.bpfv:.3f}" + ("" if e.within else " (**over D**)"))
            lines.append(f"| {name} | {coder} | " + " | ".join(cells) + " |")
    return lines


def combined_rows(rows: list[Combined]) -> list[str]:
    lines = [
        "| sequence | plain KG file bytes (bpfv) | its worst vertex W | bound | bounded file "
        "bytes (bpfv) | its worst vertex | its KG | size ratio |",
        "|" + "---|" * 8,
    ]
    for r in rows:
        head = (
            f"| {r.sequence} | {r.plain_bytes} ({r.plain_bpfv:.3f}) | {r.plain_worst:.4g} | "
            f"{r.factor:g} W = {r.bound:.4g} |"
        )
        if r.error is not None:
            lines.append(f"{head} {r.error} | | | |")
            continue
        assert r.bpfv is not None and r.ratio is not None and r.worst is not None
        verdict = "" if r.ratio <= TARGET_COMBINED_RATIO else " **over 1.10**"
        within = "" if r.worst <= r.bound else " **over the bound**"
        over_kg = "" if r.measured_kg is not None and r.measured_kg <= r.kg else " **over KG**"
        lines.append(
            f"{head} {r.bytes} ({r.bpfv:.3f}) | {r.worst:.4g}{within} | "
            f"{_g(r.measured_kg, 4)}{over_kg} | {r.ratio:.3f}{verdict} |"
        )
    return lines


def misses(entries: list[Entry], rows: list[Combined], relatives: list[float]) -> list[str]:
    """What broke a promise or missed a target of the bound mode."""
    found = []
    for e in entries:
        label = f"{e.sequence} {e.coder} at {e.relative:g} of the diagonal"
        if e.error is not None:
            found.append(f"{label}: no file ({e.error})")
            continue
        if not e.within:
            found.append(f"{label}: worst vertex {e.worst:.4g} > D = {e.bound:.4g}")
        if e.reported_worst is not None and e.worst is not None:
            gap = abs(e.reported_worst - e.worst) / max(e.worst, 1e-300)
            if gap > REPORT_TOLERANCE:
                found.append(
                    f"{label}: the encoder reports a worst vertex of {e.reported_worst:.6g}, "
                    f"measured {e.worst:.6g}"
                )
        if e.coder == "tuckercodec" and e.relative in relatives:
            sz3 = _find(entries, e.sequence, e.relative, "sz3")
            if sz3 is not None and sz3.bytes and e.bytes:
                ratio = e.bytes / sz3.bytes
                if ratio > TARGET_SZ3_RATIO:
                    found.append(f"{label}: {ratio:.3f} of SZ3's size (target <= 0.5)")
    for r in rows:
        label = f"{r.sequence} KG {r.kg:g} with max_error {r.factor:g} W"
        if r.error is not None:
            found.append(f"{label}: no file ({r.error})")
            continue
        assert r.ratio is not None and r.worst is not None
        if r.ratio > TARGET_COMBINED_RATIO:
            found.append(f"{label}: {r.ratio:.3f} of the plain file (target <= 1.10)")
        if r.worst > r.bound:
            found.append(f"{label}: worst vertex {r.worst:.4g} > {r.bound:.4g}")
        if r.measured_kg is None or r.measured_kg > r.kg:
            found.append(f"{label}: KG {_g(r.measured_kg, 4)} > {r.kg:g}")
    return found


def plot(entries: list[Entry], names: list[str], path: Path, force: bool) -> str | None:
    """bpfv against D / diagonal, one panel per sequence, a line per coder (a cross where the
    worst vertex is over D); None, or why there is no plot."""
    try:
        plt = tuckercodec.internal.pyplot()
    except tuckercodec.DependencyError as error:
        return str(error)
    columns = min(2, len(names))
    rows = math.ceil(len(names) / columns)
    fig, axes = plt.subplots(rows, columns, figsize=(6 * columns, 4.2 * rows), squeeze=False)
    for ax, name in zip(axes.flat, names, strict=False):
        for coder in CODERS:
            points = sorted(
                (e.relative, e.bpfv, e.within)
                for e in entries
                if e.sequence == name and e.coder == coder and e.bpfv is not None
            )
            if not points:
                continue
            x = [p[0] for p in points]
            y = [p[1] for p in points]
            (line,) = ax.plot(x, y, "o-", ms=4, lw=1.3, label=coder)
            over = [(p[0], p[1]) for p in points if not p[2]]
            if over:
                ox, oy = zip(*over, strict=True)
                ax.plot(ox, oy, "x", ms=9, color=line.get_color(), label=f"{coder}: over D")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.invert_xaxis()  # tighter bounds to the right
        ax.set_xlabel("bound D on every vertex / bounding-box diagonal")
        ax.set_ylabel("bpfv (whole file, faces included)")
        ax.set_title(name)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    for ax in list(axes.flat)[len(names) :]:
        ax.set_visible(False)
    fig.suptitle("Size against a bound on every vertex's Euclidean error")
    fig.tight_layout()
    tuckercodec.internal.save_figure(fig, path, dpi=120, overwrite=force)
    return None


# ------------------------------------------------------------------------------------------
# the suite


def _fractions(text: str) -> list[float]:
    values = sorted({float(v) for v in text.split(",") if v.strip()}, reverse=True)
    if not values or any(not 0 < v < 1 for v in values):
        raise UsageError(f"bounds are fractions of the diagonal between 0 and 1, got {text!r}")
    return values


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The bounds suite's options."""
    arguments.sequences(parser, "every sequence of ../shared/data")
    parser.add_argument(
        "--bounds",
        default=",".join(f"{b:g}" for b in DEFAULT_BOUNDS),
        help="bounds D of the tables, fractions of the bounding-box diagonal, comma-separated",
    )
    parser.add_argument(
        "--plot-bounds",
        default=",".join(f"{b:g}" for b in DEFAULT_PLOT_BOUNDS),
        help="bounds D of the plot (the tables' are measured anyway), comma-separated",
    )
    parser.add_argument("--coders", default=",".join(CODERS), help="coders to run, comma-separated")
    parser.add_argument(
        "--combined-kg", type=float, default=0.1, help="KG target of the combined row"
    )
    parser.add_argument(
        "--combined-factor",
        type=float,
        default=2.0,
        help="the combined row's bound, over the plain file's worst vertex",
    )
    parser.add_argument(
        "--no-combined", action="store_true", help="leave out the combined KG + bound row"
    )
    arguments.repeat(parser, 1, "timings of each entry of the tables, the medians kept")
    arguments.output(parser, "output folder (default results/bench-bounds)", "results/bench-bounds")


def run(args: argparse.Namespace) -> int:
    """Measure and print; the exit status."""
    relatives = _fractions(args.bounds)
    plotted = sorted(set(relatives) | set(_fractions(args.plot_bounds)), reverse=True)
    coders, skipped = arguments.available_coders(
        args.coders, CODERS, lambda coder: base.missing(CODERS[coder][0])
    )
    inputs = arguments.sequences_and_folder(args, "bounds.md")
    if inputs is None:
        return 2
    paths, out = inputs

    started = time.monotonic()
    entries: list[Entry] = []
    rows: list[Combined] = []
    names: list[str] = []
    taken: set[str] = set()
    header: list[str] = []
    for path in paths:
        name = common.unique_name(sequence_name(path), taken)
        names.append(name)
        sequence = common.load(path)
        values = base.own_precision(sequence)
        diagonal = base.bounding_box_diagonal(sequence.vertices)
        header.append(
            f"- {name}: {sequence.frame_count} frames, {sequence.vertex_count} vertices, "
            f"{sequence.faces.shape[0]} faces, values {values.dtype}, diagonal {diagonal:.6g}"
        )
        for relative in plotted:
            for coder in coders:
                print(f"{name}: {coder} at {relative:g} of the diagonal...", file=sys.stderr)
                repeat = args.repeat if relative in relatives else 1
                entries.append(
                    measure(
                        name, coder, CODERS[coder][1], sequence, values, relative, diagonal, repeat
                    )
                )
        if "tuckercodec" in coders and not args.no_combined:
            print(f"{name}: KG {args.combined_kg:g} with and without a bound...", file=sys.stderr)
            rows.append(combined(name, sequence, args.combined_kg, args.combined_factor))

    found = misses(entries, rows, relatives)
    text = [
        f"# Size against a bound on every vertex ({datetime.date.today()}, "
        f"tuckercodec {tuckercodec.__version__})",
        "",
        f"Machine: {common.machine()}. Command: `{args.command}`. "
        f"Wall time {time.monotonic() - started:.0f} s.",
        "",
        *header,
        "",
        "Sizes: whole files, faces included (their share in brackets). Worst vertex: the "
        "largest Euclidean distance of a decoded vertex from the input, measured here; D is a "
        "fraction of the bounding-box diagonal. Times: medians of "
        f"{args.repeat} run(s).",
        "",
        *summary_rows(entries, names, relatives),
        "",
        *entry_rows(entries, relatives),
        "",
    ]
    if plotted != relatives:
        text += [
            "bpfv at every bound measured (the plot's points; D over the diagonal):",
            "",
            *plot_rows(entries, names, plotted),
            "",
        ]
    if rows:
        text += [
            f"KG {args.combined_kg:g} alone, then with a bound at {args.combined_factor:g} times "
            f"its worst vertex ({KG_DEFINITION}):",
            "",
            *combined_rows(rows),
            "",
        ]
    text += [f"{coder}: skipped, {why}." for coder, why in skipped.items()]
    text += ["Misses:", *(f"- {m}" for m in found)] if found else ["Misses: none."]
    common.write_text(out / "bounds.md", "\n".join(text) + "\n", args.force)
    everything = [asdict(e) for e in entries] + [
        {**asdict(r), "kind": "combined", "ratio": r.ratio} for r in rows
    ]
    common.write_text(out / "results.json", json.dumps(everything, indent=1), args.force)
    why = plot(entries, names, out / "bounds.png", args.force)
    if why is not None:
        print(f"plot skipped: {why}", file=sys.stderr)
    print("\n".join(text))
    return 0
