"""The seed paper's figures, drawn with matplotlib (the optional ``plot`` extra).

* :func:`plot_rd_curve`: its Fig. 1, reduction rate Theta against log KG error for the exact
  HOSVD curve, the curve the estimate would choose, and the PCA reference.
* :func:`plot_heatmaps`: its Fig. 3, log10 KG error and log10 psi over the ranks (i, k).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .analysis import Analysis
from .atomic import write_atomic
from .errors import DependencyError


def _pyplot():
    try:
        import matplotlib

        matplotlib.use("Agg")  # files only; never needs a display
        import matplotlib.pyplot as plt
    except ImportError as error:  # pragma: no cover - depends on the environment
        raise DependencyError(
            "plots need matplotlib: pip install 'tuckercodec[plot]'"
        ) from error
    return plt


def _save(fig, path: str | Path, overwrite: bool) -> None:
    plt = _pyplot()
    suffix = Path(path).suffix.lstrip(".").lower() or "png"
    try:
        write_atomic(path, lambda handle: fig.savefig(handle, format=suffix, dpi=120), overwrite=overwrite)
    finally:
        plt.close(fig)


def plot_rd_curve(analysis: Analysis, path: str | Path, *, title: str = "", overwrite: bool = False) -> None:
    """Draw Theta against KG error (log scale): exact front, estimate's front, PCA."""
    plt = _pyplot()
    exact = analysis.rd_curve()
    estimated = analysis.rd_curve(select="bound")
    pca = analysis.pca_curve()
    fig, ax = plt.subplots(figsize=(7, 4.5))
    ax.plot(exact.kg, exact.rate, "-", lw=1.6, label="HOSVD, exact error (this codec)")
    ax.plot(estimated.kg_bound, estimated.rate, "--", lw=1.2, label="HOSVD, estimated error (paper's bound)")
    ax.plot(pca.kg, pca.rate, ":", lw=1.6, label="PCA of frames (paper's section 2.4)")
    ax.set_xscale("log")
    ax.set_xlabel("KG error, % (Karni-Gotsman, per-frame centroid)")
    ax.set_ylabel("reduction rate Θ = S / (3KF)")
    # Show the useful part of the curve: rates up to where the exact error reaches 0.001 %.
    useful = exact.rate[exact.kg >= 1e-3]
    ax.set_ylim(0, min(1.0, 1.1 * (useful.max() if useful.size else exact.rate.max())))
    ax.set_xlim(left=max(1e-3, 0.5 * float(exact.kg.min(initial=1e-3))))
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    ax.set_title(title or f"Rate-distortion, K={analysis.vertex_count}, F={analysis.frame_count}")
    fig.tight_layout()
    _save(fig, path, overwrite)


def plot_heatmaps(analysis: Analysis, path: str | Path, *, title: str = "", overwrite: bool = False) -> None:
    """Draw log10 KG error and log10 psi over the mode-1 rank i and the mode-3 rank k."""
    plt = _pyplot()
    kg = analysis.kg_table()[1:, 1:]
    psi = analysis.psi_table()[1:, 1:]
    floor = np.finfo(float).tiny
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.5))
    panels = [
        (axes[0], np.log10(np.maximum(kg, floor)), "log10 KG error (exact)"),
        (axes[1], np.log10(np.maximum(psi, floor)), "log10 ψ = KG estimate − KG exact"),
    ]
    r1, r3 = kg.shape
    for ax, values, label in panels:
        finite = values[values > np.log10(floor)]
        low = np.percentile(finite, 1) if finite.size else 0.0
        image = ax.imshow(
            values.T,
            origin="lower",
            aspect="auto",
            extent=(0.5, r1 + 0.5, 0.5, r3 + 0.5),
            vmin=low,
            cmap="viridis",
        )
        ax.set_xlabel("mode-1 rank i (vertices)")
        ax.set_ylabel("mode-3 rank k (frames)")
        ax.set_title(label)
        fig.colorbar(image, ax=ax)
    fig.suptitle(title or f"K={analysis.vertex_count}, F={analysis.frame_count}")
    fig.tight_layout()
    _save(fig, path, overwrite)
