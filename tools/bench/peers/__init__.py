"""Rate-distortion benchmark of tuckercodec against its peers, all measured in one run.

For each sequence (default: every one of ../shared/data present) and each coder of
:data:`CODERS` (a module each in this package) that can run here, every encode is decoded again
and measured the same way:

* size: the whole file in bytes and in bpfv (8 * bytes / (F * K)), the connectivity stored once
  shown separately ("in frames" where every frame carries its own, as per-frame Draco meshes);
* error: KG (Karni-Gotsman 2004, per-frame centroid, percent), STED (Vasa and Skala 2011, see
  tuckercodec.sted, with its default parameters) and the largest vertex displacement in
  scene units, all of the decoded positions against the input;
* time: encode and decode, seconds, the median of ``--repeat`` runs of the setting that
  represents the coder at a target (the search for SZ3/zfp/TTHRESH's bound is not counted,
  only the encode at the bound finally chosen; tuckercodec's and PCA's own searches are part of
  their encode); Draco's decode time leaves out the matching of its reordered vertices;
* memory: peak resident memory of one encode + decode above the resident memory before it
  (Linux VmHWM, so native allocations count), in MiB.

At each KG target a coder is represented by its smallest file whose decoded KG meets the
target: tuckercodec, PCA, SZ3, zfp and TTHRESH are searched for each target; Draco and
meshoptimizer are run at every quantization bit count (default 8-16) and the smallest that meets
the target is taken ("not reached" if none does).

Output, in ``--out`` (default results/bench): one markdown table and one rate-distortion plot
(bpfv against KG, both log scale) per sequence, summary.md (the smallest coder per target and
tuckercodec's ratio to each coder) and results.json (every trial).

    python -m tools.bench peers                             # everything present, ~7 minutes
    python -m tools.bench peers --repeat 3                  # medians of 3 timings (BENCHMARKS.md)
    python -m tools.bench peers ../shared/data/chicken.npz --coders tuckercodec,pca --targets 1
"""

from __future__ import annotations

import argparse
import datetime
import inspect
import json
import math
import sys
import time
from pathlib import Path

import tuckercodec
from tools import common
from tools.bench import arguments
from tools.bench.arguments import UsageError
from tools.bench.peers import base
from tools.bench.peers.draco import run_draco_mesh, run_draco_points
from tools.bench.peers.meshopt import run_meshopt
from tools.bench.peers.pca import run_pca
from tools.bench.peers.sz3 import run_sz3
from tools.bench.peers.tkc import run_tuckercodec
from tools.bench.peers.tthresh import run_tthresh
from tools.bench.peers.zfp import run_zfp
from tools.bench.peers.zstd import run_zstd
from tuckercodec import bpfv, internal, max_vertex_displacement, sted
from tuckercodec.internal import KG_DEFINITION

#: Every coder, in the order of the tables.
CODERS: list[base.Coder] = [
    base.Coder("tuckercodec", run_tuckercodec),
    base.Coder("pca", run_pca),
    base.Coder("draco-mesh", run_draco_mesh, "DracoPy"),
    base.Coder("draco-points", run_draco_points, "DracoPy"),
    base.Coder("meshopt", run_meshopt, "meshoptimizer"),
    base.Coder("sz3", run_sz3, "pysz"),
    base.Coder("zfp", run_zfp, "zfpy"),
    base.Coder("zstd-f32", run_zstd),
    base.Coder("tthresh", run_tthresh, "binary:tthresh"),
]

DEFAULT_TARGETS = [2.0, 1.0, 0.5, 0.2, 0.1, 0.05, 0.02]
DEFAULT_BITS = list(range(8, 17))


def _sequence_name(path: str) -> str:
    if path == common.SAMPLE:
        return common.SAMPLE
    name = Path(path.rstrip("/")).name
    for suffix in (".npz", ".obj"):
        name = name.removesuffix(suffix)
    return name.removesuffix("-gallop").removesuffix("-vellum") or name


class Progress:
    """A bar on a terminal, one line per step elsewhere (CI logs, pipes)."""

    def __init__(self, total: int) -> None:
        self.total = total
        self.done = 0
        self.start = time.monotonic()
        self.tty = sys.stderr.isatty()

    def step(self, label: str) -> None:
        self.done += 1
        elapsed = time.monotonic() - self.start
        if self.tty:
            filled = 30 * self.done // self.total
            sys.stderr.write(
                f"\r[{'#' * filled}{'.' * (30 - filled)}] {self.done}/{self.total} "
                f"{elapsed:6.0f} s  {label:<40.40}"
            )
            if self.done == self.total:
                sys.stderr.write("\n")
        else:
            sys.stderr.write(f"[{self.done}/{self.total}] {elapsed:6.1f} s  {label}\n")
        sys.stderr.flush()


def measure(trial: base.Trial, sequence: tuckercodec.MeshSequence, context: base.Context) -> None:
    """Fill ``trial.metrics`` from its decoded positions, then drop them."""
    decoded = trial.decoded
    assert decoded is not None, f"{trial.coder} {trial.setting} was measured already"
    if math.isnan(trial.kg):
        trial.kg = context.kg(decoded)
    frames, vertices = sequence.frame_count, sequence.vertex_count
    m: dict[str, float] = {
        "kg": trial.kg,
        "bpfv": bpfv(trial.total_bytes, frames, vertices),
        "max_displacement": max_vertex_displacement(sequence.vertices, decoded).distance,
    }
    if trial.connectivity_bytes is not None:
        m["connectivity_bpfv"] = bpfv(trial.connectivity_bytes, frames, vertices)
    if sequence.faces.size:  # STED compares edges: none without faces
        value = sted(sequence.vertices, decoded, sequence.faces)
        m.update(sted=value.value, sted_spatial=value.spatial, sted_temporal=value.temporal)
    trial.metrics = m
    trial.decoded = None


def best_at(trials: list[base.Trial], target: float) -> base.Trial | None:
    """The smallest trial whose decoded KG meets ``target``."""
    met = [t for t in trials if t.kg <= target]
    return min(met, key=lambda t: t.total_bytes) if met else None


def retime_chosen(
    trials_by_coder: dict[str, list[base.Trial]], targets: list[float], repeat: int
) -> None:
    """Time the trials that represent a coder at some target ``repeat`` times in all and keep
    the medians (the first, measured run included)."""
    if repeat <= 1:
        return
    chosen = {
        id(t): t
        for trials in trials_by_coder.values()
        for target in targets
        if (t := best_at(trials, target)) is not None
    }
    for trial in chosen.values():
        base.retime_median(trial, repeat)


def encode_seconds(trial: base.Trial) -> float:
    """The encode's time, with its share of work done once for every setting (PCA's SVD)."""
    return trial.encode_seconds + trial.setup_seconds


def _fmt(value: float | None, digits: int = 3) -> str:
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "n/a"
    return (
        f"{value:.{digits}g}" if abs(value) < 1e-3 or abs(value) >= 1e4 else f"{value:.{digits}f}"
    )


def _sted_parameters() -> str:
    """The STED parameters used (tuckercodec.sted's defaults), for the table's legend."""
    defaults = inspect.signature(sted).parameters
    named = ", ".join(f"{name} {defaults[name].default}" for name in ("width", "window", "dt", "c"))
    return f"(Vasa-Skala 2011; {named}; scale 1 / first frame's bounding-box diagonal)"


def sequence_table(name: str, sequence, trials_by_coder, targets, skipped) -> str:
    """The markdown report of one sequence: every coder at every target."""
    lines = [
        f"## {name}: {sequence.frame_count} frames, {sequence.vertex_count} vertices, "
        f"{sequence.faces.shape[0]} faces",
        "",
    ]
    lines.append(
        f"Errors: {KG_DEFINITION}; STED {_sted_parameters()}; largest displacement in "
        "scene units. Sizes count the whole file, connectivity included (its share in "
        "brackets)."
    )
    lines.append("")
    header = (
        "| target KG | coder | setting | bytes | bpfv (conn.) | KG | STED | max disp. | "
        "enc s | dec s | peak MiB |"
    )
    lines += [header, "|" + "---|" * 11]
    for target in targets:
        for coder, trials in trials_by_coder.items():
            best = best_at(trials, target)
            if not trials:
                lines.append(
                    f"| {target:g} | {coder} | not run on this sequence (no faces) "
                    "| | | | | | | | |"
                )
                continue
            if best is None:
                reach = min((t.kg for t in trials), default=math.nan)
                lines.append(
                    f"| {target:g} | {coder} | not reached (best KG {_fmt(reach)}) "
                    "| | | | | | | | |"
                )
                continue
            m = best.metrics
            conn = m.get("connectivity_bpfv")
            conn_text = f"({conn:.3f})" if conn is not None else "(in frames)"
            peak = "n/a" if best.peak_bytes is None else f"{best.peak_bytes / common.MIB:.0f}"
            lines.append(
                f"| {target:g} | {coder} | {best.setting} | {best.total_bytes} | "
                f"{m['bpfv']:.3f} {conn_text} | {_fmt(m['kg'], 4)} | {_fmt(m.get('sted'))} | "
                f"{_fmt(m['max_displacement'])} | {encode_seconds(best):.2f} | "
                f"{best.decode_seconds:.2f} | {peak} |"
            )
    for coder, why in skipped.items():
        lines.append(f"\n{coder}: skipped, {why}.")
    return "\n".join(lines) + "\n"


def summary_rows(name: str, trials_by_coder, targets) -> list[str]:
    """For each target: the smallest coder, and every coder's bpfv over tuckercodec's."""
    coders = list(trials_by_coder)
    lines = []
    for target in targets:
        best = {coder: best_at(trials, target) for coder, trials in trials_by_coder.items()}
        sizes = {c: b.total_bytes for c, b in best.items() if b is not None}
        if not sizes:
            continue
        smallest = min(sizes, key=lambda coder: sizes[coder])
        ours = sizes.get("tuckercodec")
        cells = []
        for coder in coders:
            b = best[coder]
            trials = trials_by_coder[coder]
            # ‡: the coder's coarsest setting, far below the target: the ratio compares unequal
            # errors
            floor = (
                "‡"
                if b is not None
                and b.setting.endswith(" bits")
                and b is max(trials, key=lambda t: t.kg)
                and b.kg < target / 2
                else ""
            )
            if b is None:
                cells.append("not reached" if trials else "not run")
            elif ours is None or coder == "tuckercodec":
                cells.append(f"{b.metrics['bpfv']:.3f}{floor}")
            else:
                cells.append(f"{b.metrics['bpfv']:.3f}{floor} ({b.total_bytes / ours:.2f}×)")
        lines.append(f"| {name} | {target:g} | {smallest} | " + " | ".join(cells) + " |")
    return lines


def plot(name: str, trials_by_coder, targets, path: Path, force: bool) -> None:
    plt = internal.pyplot()
    fig, ax = plt.subplots(figsize=(8, 5))
    for coder, trials in trials_by_coder.items():
        points = sorted((t.kg, t.metrics["bpfv"]) for t in trials if t.kg > 0 and t.metrics)
        exact = [t.metrics["bpfv"] for t in trials if t.kg == 0 and t.metrics]
        if exact:  # a lossless coder has no place on a log error axis: draw its rate across
            ax.axhline(min(exact), ls="--", lw=1.0, color="0.4", label=f"{coder} (KG 0, lossless)")
        if not points:
            continue
        kg, rate = zip(*points, strict=True)  # pairs: two sequences of equal length
        ax.plot(kg, rate, "o-" if len(points) > 1 else "s", ms=3.5, lw=1.3, label=coder)
    for target in targets:
        ax.axvline(target, color="0.85", lw=0.8, zorder=0)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("decoded KG error, % (Karni-Gotsman, per-frame centroid)")
    ax.set_ylabel("bpfv (whole file, connectivity included)")
    ax.set_title(f"{name}: rate-distortion, every coder measured in one run")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    internal.save_figure(fig, path, dpi=120, overwrite=force)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The peers suite's options."""
    arguments.sequences(parser, "every sequence of ../shared/data")
    parser.add_argument(
        "--targets",
        default=",".join(f"{t:g}" for t in DEFAULT_TARGETS),
        help="KG targets, comma-separated",
    )
    parser.add_argument(
        "--coders",
        default=",".join(c.name for c in CODERS),
        help="coders to run, comma-separated",
    )
    parser.add_argument(
        "--bits",
        default=f"{DEFAULT_BITS[0]}-{DEFAULT_BITS[-1]}",
        help="quantization bits of Draco and meshoptimizer, A-B",
    )
    arguments.repeat(parser, 1, "timings of each coder's chosen setting, the medians kept")
    arguments.output(parser, "output folder (default results/bench)", default="results/bench")


def run(args: argparse.Namespace) -> int:
    """Measure and print; the exit status."""

    targets = sorted({float(t) for t in args.targets.split(",")}, reverse=True)
    low, _, high = args.bits.partition("-")
    bits = list(range(int(low), int(high or low) + 1))
    wanted = args.coders.split(",")
    unknown = set(wanted) - {c.name for c in CODERS}
    if unknown:
        raise UsageError(f"unknown coders: {', '.join(sorted(unknown))}")
    coders = [c for c in CODERS if c.name in wanted]
    found = arguments.sequences_and_folder(args, "summary.md")
    if found is None:
        return 2
    paths, out = found

    skipped = {c.name: c.unavailable() for c in coders if c.unavailable()}
    for name, why in skipped.items():
        print(f"{name}: skipped, {why}", file=sys.stderr)
    runnable = [c for c in coders if c.name not in skipped]
    progress = Progress(len(paths) * len(runnable))
    started = time.monotonic()
    summary = []
    everything = []
    taken: set[str] = set()
    for path in paths:
        name = common.unique_name(_sequence_name(path), taken)
        sequence = common.load(path)
        context = base.Context.of(sequence, bits)
        trials_by_coder: dict[str, list[base.Trial]] = {}
        for coder in runnable:
            trials = coder.run(sequence, targets, context)
            for trial in trials:
                measure(trial, sequence, context)
            retime_chosen({coder.name: trials}, targets, args.repeat)
            trials_by_coder[coder.name] = trials
            progress.step(f"{name}: {coder.name}")
            everything += [
                {
                    "sequence": name,
                    "coder": t.coder,
                    "setting": t.setting,
                    "target": t.target,
                    "bytes": t.total_bytes,
                    "connectivity_bytes": t.connectivity_bytes,
                    "encode_seconds": encode_seconds(t),
                    "decode_seconds": t.decode_seconds,
                    "peak_bytes": t.peak_bytes,
                    **t.metrics,
                }
                for t in trials
            ]
        common.write_text(
            out / f"{name}.md",
            sequence_table(name, sequence, trials_by_coder, targets, skipped),
            args.force,
        )
        plot(name, trials_by_coder, targets, out / f"{name}.png", args.force)
        summary += summary_rows(name, trials_by_coder, targets)

    names = [c.name for c in runnable]
    text = [
        f"# Benchmark summary ({datetime.date.today()}, tuckercodec {tuckercodec.__version__})",
        "",
        f"Machine: {common.machine()}. Command: `{args.command}`. "
        f"Wall time {time.monotonic() - started:.0f} s.",
        "",
        "bpfv of the smallest file of each coder whose decoded KG error (Karni-Gotsman) meets the "
        "target, whole file with connectivity; in brackets its size over tuckercodec's "
        "(above 1×: tuckercodec is smaller). ‡: the coder's coarsest setting (8 bits), whose "
        "error is less than half the target: a coarser one would be smaller.",
        "",
        "| sequence | target KG | smallest | " + " | ".join(names) + " |",
        "|" + "---|" * (3 + len(names)),
        *summary,
        "",
        *(f"{coder}: skipped, {why}." for coder, why in skipped.items()),
    ]
    common.write_text(out / "summary.md", "\n".join(text) + "\n", args.force)
    common.write_text(out / "results.json", json.dumps(everything, indent=1), args.force)
    print("\n".join(text))
    return 0
