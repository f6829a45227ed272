"""Writing a decomposition as a glTF morph animation: the shapes, weights and centroid track of the
package's docstring put in a buffer and a document, in each of the three variants, and a report of
the error a viewer shows."""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Literal, Protocol

import numpy as np

from ..decoder import selected_time_codes
from ..format.reconstruction import reconstruction_basis
from ..io.gltf.accessors import ARRAY_BUFFER, BufferBuilder, padded_rows
from ..io.gltf.document import add_triangles, file_bytes, new_gltf
from ..io.gltf.reader import sample_gltf
from ..measures.distortion import KG_DEFINITION, Displacement, ErrorAccumulator, kg_error
from ..model.attributes import Attribute
from ..model.sequence import DEFAULT_FRAME_RATE, MeshSequence, float32_times
from ..system.atomic import refuse_existing, write_atomic
from .quantization import QuantizedAnimation, quantize_animation, weight_values
from .surface import Surface, surface_of

Compression = Literal["none", "quantize", "meshopt"]
COMPRESSIONS: tuple[str, ...] = ("none", "quantize", "meshopt")
#: The default variant: KHR_mesh_quantization loads natively in three.js, Babylon.js, Blender
#: and glTFast and takes about two thirds of the float32 size (cloth and chicken at KG 0.1);
#: meshopt is a third of that again (chicken, samba, cloth) but loads only where a meshopt
#: decoder is registered (three.js: GLTFLoader.setMeshoptDecoder), so it is asked for by name.
DEFAULT_COMPRESSION: Compression = "quantize"
_MAX_CODEC_STRIDE = 256  # EXT_meshopt_compression's ATTRIBUTES mode
#: The power of two the meshopt variant rounds the normals' target offsets to.
NORMAL_OFFSET_EXPONENT = -12


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
        tkc_worst_reference: the .tkc decode's worst vertex against that reference
            (:data:`~tuckercodec.measures.distortion.MAX_DISTANCE_DEFINITION`; its frame numbered as
            in the file), measured in the same pass as ``tkc_kg_reference``.
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
    tkc_worst_reference: Displacement | None = None

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
    attributes: Sequence[Attribute] | None = None,
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
        attributes: the sequence's attributes (default: the decoder's ``attributes``, if it
            has them): its first UV is written as TEXCOORD_0 and its normals as fitted NORMAL
            offsets per target (:mod:`.surface`); per-corner UVs split vertices.

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
    animation = _Animation.of(decoder, frames, path)
    quantized = None
    if compress != "none":
        quantized = quantize_animation(
            animation.base,
            animation.targets,
            animation.weights,
            animation.centroids,
            animation.decoded,
            decoder.info.kg,
            filters=compress == "meshopt",
        )
    if attributes is None:
        attributes = getattr(decoder, "attributes", None) or []
    surface = surface_of(decoder.faces, attributes, animation.decoded, animation.weights)
    base, targets, faces = animation.base, animation.targets, decoder.faces
    if surface is not None:  # the vertices split for the UVs' seams, as copies
        copies = surface.layout.vertex_of
        base, targets, faces = base[copies], targets[:, copies], surface.layout.faces
        if quantized is not None:
            quantized = replace(
                quantized, base=quantized.base[copies], targets=quantized.targets[:, copies]
            )
    data = decomposition_bytes(
        path,
        MeshSequence(base[None], faces).triangles(),
        animation.times,
        animation.weights,
        base,
        targets,
        animation.centroids,
        quantized,
        compress,
        surface,
    )
    write_atomic(path, data, overwrite=overwrite)
    shown = None if surface is None else surface.representative
    return _report(path, len(data), compress, animation, quantized, reference, shown)


@dataclass(frozen=True)
class _Animation:
    """The frames written, as a viewer will play them: the frames ``chosen`` of the file, their
    decode, keyframe times (s) at ``rate``, and their morph parts (:func:`morph_parts`)."""

    chosen: np.ndarray
    decoded: np.ndarray
    rate: float
    times: np.ndarray
    weights: np.ndarray
    base: np.ndarray
    targets: np.ndarray
    centroids: np.ndarray

    @classmethod
    def of(cls, decoder: Decomposed, frames: Any, path: Path) -> _Animation:
        """The frames ``frames`` selects of the file (ValueError if none), to be written to
        ``path`` (an InputError naming it and the frame if float32 seconds cannot hold the
        frames' times: a frame rate as small as 5e-324 puts frame 1 beyond float32's range)."""
        chosen = decoder.frame_indices(frames)
        if chosen.size == 0:
            raise ValueError(f"the selection {frames!r} names no frame of the file")
        rate = float(decoder.info.frame_rate or DEFAULT_FRAME_RATE)
        # times: the selection's time codes as a decoded sequence has them (frames out of
        # order are renumbered 0, 1, 2..., which keyframes need: increasing times)
        codes = selected_time_codes(decoder.info, chosen)
        if codes is None:
            codes = np.arange(chosen.size, dtype=np.float64)
        decoded = decoder.positions(chosen)
        weights, base, targets = morph_parts(decoder, chosen)
        with np.errstate(over="ignore"):
            seconds = codes / rate
        times = float32_times(seconds, path)
        return cls(chosen, decoded, rate, times, weights, base, targets, decoder.centroids[chosen])


def _report(
    path: Path,
    size: int,
    compress: str,
    animation: _Animation,
    quantized: QuantizedAnimation | None,
    reference: MeshSequence | np.ndarray | None,
    shown: np.ndarray | None = None,
) -> GltfReport:
    """What was written, with the KG error of the file read back as a viewer plays it;
    ``shown``: the written vertex that shows each vertex, where vertices were split."""
    decoded = animation.decoded
    viewer = sample_gltf(path, animation.times.astype(np.float64)).positions
    if shown is not None:
        viewer = viewer[:, shown]
    original = None if reference is None else _reference(reference, decoded, animation.chosen)
    tkc = None
    if original is not None:
        tkc = ErrorAccumulator()  # the .tkc's KG error and worst vertex in one pass
        tkc.add(original, decoded, frames=animation.chosen)
    return GltfReport(
        path=path,
        size=size,
        compression=compress,
        frames=int(animation.chosen.size),
        targets=len(animation.targets),
        frame_rate=animation.rate,
        position_step=0.0 if quantized is None else quantized.step,
        weight_bits=32 if quantized is None else 8 * quantized.weights.dtype.itemsize,
        viewer_kg=kg_error(decoded, viewer),
        viewer_kg_reference=None if original is None else kg_error(original, viewer),
        tkc_kg_reference=None if tkc is None else tkc.kg,
        tkc_worst_reference=None if tkc is None else tkc.worst,
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


# ------------------------------------------------------------------------------------------
# the file's bytes, laid out for each variant (module docstring)


def decomposition_bytes(
    path: Path,
    triangles: np.ndarray,
    times: np.ndarray,
    weights: np.ndarray,
    base: np.ndarray,
    targets: np.ndarray,
    centroids: np.ndarray,
    quantized: QuantizedAnimation | None,
    compress: str,
    surface: Surface | None = None,
) -> bytes:
    """The file: ``weights`` (F, k), ``base`` (K, 3), ``targets`` (k, K, 3) and ``centroids``
    (F, 3) as :func:`morph_parts` gives them (written as float32 when ``quantized`` is None),
    else the stored numbers of ``quantized``; and the ``surface``'s UVs and normals, if any."""
    builder = BufferBuilder()
    if quantized is None:
        stored = _float32_numbers(builder, weights, base, targets, centroids)
    else:
        stored = _quantized_numbers(builder, quantized)
    filtered = compress == "meshopt"
    primitive: dict[str, Any] = {"attributes": {"POSITION": stored.position}}
    if filtered and len(triangles):
        from ..io.gltf.meshopt import vertex_cache_order

        triangles = vertex_cache_order(triangles, len(base))
    add_triangles(builder, primitive, triangles, len(base))
    primitive["targets"] = [{"POSITION": m} for m in stored.morphs]
    if surface is not None:
        _add_surface(builder, primitive, surface, filtered)
    mesh = {
        "name": "decomposition",
        "primitives": [primitive],
        "weights": [float(w) for w in stored.shown_weights[0].astype(np.float32)],
    }
    gltf = _document(stored, mesh, _samplers(builder, times, stored))
    if filtered:
        return _meshopt_file(gltf, builder, path)
    return file_bytes(gltf, builder, path)


def _add_surface(
    builder: BufferBuilder, primitive: dict[str, Any], surface: Surface, filtered: bool
) -> None:
    """The surface's vertex attributes, and its NORMAL offsets in the targets; ``filtered``
    (the meshopt variant): the offsets rounded to multiples of 2^-12 (0.014 degrees on a unit
    normal) and stored with the EXPONENTIAL filter, which the codec then packs to about a
    fifth of their float32 size."""
    for semantic, values in surface.attributes.items():
        primitive["attributes"][semantic] = builder.add_accessor(
            values, target=ARRAY_BUFFER, vertex_attribute=True
        )
    if surface.normal_offsets is None:
        return
    codec = None
    offsets = surface.normal_offsets
    if filtered:
        step = NORMAL_OFFSET_EXPONENT
        whole = np.clip(np.round(np.ldexp(offsets, -step)), -(2**22), 2**22)  # the filter's 24 bits
        offsets = np.ldexp(whole, step).astype(np.float32)
        codec = _exponential(np.full(3, step), 12)
    for target, values in zip(primitive["targets"], offsets, strict=True):
        target["NORMAL"] = builder.add_accessor(
            values, target=ARRAY_BUFFER, vertex_attribute=True, codec=codec
        )


@dataclass
class _Stored:
    """The animation's numbers as the file stores them: the accessors of the base mesh
    (``position``) and of the targets (``morphs``), the weights as stored and as a viewer reads
    them, the translation track, the meshopt codecs of the last two (``None``: plain), and what
    the child node and the file declare for the dequantization."""

    position: int
    morphs: list[int]
    weights: np.ndarray
    shown_weights: np.ndarray
    translation: np.ndarray
    weight_codec: dict[str, Any] | None = None
    translation_codec: dict[str, Any] | None = None
    node: dict[str, Any] = field(default_factory=dict)
    extensions: list[str] = field(default_factory=list)


def _float32_numbers(
    builder: BufferBuilder,
    weights: np.ndarray,
    base: np.ndarray,
    targets: np.ndarray,
    centroids: np.ndarray,
) -> _Stored:
    """The ``none`` variant's numbers: float32, a buffer view per array."""
    position = builder.add_accessor(
        base.astype(np.float32), target=ARRAY_BUFFER, bounds=True, vertex_attribute=True
    )
    morphs = [
        builder.add_accessor(
            t.astype(np.float32), target=ARRAY_BUFFER, bounds=True, vertex_attribute=True
        )
        for t in targets
    ]
    stored_weights = weights.astype(np.float32)
    return _Stored(position, morphs, stored_weights, stored_weights, centroids.astype(np.float32))


def _quantized_numbers(builder: BufferBuilder, quantized: QuantizedAnimation) -> _Stored:
    """The quantized variants' numbers (KHR_mesh_quantization), dequantized by the child node's
    translation and scale; with the meshopt variant's EXPONENTIAL filters, if any."""
    position = builder.add_accessor(
        quantized.base,
        target=ARRAY_BUFFER,
        bounds=True,
        normalized=quantized.base.dtype == np.int16,
        vertex_attribute=True,
        codec=_exponential(quantized.base_exponents, 12),
    )
    return _Stored(
        position,
        _shared_targets(builder, quantized.targets),
        quantized.weights,
        weight_values(quantized.weights),
        quantized.translation,
        _weight_codec(quantized.weight_exponents, len(quantized.weights)),
        _exponential(quantized.translation_exponents, 12),
        {
            "translation": [float(v) for v in quantized.offset],
            "scale": [float(quantized.scale)] * 3,
        },
        ["KHR_mesh_quantization"],
    )


def _samplers(builder: BufferBuilder, times: np.ndarray, stored: _Stored) -> list[dict[str, Any]]:
    """The animation's two LINEAR samplers, one keyframe per frame: the mesh's weights, then
    the root's translation."""
    key_times = builder.add_accessor(times, bounds=True)
    return [
        {
            "input": key_times,
            "output": builder.add_accessor(
                stored.weights.reshape(-1),
                normalized=stored.weights.dtype != np.float32,
                codec=stored.weight_codec,
            ),
            "interpolation": "LINEAR",
        },
        {
            "input": key_times,
            "output": builder.add_accessor(stored.translation, codec=stored.translation_codec),
            "interpolation": "LINEAR",
        },
    ]


def _document(
    stored: _Stored, mesh: dict[str, Any], samplers: list[dict[str, Any]]
) -> dict[str, Any]:
    """The glTF's JSON: the root node (the translation track) and its child (the mesh), the
    mesh, and the animation of both."""
    gltf = new_gltf(stored.extensions)
    root = {
        "name": "tuckercodec",
        "children": [1],
        "translation": [float(v) for v in stored.translation[0]],
    }
    child = {"name": "decomposition", "mesh": 0, **stored.node}
    channels = [
        {"sampler": 0, "target": {"node": 1, "path": "weights"}},
        {"sampler": 1, "target": {"node": 0, "path": "translation"}},
    ]
    gltf.update(
        {
            "scene": 0,
            "scenes": [{"nodes": [0]}],
            "nodes": [root, child],
            "meshes": [mesh],
            "animations": [{"name": "decomposition", "samplers": samplers, "channels": channels}],
        }
    )
    return gltf


def _shared_targets(builder: BufferBuilder, targets: np.ndarray) -> list[int]:
    """Every target (k, K, 3) int16 in one buffer view of 8-byte rows, an accessor each."""
    count, vertices = targets.shape[:2]
    if count == 0:
        return []
    rows = padded_rows(targets.reshape(-1, 3), 8)
    view = builder.add_view(rows, 6, byteStride=8, target=ARRAY_BUFFER)
    return [
        builder.add_accessor(
            target, view=view, byte_offset=b * vertices * 8, normalized=True, bounds=True
        )
        for b, target in enumerate(targets)
    ]


def _exponential(exponents: np.ndarray | None, stride: int) -> dict[str, Any] | None:
    """The codec of float32 rows of ``stride`` bytes with the EXPONENTIAL filter, if any."""
    if exponents is None:
        return None
    return {"stride": stride, "exponents": exponents}


def _weight_codec(exponents: np.ndarray | None, frames: int) -> dict[str, Any] | None:
    """The weights' codec: a keyframe's k weights per codec row where they fit in 256 bytes
    (differences over time), else one weight per row; each target's exponent."""
    if exponents is None:
        return None
    count = len(exponents)
    if 0 < 4 * count <= _MAX_CODEC_STRIDE:
        return {"stride": 4 * count, "exponents": exponents}
    return {"stride": 4, "exponents": np.tile(exponents, frames)}


def _meshopt_file(gltf: dict[str, Any], builder: BufferBuilder, path: Path) -> bytes:
    from ..io.gltf.container import pack_glb, pack_gltf
    from ..io.gltf.meshopt import EXTENSION, compress_views

    views, binary, fallback = compress_views(
        builder.views, builder.view_data, builder.view_elements, builder.view_codecs
    )
    gltf = dict(gltf)
    gltf["extensionsUsed"] = sorted({*gltf.get("extensionsUsed", []), EXTENSION})
    gltf["extensionsRequired"] = sorted({*gltf.get("extensionsRequired", []), EXTENSION})
    gltf["accessors"] = builder.accessors
    gltf["bufferViews"] = views
    gltf["buffers"] = [
        {"byteLength": len(binary)},
        {"byteLength": fallback, "extensions": {EXTENSION: {"fallback": True}}},
    ]
    if path.suffix.lower() == ".gltf":
        return pack_gltf(gltf, binary)
    return pack_glb(gltf, binary)
