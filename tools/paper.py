"""The seed paper's experiments, reproduced: Romaszewski and Głomb (2016), Fig. 1, 2 and 3, and
the measurements that check its four claims (see docs/paper.md).

For each sequence (chicken and samba from ../shared/data by default, skipping absent ones, or any
npz / OBJ folder / ``sample`` given on the command line) it writes into the output folder:

* ``NAME-fig1-rd.png``: reduction rate Θ against log KG: exact HOSVD front, the front the paper's
  bound would build, PCA (drawn by :func:`tuckercodec.internal.plot_rd_curve`);
* ``NAME-fig2-psi.png``: ψ = bound − exact KG against Θ in ten windows, as box plots (whiskers are
  min and max), over every truncation and along the exact rate-distortion front;
* ``NAME-fig3-heatmaps.png``: log10 KG and log10 ψ over (i, k), with both readings of "the
  diagonal" (i = k, and i/R1 = k/R3) and the exact front drawn on top;
* ``summary.md``: every table (box statistics, the four claims) with the machine, date, command.

All errors are KG errors with the Karni-Gotsman denominator (per-frame centroid), in percent.
Rates are the paper's Θ = S / (3KF), S = i*K + 9 + k*F + 3*i*k stored floats, unless the column
says bytes of a real tuckercodec file.

    python -m tools.paper                          # chicken and samba, into results/paper/
    python -m tools.paper sample --out /tmp/p      # the built-in cloth
    python -m tools.paper seq.npz frames/ --force --no-encode
"""

from __future__ import annotations

import argparse
import datetime
import re
import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from tools import common
from tuckercodec import (
    Analysis,
    InputError,
    MeshSequence,
    TuckerCodecError,
    analyze,
    decode,
    encode_with_report,
    internal,
    kg_error,
    sted,
)
from tuckercodec.internal import (
    KG_DEFINITION,
    STED_DEFINITION,
    Curve,
    plot_rd_curve,  # matplotlib itself is imported only to draw
    reconstruct,
    refuse_existing,
)

DEFAULT_SEQUENCES = ("chicken.npz", "samba.npz")
DEFAULT_OUT = common.REPO / "results" / "paper"  # /results/ is git-ignored
KG_TARGETS = (1.0, 0.5, 0.1, 0.05)
RATE_POINTS = (0.05, 0.10)  # the paper's "acceptable" and "indistinguishable" sizes
WINDOWS = 10  # Fig. 2: Θ in (0, 1] split into this many equal windows
NEAR_SHARE, FAR_SHARE = 0.10, 0.50  # claim (b): nearest 10 % vs farthest 50 % of a window
PSI_FLOOR = 1e-12  # log plots only: ψ is 0 (or -1e-16 by rounding) where nothing is discarded


# ------------------------------------------------------------------------------------------
# measurements


@dataclass(frozen=True)
class Box:
    """Box statistics of ψ (and the median ratio bound/exact) over one window of Θ."""

    low: float
    high: float
    count: int
    quantiles: tuple[float, float, float, float, float]  # min, q1, median, q3, max of ψ
    ratio: float  # median of kg_bound / kg (NaN where kg is 0)
    kg: float  # median exact KG: where on the error scale the window lies


def window_edges(windows: int = WINDOWS) -> np.ndarray:
    """Edges of the Θ windows: (0, 1] in equal parts; Θ > 1 stores more than the original."""
    return np.linspace(0.0, 1.0, windows + 1)


def boxes(
    rate: np.ndarray, psi: np.ndarray, kg: np.ndarray, kg_bound: np.ndarray, windows: int = WINDOWS
) -> list[Box]:
    """ψ statistics per Θ window; windows are (low, high] (Θ > 0 always: S > 0)."""
    edges = window_edges(windows)
    out = []
    for w in range(windows):
        inside = (rate > edges[w]) & (rate <= edges[w + 1])
        values = psi[inside]
        if values.size:
            q = np.percentile(values, [0, 25, 50, 75, 100])
            quantiles = (float(q[0]), float(q[1]), float(q[2]), float(q[3]), float(q[4]))
            with np.errstate(divide="ignore", invalid="ignore"):
                ratios = np.where(kg[inside] > 0, kg_bound[inside] / kg[inside], np.nan)
            ratio = float(np.nanmedian(ratios))
            median_kg = float(np.median(kg[inside]))
        else:
            nan = float("nan")
            quantiles, ratio, median_kg = (nan, nan, nan, nan, nan), nan, nan
        out.append(
            Box(float(edges[w]), float(edges[w + 1]), int(values.size), quantiles, ratio, median_kg)
        )
    return out


def all_truncations(analysis: Analysis) -> dict[str, np.ndarray]:
    """Flat arrays over every (i, k) with i, k >= 1: ranks, Θ, exact KG, bound, ψ."""
    r1, r3 = analysis.max_ranks
    ii, kk = np.meshgrid(np.arange(1, r1 + 1), np.arange(1, r3 + 1), indexing="ij")
    return {
        "i": ii.ravel(),
        "k": kk.ravel(),
        "rate": analysis.rate_table()[1:, 1:].ravel(),
        "kg": analysis.kg_table()[1:, 1:].ravel(),
        "kg_bound": analysis.kg_bound_table()[1:, 1:].ravel(),
        "psi": analysis.psi_table()[1:, 1:].ravel(),
    }


@dataclass(frozen=True)
class DiagonalWindow:
    """Claim (b) in one Θ window: ψ near the diagonal against ψ far from it."""

    low: float
    high: float
    near_count: int
    far_count: int
    near_distance: float  # "near" is distance <= this
    far_distance: float  # "far" is distance >= this
    psi_near: float  # medians
    psi_far: float
    ratio_near: float  # medians of kg_bound / kg
    ratio_far: float


def distances(analysis: Analysis, i: np.ndarray, k: np.ndarray) -> dict[str, np.ndarray]:
    """Distance from "the diagonal" of the (i, k) plane, in its two readings.

    R1 and R3 differ (chicken: 1200 and 400), so i = k and the corner-to-corner line differ:
    ``raw`` is |i - k| in ranks, ``normalised`` is |i/R1 - k/R3| (fractions of each range).
    """
    r1, r3 = analysis.max_ranks
    return {"raw": np.abs(i - k).astype(float), "normalised": np.abs(i / r1 - k / r3)}


def diagonal_study(
    analysis: Analysis, table: dict[str, np.ndarray]
) -> dict[str, list[DiagonalWindow]]:
    """Within each Θ window (so that rate is held roughly fixed: ψ falls steeply with rate,
    which would swamp any effect of the position), compare the nearest NEAR_SHARE of the
    window's truncations to the diagonal with its farthest FAR_SHARE."""
    edges = window_edges()
    out: dict[str, list[DiagonalWindow]] = {}
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.where(table["kg"] > 0, table["kg_bound"] / table["kg"], np.nan)
    for reading, distance in distances(analysis, table["i"], table["k"]).items():
        rows = []
        for w in range(WINDOWS):
            inside = (table["rate"] > edges[w]) & (table["rate"] <= edges[w + 1])
            if inside.sum() < 2:
                continue
            d = distance[inside]
            near_d, far_d = np.quantile(d, NEAR_SHARE), np.quantile(d, 1 - FAR_SHARE)
            near, far = d <= near_d, d >= far_d
            psi, rat = table["psi"][inside], ratio[inside]
            rows.append(
                DiagonalWindow(
                    float(edges[w]),
                    float(edges[w + 1]),
                    int(near.sum()),
                    int(far.sum()),
                    float(near_d),
                    float(far_d),
                    float(np.median(psi[near])),
                    float(np.median(psi[far])),
                    float(np.nanmedian(rat[near]))
                    if np.isfinite(rat[near]).any()
                    else float("nan"),
                    float(np.nanmedian(rat[far])) if np.isfinite(rat[far]).any() else float("nan"),
                )
            )
        out[reading] = rows
    return out


@dataclass(frozen=True)
class TargetRow:
    """Claims (a) and (d) at one KG target."""

    target: float
    exact: tuple[int, int]
    exact_floats: int
    exact_rate: float
    exact_kg: float
    exact_kg_bound: float  # the bound's estimate at the exact choice
    bound: tuple[int, int]
    bound_floats: int
    bound_kg: float  # exact error of the bound's choice
    pca_rank: int
    pca_floats: int
    pca_rate: float
    file: FileCost | None


@dataclass(frozen=True)
class FileCost:
    """A real tuckercodec file encoded at a KG target (ranks chosen by the exact table)."""

    ranks: tuple[int, int]
    kg: float  # decoded
    total_bytes: int
    bpfv: float
    raw_share: float  # bytes / raw float32 positions: the real "share of the original size"
    seconds: float
    sted: float | str | None = None  # of the decoded file, when asked for (str: undefined)


@dataclass(frozen=True)
class RateRow:
    """Claim (c): the exact front's best truncation within Θ <= a given rate."""

    theta: float
    ranks: tuple[int, int]
    floats: int
    rate: float
    kg: float
    #: the same reconstruction, KG with each vertex's temporal mean (the paper's formula)
    kg_temporal: float
    sted: float | str  # str: why STED is undefined here (a point cloud has no edges)
    file: FileCost | None


def pca_cheapest(pca: Curve, target: float) -> int:
    """Index of the smallest PCA rank whose error is at most ``target`` (its error falls with r)."""
    return int(np.argmax(pca.kg <= target))


def file_cost(
    sequence: MeshSequence, analysis: Analysis, target: float, *, with_sted: bool = False
) -> FileCost:
    """Encode for real at ``target`` and measure the file (and, if asked, STED once decoded:
    quantization noise is rough in space, which STED weighs more than KG does)."""
    result = encode_with_report(sequence, target_kg=target, analysis=analysis)
    report = result.report
    file_sted = sted_of(sequence, decode(result.data)) if with_sted else None
    return FileCost(
        report.ranks,
        report.kg,
        report.total_bytes,
        report.bpfv,
        report.total_bytes / report.raw_float32_bytes,
        report.seconds,
        file_sted,
    )


def target_rows(
    sequence: MeshSequence, analysis: Analysis, targets: Sequence[float], encode: bool
) -> list[TargetRow]:
    """For each target: cheapest ranks by the exact table and by the bound, cheapest PCA rank,
    and (with ``encode``) the real file."""
    pca = analysis.pca_curve()
    rows = []
    for target in targets:
        exact = analysis.cheapest(target)
        bound = analysis.cheapest(target, select="bound")
        p = pca_cheapest(pca, target)
        rows.append(
            TargetRow(
                target,
                (exact.i, exact.k),
                exact.floats,
                exact.rate,
                exact.kg,
                exact.kg_bound,
                (bound.i, bound.k),
                bound.floats,
                bound.kg,
                int(pca.i[p]),
                int(pca.floats[p]),
                float(pca.rate[p]),
                file_cost(sequence, analysis, target) if encode else None,
            )
        )
    return rows


def reconstruction(sequence: MeshSequence, analysis: Analysis, i: int, k: int) -> MeshSequence:
    """The truncation (i, 3, k) rebuilt as positions, centroids added back (unquantized)."""
    tensor = reconstruct(*analysis.truncate(i, k))  # (K, 3, F)
    vertices = tensor.transpose(2, 0, 1) + analysis.centroids[:, None, :]
    return MeshSequence(vertices=vertices, faces=sequence.faces)


def sted_of(original: MeshSequence, approx: MeshSequence) -> float | str:
    """STED with its default parameters, or why it is undefined for this sequence (no faces,
    a first frame of zero extent)."""
    try:
        return sted(original, approx).value
    except InputError as error:
        return f"n/a ({error})"


def rate_rows(
    sequence: MeshSequence, analysis: Analysis, front: Curve, encode: bool
) -> list[RateRow]:
    """Claim (c) at each Θ of RATE_POINTS: best front point within budget, its errors, the file."""
    rows = []
    for theta in RATE_POINTS:
        within = np.flatnonzero(front.rate <= theta)
        if within.size == 0:
            continue
        n = int(within[-1])  # the front is ordered by rate, its error falling
        i, k = int(front.i[n]), int(front.k[n])
        approx = reconstruction(sequence, analysis, i, k)
        rows.append(
            RateRow(
                theta,
                (i, k),
                int(front.floats[n]),
                float(front.rate[n]),
                float(front.kg[n]),
                kg_error(sequence, approx, mean="temporal"),
                sted_of(sequence, approx),
                file_cost(sequence, analysis, float(front.kg[n]), with_sted=True)
                if encode
                else None,
            )
        )
    return rows


@dataclass
class Result:
    """Everything measured on one sequence."""

    name: str
    source: str
    frames: int
    vertices: int
    max_ranks: tuple[int, int]
    seconds_analyze: float
    all_boxes: list[Box]
    front_boxes: list[Box]
    beyond_one: int  # truncations with Θ > 1, outside the windows
    diagonal: dict[str, list[DiagonalWindow]]
    #: median distance of the exact front (Θ <= 1) from each reading of the diagonal
    front_distance: dict[str, float]
    targets: list[TargetRow]
    rates: list[RateRow]
    figures: list[str] = field(default_factory=list)
    seconds_total: float = 0.0


# ------------------------------------------------------------------------------------------
# figures (Fig. 1 is the package's plot_rd_curve; Fig. 2 and 3 are drawn only here)


def draw_fig2(
    path: Path, name: str, all_boxes: list[Box], front_boxes: list[Box], force: bool
) -> None:
    """ψ box plots per Θ window; whiskers are min and max, like the printed table."""
    plt = internal.pyplot()
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.5), sharey=True)
    for ax, rows, label in (
        (axes[0], all_boxes, "every truncation (i, 3, k)"),
        (axes[1], front_boxes, "exact rate-distortion front"),
    ):
        stats = [
            {
                "whislo": max(b.quantiles[0], PSI_FLOOR),
                "q1": max(b.quantiles[1], PSI_FLOOR),
                "med": max(b.quantiles[2], PSI_FLOOR),
                "q3": max(b.quantiles[3], PSI_FLOOR),
                "whishi": max(b.quantiles[4], PSI_FLOOR),
                "label": f"{b.low:.1f}–{b.high:.1f}\n({b.count})",
            }
            for b in rows
            if b.count
        ]
        if stats:
            ax.bxp(stats, showfliers=False)
        ax.set_yscale("log")
        ax.set_xlabel("Θ window (points)")
        ax.set_title(label)
        ax.tick_params(axis="x", labelsize=7)
        ax.grid(True, axis="y", which="major", alpha=0.3)
    axes[0].set_ylabel(f"ψ = KG bound − KG exact (floored at {PSI_FLOOR:g})")
    fig.suptitle(f"{name}: ψ against reduction rate (paper's Fig. 2)")
    fig.tight_layout()
    internal.save_figure(fig, path, dpi=110, overwrite=force)


def draw_fig3(path: Path, name: str, analysis: Analysis, front: Curve, force: bool) -> None:
    """log10 KG and log10 ψ over (i, k), with i = k, i/R1 = k/R3 and the exact front on top."""
    plt = internal.pyplot()
    r1, r3 = analysis.max_ranks
    kg = analysis.kg_table()[1:, 1:]
    psi = analysis.psi_table()[1:, 1:]
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.8))
    keep = front.rate <= 1.0
    for ax, values, label in ((axes[0], kg, "log10 KG (exact)"), (axes[1], psi, "log10 ψ")):
        logged = np.log10(np.maximum(values, PSI_FLOOR))
        image = ax.imshow(
            logged.T,
            origin="lower",
            aspect="auto",
            cmap="viridis",
            extent=(0.5, r1 + 0.5, 0.5, r3 + 0.5),
            vmin=np.percentile(logged, 1),
        )
        top = min(r1, r3)
        ax.plot([1, top], [1, top], "w--", lw=1, label="i = k")
        ax.plot([1, r1], [r3 / r1, r3], "w:", lw=1.4, label="i/R1 = k/R3")
        # Points, not a line: consecutive front points jump back and forth in k.
        ax.plot(front.i[keep], front.k[keep], "r.", ms=1.5, label="exact front (Θ ≤ 1)")
        ax.set_xlim(0.5, r1 + 0.5)
        ax.set_ylim(0.5, r3 + 0.5)
        ax.set_xlabel("mode-1 rank i (vertices)")
        ax.set_ylabel("mode-3 rank k (frames)")
        ax.set_title(label)
        fig.colorbar(image, ax=ax)
    axes[1].legend(loc="upper right", fontsize=7, framealpha=0.6)
    fig.suptitle(f"{name}: error and ψ over the ranks (paper's Fig. 3)")
    fig.tight_layout()
    internal.save_figure(fig, path, dpi=110, overwrite=force)


# ------------------------------------------------------------------------------------------
# the summary


def _g(value: float | None, digits: int = 6) -> str:
    if value is None:
        return "n/a"
    return f"{value:.{digits}g}" if np.isfinite(value) else "–"


def _box_table(rows: list[Box]) -> list[str]:
    lines = [
        "| Θ window | points | min ψ | q1 | median ψ | q3 | max ψ | median bound/exact "
        "| median KG exact |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for b in rows:
        q = " | ".join(_g(v) for v in b.quantiles)
        lines.append(
            f"| {b.low:.1f}–{b.high:.1f} | {b.count} | {q} | {_g(b.ratio)} | {_g(b.kg, 4)} |"
        )
    return lines


def _sted_cell(value: float | str | None) -> str:
    return value if isinstance(value, str) else _g(value, 4)


def _file_cells(cost: FileCost | None) -> str:
    if cost is None:
        return "not encoded | | | "
    return (
        f"({cost.ranks[0]}, {cost.ranks[1]}) KG {_g(cost.kg, 4)} | {cost.total_bytes} | "
        f"{cost.bpfv:.4f} | {100 * cost.raw_share:.3f} %"
    )


def summary_section(r: Result) -> list[str]:
    """The markdown of one sequence."""
    lines = [
        f"## {r.name}",
        "",
        (
            f"Source `{r.source}`: F = {r.frames} frames, K = {r.vertices} vertices; "
            f"ranks 1..{r.max_ranks[0]} × 1..{r.max_ranks[1]}; analyze {r.seconds_analyze:.2f} s, "
            f"whole sequence {r.seconds_total:.2f} s."
        ),
        "",
        "Figures: " + ", ".join(f"[{f}]({f})" for f in r.figures),
        "",
        f"### Fig. 2: ψ by Θ window, every truncation ({r.beyond_one} with Θ > 1 left out)",
        "",
        *_box_table(r.all_boxes),
        "",
        "### Fig. 2: ψ by Θ window, along the exact rate-distortion front",
        "",
        *_box_table(r.front_boxes),
        "",
        "### (a) Is the estimator saturated? Bound's choice against the exact choice",
        "",
        (
            "| target KG | exact (i, k) | S exact | KG exact | bound there | bound/exact | ψ there "
            "| bound's (i, k) | S bound | KG of bound's choice | extra floats |"
        ),
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for t in r.targets:
        extra = 100.0 * (t.bound_floats - t.exact_floats) / t.exact_floats
        lines.append(
            f"| {_g(t.target)} | ({t.exact[0]}, {t.exact[1]}) | {t.exact_floats} | "
            f"{_g(t.exact_kg)} | {_g(t.exact_kg_bound)} | {_g(t.exact_kg_bound / t.exact_kg)} | "
            f"{_g(t.exact_kg_bound - t.exact_kg)} | ({t.bound[0]}, {t.bound[1]}) | "
            f"{t.bound_floats} | {_g(t.bound_kg)} | {extra:+.3f} % |"
        )
    lines += [
        "",
        (
            f"### (b) Is ψ small near the diagonal? Per Θ window: nearest {NEAR_SHARE:.0%} of "
            f"the window's truncations against the farthest {FAR_SHARE:.0%}"
        ),
        "",
    ]
    for reading, rows in r.diagonal.items():
        unit = "|i − k| in ranks" if reading == "raw" else "|i/R1 − k/R3|"
        smaller = sum(w.psi_near < w.psi_far for w in rows)
        lines += [
            (
                f"Reading `{reading}` (distance {unit}): median ψ is smaller near the diagonal in "
                f"{smaller} of {len(rows)} windows; the exact front (Θ ≤ 1) lies at median "
                f"distance {_g(r.front_distance[reading], 4)}."
            ),
            "",
            (
                "| Θ window | near: distance ≤ | far: distance ≥ | median ψ near | median ψ far "
                "| median bound/exact near | far |"
            ),
            "|---|---|---|---|---|---|---|",
        ]
        lines += [
            f"| {w.low:.1f}–{w.high:.1f} | {_g(w.near_distance, 4)} | {_g(w.far_distance, 4)} | "
            f"{_g(w.psi_near)} | {_g(w.psi_far)} | {_g(w.ratio_near)} | {_g(w.ratio_far)} |"
            for w in rows
        ]
        lines.append("")
    lines += [
        "### (c) What do Θ = 0.05 and 0.10 buy? Best exact-front truncation within the rate",
        "",
        (
            "| Θ budget | (i, k) | S | Θ | KG exact | KG temporal-mean variant | STED "
            "| tuckercodec file at that KG | bytes | bpfv | file / raw float32 | STED of the file |"
        ),
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for row in r.rates:
        file_sted = _sted_cell(row.file.sted) if row.file is not None else ""
        lines.append(
            f"| {row.theta:.2f} | ({row.ranks[0]}, {row.ranks[1]}) | {row.floats} | "
            f"{_g(row.rate, 4)} | {_g(row.kg)} | {_g(row.kg_temporal)} | {_sted_cell(row.sted)} | "
            f"{_file_cells(row.file)} | {file_sted} |"
        )
    lines += [
        "",
        "### (d) Does HOSVD beat PCA? Cheapest of each at the KG targets",
        "",
        (
            "| target KG | HOSVD (i, k) | S HOSVD | Θ HOSVD | PCA rank | S PCA | Θ PCA "
            "| PCA / HOSVD floats | tuckercodec file | bytes | bpfv | file / raw float32 |"
        ),
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for t in r.targets:
        lines.append(
            f"| {_g(t.target)} | ({t.exact[0]}, {t.exact[1]}) | {t.exact_floats} | "
            f"{_g(t.exact_rate, 4)} | {t.pca_rank} | {t.pca_floats} | {_g(t.pca_rate, 4)} | "
            f"{t.pca_floats / t.exact_floats:.3f} | {_file_cells(t.file)} |"
        )
    lines.append("")
    return lines


def summary(results: list[Result], command: str, seconds: float, encode: bool) -> str:
    """The whole markdown summary."""
    lines = [
        "# The seed paper's experiments (Romaszewski and Głomb 2016), reproduced",
        "",
        f"- date: {datetime.date.today().isoformat()}",
        f"- machine: {common.machine()}",
        f"- command: `{command}`",
        f"- total time: {seconds:.1f} s"
        + ("" if encode else " (no real files encoded: --no-encode)"),
        f"- errors: {KG_DEFINITION}, in percent, unless a column says otherwise;",
        "  ψ = the paper's bound (discarded mode-1 plus mode-3 energy) minus the exact KG error.",
        "- rates: Θ = S / (3KF), S = i·K + 9 + k·F + 3·i·k floats (PCA: r·(3K + F)); "
        "files are real",
        "  tuckercodec files (exact ranks, quantized, connectivity included), raw float32 = "
        "12·K·F bytes.",
        f"- STED: {STED_DEFINITION}",
        "",
    ]
    for result in results:
        lines += summary_section(result)
    return "\n".join(lines)


# ------------------------------------------------------------------------------------------
# driving


def measure(
    name: str,
    source: str,
    sequence: MeshSequence,
    out: Path,
    force: bool,
    encode: bool,
    targets: Sequence[float],
) -> Result:
    """Analyse one sequence, draw its three figures and collect its tables."""
    start = time.perf_counter()
    analysis = analyze(sequence)
    seconds_analyze = time.perf_counter() - start
    front = analysis.rd_curve()
    table = all_truncations(analysis)
    front_table = {
        "rate": front.rate,
        "kg": front.kg,
        "kg_bound": front.kg_bound,
        "psi": front.kg_bound - front.kg,
    }
    kept = front.rate <= 1.0
    front_distance = {
        reading: float(np.median(d))
        for reading, d in distances(analysis, front.i[kept], front.k[kept]).items()
    }
    result = Result(
        name=name,
        source=source,
        frames=sequence.frame_count,
        vertices=sequence.vertex_count,
        max_ranks=analysis.max_ranks,
        seconds_analyze=seconds_analyze,
        all_boxes=boxes(table["rate"], table["psi"], table["kg"], table["kg_bound"]),
        front_boxes=boxes(
            front_table["rate"], front_table["psi"], front_table["kg"], front_table["kg_bound"]
        ),
        beyond_one=int((table["rate"] > 1.0).sum()),
        diagonal=diagonal_study(analysis, table),
        front_distance=front_distance,
        targets=target_rows(sequence, analysis, targets, encode),
        rates=rate_rows(sequence, analysis, front, encode),
    )
    names = output_names(name)
    # Fig. 1 exactly as `tuckercodec rd --plot` draws it.
    plot_rd_curve(
        analysis, out / names[0], title=f"{name}: rate-distortion (paper's Fig. 1)", overwrite=force
    )
    draw_fig2(out / names[1], name, result.all_boxes, result.front_boxes, force)
    draw_fig3(out / names[2], name, analysis, front, force)
    result.figures = list(names)
    result.seconds_total = time.perf_counter() - start
    return result


def output_names(name: str) -> tuple[str, str, str]:
    """The three PNG names of one sequence."""
    return f"{name}-fig1-rd.png", f"{name}-fig2-psi.png", f"{name}-fig3-heatmaps.png"


def sources(given: list[str]) -> list[tuple[str, str | Path]]:
    """(name, source) for each sequence to run; absent defaults are skipped with a message."""
    if not given:
        present, absent = common.in_shared_data(DEFAULT_SEQUENCES)
        for path in absent:
            print(f"skipping {path.name}: {path} is absent", file=sys.stderr)
        return [(path.stem, path) for path in present]
    out: list[tuple[str, str | Path]] = []
    taken: set[str] = set()
    for item in given:
        stem = common.SAMPLE if item == common.SAMPLE else Path(item.rstrip("/")).stem
        # File-name safe (a glob's stem is "*"), so figure names are plain.
        name = re.sub(r"[^A-Za-z0-9._-]+", "_", stem).strip("_") or "sequence"
        # two inputs with one stem must not share figure names
        out.append((common.unique_name(name, taken), item))
    return out


def parse_targets(text: str) -> list[float]:
    """Comma-separated positive KG targets."""
    try:
        values = [float(v) for v in text.split(",") if v.strip()]
    except ValueError as error:
        raise argparse.ArgumentTypeError(
            f"targets must be numbers separated by commas: {text!r}"
        ) from error
    if not values or any(not (np.isfinite(v) and v > 0) for v in values):
        raise argparse.ArgumentTypeError(f"targets must be positive numbers: {text!r}")
    return values


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m tools.paper", description=__doc__.splitlines()[0]
    )
    parser.add_argument(
        "sequences",
        nargs="*",
        help="npz files, OBJ folders or 'sample' (default: chicken and samba of ../shared/data)",
    )
    parser.add_argument(
        "--out", type=Path, default=DEFAULT_OUT, help="output folder (default results/paper/)"
    )
    parser.add_argument("--force", action="store_true", help="replace existing outputs")
    parser.add_argument(
        "--targets",
        type=parse_targets,
        default=list(KG_TARGETS),
        help="KG targets of claims (a) and (d), comma-separated (default 1,0.5,0.1,0.05)",
    )
    parser.add_argument("--no-encode", action="store_true", help="skip the real tuckercodec files")
    args = parser.parse_args(argv)
    command = common.command("tools.paper", argv)

    todo = sources(args.sequences)
    if not todo:
        print(f"no sequences given and none found in {common.SHARED_DATA}", file=sys.stderr)
        return 2
    out: Path = args.out
    outputs = [out / "summary.md"] + [out / f for name, _ in todo for f in output_names(name)]
    try:
        out.mkdir(parents=True, exist_ok=True)
        refuse_existing(outputs, args.force)  # before any work: never half a results folder
    except OSError as error:
        print(f"error: {error}", file=sys.stderr)
        return 1

    start = time.perf_counter()
    results = []
    for name, source in todo:
        print(f"{name}: reading {source}", flush=True)
        try:
            sequence = common.load(source)
            results.append(
                measure(
                    name, str(source), sequence, out, args.force, not args.no_encode, args.targets
                )
            )
        except TuckerCodecError as error:  # unreadable input, or one analyze refuses (one frame)
            print(f"error: {error}", file=sys.stderr)
            return 4
        print(f"{name}: done in {results[-1].seconds_total:.1f} s", flush=True)
    seconds = time.perf_counter() - start
    text = summary(results, command, seconds, not args.no_encode)
    common.write_text(out / "summary.md", text, args.force)
    print(f"wrote {out / 'summary.md'} and {3 * len(results)} figures in {seconds:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
