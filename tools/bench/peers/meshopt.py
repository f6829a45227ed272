"""meshoptimizer's vertex codec on each frame, positions quantized to 8-16 bits over the
sequence's bounding box (uint16 x 4 per vertex, glTF's KHR_mesh_quantization layout), the frames
then packed with zstd 19 as gltfpack users do; faces by meshoptimizer's index codec after its
vertex-cache optimisation (which reorders triangles, never vertices), then zstd 19."""

from __future__ import annotations

import io
import struct

import numpy as np
import zstandard

from tools.bench.peers.base import Context, Trial, timed_trial, zstd_bytes
from tuckercodec import MeshSequence


def run_meshopt(sequence: MeshSequence, targets: list[float], context: Context) -> list[Trial]:
    import meshoptimizer

    frames, vertices = sequence.frame_count, sequence.vertex_count
    low = sequence.vertices.min(axis=(0, 1))
    extent = float((sequence.vertices.max(axis=(0, 1)) - low).max()) or 1.0
    indices = sequence.triangles().astype(np.uint32).reshape(-1)
    optimised = np.empty_like(indices)
    if indices.size:
        meshoptimizer.optimize_vertex_cache(optimised, indices, vertex_count=vertices)
    index_bytes = (
        zstd_bytes(
            meshoptimizer.encode_index_buffer(
                np.asarray(optimised, dtype=np.uint32), vertex_count=vertices
            )
        )
        if indices.size
        else b""
    )

    def trial_at(bits: int) -> Trial:
        step = extent / ((1 << bits) - 1)

        def encode() -> tuple[int, int, bytes]:
            q = np.zeros((vertices, 4), dtype=np.uint16)
            stream = io.BytesIO()
            stream.write(struct.pack("<4dB", *low, extent, bits))  # the dequantization, once
            for frame in sequence.vertices:
                q[:, :3] = np.rint((frame - low) / step)
                encoded = meshoptimizer.encode_vertex_buffer(q)
                stream.write(struct.pack("<I", len(encoded)))
                stream.write(encoded)
            packed = zstd_bytes(stream.getvalue())
            return len(packed) + len(index_bytes), len(index_bytes), packed

        def decode_(packed: bytes) -> np.ndarray:
            raw = zstandard.ZstdDecompressor().decompress(packed)
            *origin, span, stored_bits = struct.unpack_from("<4dB", raw)
            unit = span / ((1 << stored_bits) - 1)
            offset = struct.calcsize("<4dB")
            out = np.empty((frames, vertices, 3))
            for f in range(frames):
                (length,) = struct.unpack_from("<I", raw, offset)
                offset += 4
                # Ask for the default float32 (vertices, 2) and view it as uint16: the package's
                # dtype=np.uint16 allocates vertices, not vertices * 4, entries and overruns it.
                data = meshoptimizer.decode_vertex_buffer(
                    vertices, 8, raw[offset : offset + length]
                )
                offset += length
                q = np.ascontiguousarray(data).view(np.uint16).reshape(vertices, 4)
                out[f] = q[:, :3] * unit + np.asarray(origin)
            return out

        return timed_trial("meshopt", f"{bits} bits", encode, decode_)

    return [trial_at(bits) for bits in context.bits]
