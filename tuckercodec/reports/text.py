"""Text and CSV renderings of an analysis, and of the worst vertex, shared by the command line
and the tools."""

from __future__ import annotations

import csv
import io
from collections.abc import Sequence

import numpy as np

from ..decomposition.analysis import SELECTIONS, Analysis, Curve

DEFAULT_TARGETS = (1.0, 0.5, 0.1, 0.05, 0.02)


def worst_vertex(distance: float, at: tuple[int, int] | None) -> str:
    """A worst vertex as every command prints it: ``0.00123457 at frame 6, vertex 11`` (the
    distance in the sequence's units,
    :data:`tuckercodec.measures.distortion.MAX_DISTANCE_DEFINITION`; the frame as the file numbers
    it). ``at`` None: a distance whose place is not known."""
    where = "" if at is None else f" at frame {at[0]}, vertex {at[1]}"
    return f"{distance:.6g}{where}"


def targets_table(analysis: Analysis, targets: Sequence[float] = DEFAULT_TARGETS) -> str:
    """For each target KG error: the ranks the exact table picks and those the bound picks."""
    header = (
        f"{'target KG':>9}  {'select':>6}  {'i':>4}  {'k':>4}  {'floats S':>10}  "
        f"{'rate Θ':>8}  {'exact KG':>9}  {'est. KG':>9}"
    )
    lines = [header, "-" * len(header)]
    for target in targets:
        for select in SELECTIONS:
            try:
                c = analysis.cheapest(target, select=select)
            except ValueError:
                lines.append(f"{target:>9g}  {select:>6}  {'unreachable':>40}")
                continue
            lines.append(
                f"{target:>9g}  {select:>6}  {c.i:>4}  {c.k:>4}  {c.floats:>10}  "
                f"{c.rate:>8.5f}  {c.kg:>9.5f}  {c.kg_bound:>9.5f}"
            )
    return "\n".join(lines)


def curves_csv(analysis: Analysis) -> str:
    """The whole rate-distortion curves as CSV: the exact HOSVD front, the front the bound would
    choose, and the PCA reference, one row per point, with a ``curve`` column naming which."""
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(["curve", "i", "k", "floats", "rate", "kg_exact", "kg_estimate", "psi"])

    def rows(name: str, curve: Curve) -> None:
        for n in range(len(curve)):
            estimate = curve.kg_bound[n]
            psi = estimate - curve.kg[n] if np.isfinite(estimate) else float("nan")
            writer.writerow(
                [
                    name,
                    int(curve.i[n]),
                    int(curve.k[n]),
                    int(curve.floats[n]),
                    f"{curve.rate[n]:.8g}",
                    f"{curve.kg[n]:.10g}",
                    "" if not np.isfinite(estimate) else f"{estimate:.10g}",
                    "" if not np.isfinite(psi) else f"{psi:.10g}",
                ]
            )

    rows("hosvd_exact", analysis.rd_curve())
    rows("hosvd_bound", analysis.rd_curve(select="bound"))
    rows("pca", analysis.pca_curve())
    return out.getvalue()
