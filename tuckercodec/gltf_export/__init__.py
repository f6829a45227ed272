"""A compressed file's decomposition as a glTF morph animation that viewers play unaided.

Frame f of a file is ``c_f + Σ_b U3[f, b] · B_b`` with the basis shapes
``B_b = U1 · B[:, :, b]`` (K x 3, ``B[a, x, b] = Σ_c CORE[a, c, b] · U2[x, c]``, spec §8). The
glTF holds the same sum as a viewer evaluates it:

* the weights are U3's columns rescaled into 0..1, ``w_fb = (U3[f, b] - lo_b) / (hi_b - lo_b)``
  over the frames written, so that tools which store weights as normalized 8- or 16-bit
  integers (gltfpack does) keep them; the offsets go into the mesh,
  ``base = Σ_b lo_b · B_b``, and the ranges into the targets, ``T_b = (hi_b - lo_b) · B_b``;
* the centroids ``c_f`` are the translation track of the root node (in the quantized
  variants plus the rigid shift of the targets' offsets, :mod:`.quantization`), the mesh sits
  on a child node (which holds the dequantization of the quantized variants);
* one keyframe per frame at its time in seconds: the frame's time code (its number in the file,
  or in the part written) over the file's frame rate, 24 when the file records none.

Variants (``compress``): ``none``, float32 everywhere; ``quantize`` (the default),
KHR_mesh_quantization: mesh and targets as normalized 16-bit integers, dequantized by the
child node's scale and translation, the weights as normalized 8- or 16-bit integers where the
budget allows; ``meshopt``, EXT_meshopt_compression (three.js needs its MeshoptDecoder
registered to load it): the targets as 16-bit integers at the coarsest step the budget allows,
the base, weights and translation float32 with the EXPONENTIAL filter, the triangles in vertex
cache order. The rounding follows from an error budget, not a fixed bit count
(:mod:`.quantization`); the layouts are :mod:`.decomposition_file`'s.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal, Protocol

import numpy as np

from ..atomic import refuse_existing, write_atomic
from ..format.reconstruction import reconstruction_basis
from ..io.gltf.reader import sample_gltf
from ..metrics import KG_DEFINITION, kg_error
from ..sequence import DEFAULT_FRAME_RATE, MeshSequence
from .layout import decomposition_bytes
from .quantization import quantize_animation

Compression = Literal["none", "quantize", "meshopt"]
COMPRESSIONS: tuple[str, ...] = ("none", "quantize", "meshopt")
#: The default variant: KHR_mesh_quantization loads natively in three.js, Babylon.js, Blender
#: and glTFast and takes about two thirds of the float32 size (cloth and chicken at KG 0.1);
#: meshopt is a third of that again (chicken, samba, cloth) but loads only where a meshopt
#: decoder is registered (three.js: GLTFLoader.setMeshoptDecoder), so it is asked for by name.
DEFAULT_COMPRESSION: Compression = "quantize"


class Decomposed(Protocol):
    """What the writer needs of a compressed file (a :class:`tuckercodec.Decoder` has it)."""

    faces: np.ndarray
    frame_names: list[str]

    @property
    def u1(self) -> np.ndarray: ...

    @property
    def core(self) -> np.ndarray: ...

    @property
    def u2(self) -> np.ndarray: ...

    @property
    def u3(self) -> np.ndarray: ...

    @property
    def centroids(self) -> np.ndarray: ...

    @property
    def info(self) -> Any: ...

    def frame_indices(self, frames: Any) -> np.ndarray: ...

    def positions(self, frames: Any = None) -> np.ndarray: ...


@dataclass(frozen=True)
class GltfReport:
    """What :func:`write_decomposition_gltf` wrote and the KG error a viewer shows.

    Attributes:
        path: the file written.
        size: its bytes.
        compression: the variant ("none", "quantize", "meshopt").
        frames, targets: keyframes and morph targets (the file's rank k).
        frame_rate: the frames per second of the keyframe times.
        position_step: the quantization step of the targets in scene units (0: float32).
        weight_bits: bits of the stored weights (32: float32, with the meshopt variant's
            EXPONENTIAL filter rounding each target's weights to a power-of-two step).
        viewer_kg: the KG error of the animation as a viewer evaluates it from the written
            file (sampled at each frame's time) against the .tkc's own decode of those frames.
        viewer_kg_reference: the same against a reference sequence, if one was given.
        tkc_kg_reference: the .tkc decode's KG error against that reference.
        definition: the KG definition of the three figures.
    """

    path: Path
    size: int
    compression: str
    frames: int
    targets: int
    frame_rate: float
    position_step: float
    weight_bits: int
    viewer_kg: float
    viewer_kg_reference: float | None = None
    tkc_kg_reference: float | None = None
    definition: str = KG_DEFINITION

    def summary(self) -> str:
        """The report as the command line prints it."""
        text = f"glTF viewer KG vs the .tkc decode: {self.viewer_kg:.5f}"
        if self.viewer_kg_reference is not None:
            text += (
                f"; vs the original: {self.viewer_kg_reference:.5f} (the .tkc: "
                f"{self.tkc_kg_reference:.5f})"
            )
        return f"{text} ({self.definition})"


def write_decomposition_gltf(
    decoder: Decomposed,
    path: str | os.PathLike[str],
    *,
    frames: Any = None,
    compress: Compression = DEFAULT_COMPRESSION,
    overwrite: bool = False,
    reference: MeshSequence | np.ndarray | None = None,
) -> GltfReport:
    """Write the decomposition of a compressed file as a playable glTF morph animation.

    Args:
        decoder: the opened file (a :class:`tuckercodec.Decoder`).
        path: a ``.glb``, or a ``.gltf`` (one JSON file, its buffer in a data: URI).
        frames: the frames to write (as for :meth:`Decoder.positions`): their times are their
            frame numbers over the file's frame rate (24 when it records none).
        compress: "none" (float32), "quantize" (KHR_mesh_quantization, the default) or
            "meshopt" (EXT_meshopt_compression, the smallest; needs the extra ``gltf``). The
            rounding keeps the viewer's KG error against the .tkc decode within 0.32 times
            the file's recorded KG error, so about 1.05 times it against the original
            (:mod:`.quantization`).
        overwrite: replace an existing file.
        reference: the original frames (all of the file's, or those of ``frames``), to report
            the viewer's KG error against them beside the .tkc's.

    Returns:
        A :class:`GltfReport`; its ``viewer_kg`` is measured by reading the written file back
        and evaluating the morph formula at each keyframe.

    Raises:
        ValueError: ``compress`` is not a variant, or ``frames`` selects none.
        DependencyError: "meshopt" without the ``meshoptimizer`` package.
    """
    if compress not in COMPRESSIONS:
        raise ValueError(f"compress must be one of {', '.join(COMPRESSIONS)}, got {compress!r}")
    path = Path(path)
    refuse_existing([path], overwrite)  # before the work, not after it
    chosen = decoder.frame_indices(frames)
    if chosen.size == 0:
        raise ValueError(f"the selection {frames!r} names no frame of the file")
    decoded = decoder.positions(chosen)
    rate = float(decoder.info.frame_rate or DEFAULT_FRAME_RATE)
    in_order = chosen.size < decoder.info.frames and bool(np.all(np.diff(chosen) > 0))
    codes = chosen if in_order or chosen.size == decoder.info.frames else np.arange(chosen.size)
    times = (codes / rate).astype(np.float32)

    weights, base, targets = morph_parts(decoder, chosen)
    centroids = decoder.centroids[chosen]
    quantized = None
    if compress != "none":
        quantized = quantize_animation(
            base,
            targets,
            weights,
            centroids,
            decoded,
            decoder.info.kg,
            filters=compress == "meshopt",
        )
    triangles = MeshSequence(base[None], decoder.faces).triangles()
    data = decomposition_bytes(
        path, triangles, times, weights, base, targets, centroids, quantized, compress
    )
    write_atomic(path, data, overwrite=overwrite)

    viewer = sample_gltf(path, times.astype(np.float64)).positions
    report_reference = None if reference is None else _reference(reference, decoded, chosen)
    return GltfReport(
        path=path,
        size=len(data),
        compression=compress,
        frames=int(chosen.size),
        targets=len(targets),
        frame_rate=rate,
        position_step=0.0 if quantized is None else quantized.step,
        weight_bits=32 if quantized is None else 8 * quantized.weights.dtype.itemsize,
        viewer_kg=kg_error(decoded, viewer),
        viewer_kg_reference=None
        if report_reference is None
        else kg_error(report_reference, viewer),
        tkc_kg_reference=None if report_reference is None else kg_error(report_reference, decoded),
    )


def _reference(
    reference: MeshSequence | np.ndarray, decoded: np.ndarray, chosen: np.ndarray
) -> np.ndarray:
    positions = reference.vertices if isinstance(reference, MeshSequence) else np.asarray(reference)
    if positions.shape[1:] != decoded.shape[1:]:
        raise ValueError(f"the reference has shape {positions.shape}, the file {decoded.shape}")
    if len(positions) == len(decoded):
        return positions
    return positions[chosen]


def morph_parts(
    decoder: Decomposed, chosen: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The weights (n, k) in 0..1, the base mesh (K, 3) and the targets (k, K, 3) of the
    frames ``chosen``: frame f is ``c_f + base + Σ_b w_fb · T_b`` (module docstring)."""
    basis = reconstruction_basis(decoder.core, decoder.u2)  # (i, 3, k)
    shapes = np.einsum("va,axb->bvx", decoder.u1, basis)  # B_b, (k, K, 3)
    u3 = decoder.u3[chosen]
    lo, hi = u3.min(axis=0), u3.max(axis=0)
    span = np.where(hi > lo, hi - lo, 1.0)  # a constant column: weight 0, all in the base
    weights = (u3 - lo) / span
    base = np.einsum("b,bvx->vx", lo, shapes)
    return weights, base, shapes * span[:, None, None]
