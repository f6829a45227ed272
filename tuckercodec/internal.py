"""The one internal surface that the project's own tools use, beside the public API.

``tools/`` (the benchmarks, the seed paper's experiments, the conformance-vector writer and the
fuzzer) imports only :mod:`tuckercodec` and this module; a test checks it. What is here is not
part of the public API and may change in any release; it is listed so that a change to the
package sees at once what the tools rely on.

* The format's building blocks, for tools that build or take apart files (the vector writer,
  the fuzzer, the PCA peer written in this codec's container): the container's
  :func:`pack_container` and :func:`parse_container`, :func:`pack_raw` for files that break
  one rule on purpose, and :data:`SIGNATURE`, :data:`HEAD_SIZE`, :data:`PREAMBLE`,
  :data:`CRC`; the modules :mod:`~tuckercodec.format.faces`, :mod:`~tuckercodec.format.qmat`,
  :mod:`~tuckercodec.format.sections`, :mod:`~tuckercodec.format.streams`,
  :mod:`~tuckercodec.format.traversal` (§6.8, with :mod:`~tuckercodec.format.unseen`, its NEW
  vertices' ranks, and :mod:`~tuckercodec.format.uniform`, their places in 1.9) and
  :mod:`~tuckercodec.format.adaptive` (§6.14);
  the mesh parents of §6.2 and :func:`mesh_prediction` (its predictor 2), and
  :func:`tree_depths` of a parent forest.
* The decomposition and its analysis: :func:`centre_frames`, :func:`reconstruct`, :class:`Curve`.
* The definitions the reports quote: :data:`KG_DEFINITION`, :data:`MAX_DISTANCE_DEFINITION`
  (the worst vertex, measured with :func:`max_distance`), :data:`STED_DEFINITION`.
* Files and pictures: :func:`write_atomic`, :func:`refuse_existing`, :func:`plot_rd_curve`,
  :func:`pyplot` (matplotlib on the Agg backend, or a DependencyError naming the extra) and
  :func:`save_figure` (atomic, never replacing a file unasked).
* glTF: :func:`write_decomposition_gltf` (a compressed file's decomposition as a morph
  animation, with the KG error a viewer shows) and :func:`sample_gltf` (a glTF's mesh
  evaluated at given times, as a viewer does), for the glTF benchmark.
* The encoder's quantizer choice, :mod:`~tuckercodec.encoder.rdo`, which
  ``python -m tools.bench entropy --rdo`` switches off to measure what it gains.
* zarr chunks: :func:`encode_chunk` with its :func:`chunk_mode`, and :func:`decode_chunk`, the
  work both zarr codecs share, without zarr or numcodecs (the fuzzer's door into the codec).
* Sample data: :func:`sample_path`, and the synthetic :func:`wave_sheet` with its
  :func:`sheet_triangles`.
* The compiled core's switch, :mod:`~tuckercodec.system.native` (``native.core()``, and
  ``native.pure_python()`` to run the reference), for the differential test of the two.
* Animated fields (§6.13): :func:`encode_field` with its :class:`FieldTarget`,
  :func:`decoded_field` (an encoded field's sections decoded as a file's would be), and the
  measures :func:`relative_rms` and :func:`max_abs`, for ``python -m tools.bench fields``.
* Static attributes (§6.11): the module :mod:`~tuckercodec.format.attributes`
  (``attributes.encode_attribute`` and its ``Mesh``), and :mod:`~tuckercodec.model.normals`
  (normals recomputed from positions, and their angle error), for
  ``python -m tools.bench attributes``.
* Defaults the benchmarks offer as their own: :data:`DEFAULT_TARGET_KG` (the encoder's KG
  target) and :func:`default_max_memory` (half the machine's memory, what an encode may use).
"""

from __future__ import annotations

from .decomposition.analysis import Curve
from .decomposition.hosvd import centre_frames, reconstruct
from .encoder import rdo
from .encoder.fields import FieldTarget, encode_field, max_abs, relative_rms
from .encoder.fields import decoded as decoded_field
from .encoder.options import DEFAULT_TARGET_KG
from .format import (
    adaptive,
    attributes,
    faces,
    prediction,
    qmat,
    residual,
    sections,
    streams,
    traversal,
    uniform,
    unseen,
)
from .format.container import (
    CRC,
    HEAD_SIZE,
    PREAMBLE,
    SIGNATURE,
    pack_container,
    pack_raw,
    parse_container,
)
from .format.limits import DEFAULT_LIMITS
from .format.prediction import tree_depths
from .gltf_export import write_decomposition_gltf
from .io.gltf.reader import sample_gltf
from .io.samples import sample_path, sheet_triangles, wave_sheet
from .measures.distortion import KG_DEFINITION, MAX_DISTANCE_DEFINITION, max_distance
from .measures.perceptual import STED_DEFINITION
from .model import normals
from .model.topology import mesh_parents, mesh_prediction
from .reports.plots import plot_rd_curve, pyplot, save_figure
from .system import native
from .system.atomic import refuse_existing, write_atomic
from .system.memory import default_max_memory
from .zarr_codec.chunk import chunk_mode, decode_chunk, encode_chunk

__all__ = [
    "CRC",
    "DEFAULT_LIMITS",
    "DEFAULT_TARGET_KG",
    "HEAD_SIZE",
    "KG_DEFINITION",
    "MAX_DISTANCE_DEFINITION",
    "PREAMBLE",
    "SIGNATURE",
    "STED_DEFINITION",
    "Curve",
    "FieldTarget",
    "adaptive",
    "attributes",
    "centre_frames",
    "chunk_mode",
    "decode_chunk",
    "decoded_field",
    "default_max_memory",
    "encode_chunk",
    "encode_field",
    "faces",
    "max_abs",
    "max_distance",
    "mesh_parents",
    "mesh_prediction",
    "native",
    "normals",
    "pack_container",
    "pack_raw",
    "parse_container",
    "plot_rd_curve",
    "prediction",
    "pyplot",
    "qmat",
    "rdo",
    "reconstruct",
    "refuse_existing",
    "relative_rms",
    "residual",
    "sample_gltf",
    "sample_path",
    "save_figure",
    "sections",
    "sheet_triangles",
    "streams",
    "traversal",
    "tree_depths",
    "uniform",
    "unseen",
    "wave_sheet",
    "write_atomic",
    "write_decomposition_gltf",
]
