"""Figures, drawn with matplotlib (the optional ``plot`` extra).

The seed paper's:

* :func:`plot_rd_curve`: its Fig. 1, reduction rate Theta against log KG error for the exact
  HOSVD curve, the curve the estimate would choose, and the PCA reference.
* :func:`plot_heatmaps`: its Fig. 3, log10 KG error and log10 psi over the ranks (i, k).

And pictures of one comparison:

* :func:`plot_frame_errors`: each frame's share of the KG error and its worst vertex, over time.
* :func:`render_frame`: one frame of a mesh in 3D, shaded, or coloured by per-vertex error.
"""

from __future__ import annotations

from pathlib import Path
from types import ModuleType
from typing import TYPE_CHECKING, Any

import numpy as np

from ..decomposition.analysis import Analysis
from ..errors import DependencyError
from ..system.atomic import write_atomic

if TYPE_CHECKING:
    from matplotlib.figure import Figure


def pyplot() -> ModuleType:
    """matplotlib.pyplot on the Agg backend, or a DependencyError naming the extra."""
    try:
        import matplotlib

        matplotlib.use("Agg")  # files only; never needs a display
        import matplotlib.pyplot as plt
    except ImportError as error:  # a test hides matplotlib to see this
        raise DependencyError("plots need matplotlib: pip install 'tuckercodec[plot]'") from error
    return plt


def save_figure(fig: Figure, path: str | Path, *, overwrite: bool, dpi: int = 120) -> None:
    """Write ``fig`` to ``path`` (the format from its suffix) atomically, then close it."""
    plt = pyplot()
    suffix = Path(path).suffix.lstrip(".").lower() or "png"
    try:
        write_atomic(
            path, lambda handle: fig.savefig(handle, format=suffix, dpi=dpi), overwrite=overwrite
        )
    finally:
        plt.close(fig)


def plot_rd_curve(
    analysis: Analysis, path: str | Path, *, title: str = "", overwrite: bool = False
) -> None:
    """Draw Theta against KG error (log scale): exact front, estimate's front, PCA."""
    plt = pyplot()
    exact = analysis.rd_curve()
    estimated = analysis.rd_curve(select="bound")
    pca = analysis.pca_curve()
    fig, ax = plt.subplots(figsize=(7, 4.5))
    ax.plot(exact.kg, exact.rate, "-", lw=1.6, label="HOSVD, exact error (this codec)")
    ax.plot(
        estimated.kg_bound,
        estimated.rate,
        "--",
        lw=1.2,
        label="HOSVD, estimated error (paper's bound)",
    )
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
    save_figure(fig, path, overwrite=overwrite)


def plot_heatmaps(
    analysis: Analysis, path: str | Path, *, title: str = "", overwrite: bool = False
) -> None:
    """Draw log10 KG error and log10 psi over the mode-1 rank i and the mode-3 rank k."""
    plt = pyplot()
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
    save_figure(fig, path, overwrite=overwrite)


def plot_frame_errors(
    frame_kg: np.ndarray,
    worst_vertex: np.ndarray,
    path: str | Path,
    *,
    title: str = "",
    overwrite: bool = False,
) -> None:
    """Draw two panels over the frame number: each frame's share of the KG error
    (:func:`tuckercodec.measures.distortion.per_frame_kg`) and its largest vertex displacement in
    scene units (:func:`tuckercodec.measures.distortion.per_frame_max_displacement`)."""
    frame_kg = np.asarray(frame_kg, dtype=np.float64)
    worst_vertex = np.asarray(worst_vertex, dtype=np.float64)
    if frame_kg.ndim != 1 or frame_kg.shape != worst_vertex.shape or frame_kg.size == 0:
        raise ValueError(
            f"expected two equal, non-empty series of per-frame values, got {frame_kg.shape} "
            f"and {worst_vertex.shape}"
        )
    plt = pyplot()
    frames = np.arange(frame_kg.size)
    style = "-" if frame_kg.size > 1 else "o"  # a single frame would draw no line at all
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(8, 6), sharex=True)
    panels = [
        (
            top,
            frame_kg,
            "C0",
            "KG share of frame, %",
            "each frame's share of the KG error: 100·‖A_f − B_f‖ / ‖A − E(A)‖, squares sum to KG²",
        ),
        (
            bottom,
            worst_vertex,
            "C3",
            "worst vertex, scene units",
            "worst vertex: largest displacement ‖a_fk − b_fk‖ over the vertices k of frame f",
        ),
    ]
    for ax, values, colour, label, meaning in panels:
        ax.plot(frames, values, style, color=colour, lw=1.2)
        worst = int(np.argmax(values))
        ax.plot([worst], [values[worst]], "o", color=colour, ms=5)
        right = worst > 0.7 * max(frames[-1], 1)  # keep the label inside the panel
        ax.annotate(
            f"max {values[worst]:.4g} at frame {worst}",
            (worst, values[worst]),
            textcoords="offset points",
            xytext=(-6 if right else 6, 4),
            fontsize=8,
            ha="right" if right else "left",
        )
        ax.set_ylabel(label)
        ax.set_title(meaning, fontsize=9)
        ax.set_ylim(0, 1.15 * values.max() if values.max() > 0 else 1.0)
        ax.grid(True, alpha=0.3)
    bottom.set_xlabel("frame")
    fig.suptitle(title or f"Error over time, {frame_kg.size} frames")
    fig.tight_layout()
    save_figure(fig, path, overwrite=overwrite)


#: Where each up axis goes: plot coordinates (x, y, z) as a rotation of the scene's, so that
#: ``up`` points up the picture and matplotlib's default camera looks at the scene's front.
_UP_AXES = {
    "x": ((1, 1.0), (2, 1.0), (0, 1.0)),
    "y": ((0, 1.0), (2, -1.0), (1, 1.0)),
    "z": ((0, 1.0), (1, 1.0), (2, 1.0)),
}


def render_frame(
    vertices: np.ndarray,
    triangles: np.ndarray,
    path: str | Path,
    *,
    errors: np.ndarray | None = None,
    title: str = "",
    up: str = "y",
    overwrite: bool = False,
) -> None:
    """Draw one frame, (K, 3) positions and (T, 3) triangles, with equal scaling on every axis.

    Without ``errors`` the faces are shaded by their angle to a light beside the camera. With
    ``errors`` (K values, in scene units), each face takes the colour of the mean of its corners'
    errors, unshaded so that the colour reads true against the colour bar. A mesh without
    faces is drawn as points. ``up`` names the scene axis drawn upwards.
    """
    vertices, triangles, errors = _checked_frame(vertices, triangles, errors, up)
    plt = pyplot()
    from matplotlib import colormaps
    from matplotlib.colors import Normalize
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    axes = _UP_AXES[up]
    points = np.stack([sign * vertices[:, axis] for axis, sign in axes], axis=1)
    names = [("−" if sign < 0 else "") + "xyz"[axis] for axis, sign in axes]

    fig = plt.figure(figsize=(7, 7))
    ax = fig.add_subplot(projection="3d")
    ax.view_init(elev=15, azim=-60)
    norm = Normalize(
        vmin=0.0, vmax=float(errors.max()) if errors is not None and errors.max() > 0 else 1.0
    )
    cmap = colormaps["viridis"]
    if len(triangles):
        corners = points[triangles]  # (T, 3, 3)
        if errors is not None:
            colours = cmap(norm(errors[triangles].mean(axis=1)))
        else:
            colours = _shaded(corners, _camera_direction(ax))
        ax.add_collection3d(
            Poly3DCollection(corners, facecolors=colours, edgecolors="none", linewidths=0)
        )
    else:
        colour = cmap(norm(errors)) if errors is not None else "C0"
        ax.scatter(points[:, 0], points[:, 1], points[:, 2], c=colour, s=2, depthshade=False)
    if errors is not None:
        from matplotlib.cm import ScalarMappable

        mappable = ScalarMappable(norm=norm, cmap=cmap)
        bar = fig.colorbar(mappable, ax=ax, shrink=0.6, pad=0.1)  # clear of the axis labels
        bar.set_label("vertex error ‖SEQ − REFERENCE‖, scene units (face: mean of its corners)")
    _scale_equally(ax, points, names)
    ax.set_title(title or f"{vertices.shape[0]} vertices, {len(triangles)} triangles")
    save_figure(fig, path, overwrite=overwrite)


def _checked_frame(
    vertices: np.ndarray, triangles: np.ndarray, errors: np.ndarray | None, up: str
) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """render_frame's arguments as float64 (K, 3), int64 (T, 3) and float64 (K,) arrays, or
    a ValueError naming the one that does not fit."""
    vertices = np.asarray(vertices, dtype=np.float64)
    triangles = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    if vertices.ndim != 2 or vertices.shape[1] != 3 or vertices.shape[0] == 0:
        raise ValueError(f"expected positions of shape (vertices, 3), got {vertices.shape}")
    if errors is not None:
        errors = np.asarray(errors, dtype=np.float64)
        if errors.shape != (vertices.shape[0],):
            raise ValueError(f"expected {vertices.shape[0]} per-vertex errors, got {errors.shape}")
    if up not in _UP_AXES:
        raise ValueError(f"up must be one of {', '.join(_UP_AXES)}, got {up!r}")
    return vertices, triangles, errors


def _shaded(corners: np.ndarray, camera: np.ndarray) -> np.ndarray:
    """(T, 4) RGBA colours of the faces ``corners`` (T, 3, 3), lit by a light beside the
    ``camera`` direction (a unit vector towards it, in plot coordinates)."""
    normal = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    size = np.linalg.norm(normal, axis=1, keepdims=True)
    normal = np.divide(normal, size, out=np.zeros_like(normal), where=size > 0)
    light = camera + np.array([0.3, 0.0, 0.5])
    light /= np.linalg.norm(light)
    # Two-sided: a face turned away still shows, as the far side of a thin sheet would.
    intensity = 0.3 + 0.7 * np.abs(normal @ light)
    colours = np.empty((len(corners), 4))
    colours[:, :3] = intensity[:, None] * np.array([0.70, 0.75, 0.85])
    colours[:, 3] = 1.0
    return colours


def _scale_equally(ax: Any, points: np.ndarray, names: list[str]) -> None:
    """Equal scaling: every axis spans its own extent, and the box's sides are in proportion;
    a thin side gets one tick, at its middle. ``names`` label the axes."""
    low, high = points.min(axis=0), points.max(axis=0)
    extent = np.maximum(high - low, 0.02 * max(float((high - low).max()), 1e-12))
    centre = (low + high) / 2
    ax.set_xlim(centre[0] - extent[0] / 2, centre[0] + extent[0] / 2)
    ax.set_ylim(centre[1] - extent[1] / 2, centre[1] + extent[1] / 2)
    ax.set_zlim(centre[2] - extent[2] / 2, centre[2] + extent[2] / 2)
    ax.set_box_aspect(tuple(extent))
    ax.locator_params(nbins=4)  # fewer ticks: short axes would crowd their labels
    setters = (ax.set_xticks, ax.set_yticks, ax.set_zticks)
    for axis, setter in enumerate(setters):
        if extent[axis] < 0.15 * extent.max():  # a thin side: one tick, at its middle
            setter([centre[axis]], labels=[f"{centre[axis]:.3g}"])
    ax.set_xlabel(names[0])
    ax.set_ylabel(names[1])
    ax.set_zlabel(names[2])


def _camera_direction(ax: Any) -> np.ndarray:
    """A unit vector from the scene towards matplotlib's camera, in plot coordinates."""
    elev, azim = np.radians(ax.elev), np.radians(ax.azim)
    return np.array([np.cos(elev) * np.cos(azim), np.cos(elev) * np.sin(azim), np.sin(elev)])
