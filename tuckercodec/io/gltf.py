"""The glTF 2.0 sequence format (``.glb``, ``.gltf``): morph targets and a weights animation.

Reading samples the first animation of the file's mesh as a viewer plays it, at the keyframes
or at ``--fps`` (:func:`tuckercodec.gltf.reader.read_gltf`); writing puts frame 0 in the mesh
and every other frame in a morph target, one keyframe per frame
(:mod:`tuckercodec.gltf.sequence_writer`), exact to within the float32 rounding of base +
target. A static glTF (no animation) is a one-frame sequence, so a folder of .glb frames still
reads one frame per file.
"""

from __future__ import annotations

from pathlib import Path

from ..errors import InputError
from ..gltf.reader import read_gltf
from ..gltf.sequence_writer import write_sequence_gltf
from ..sequence import MeshSequence
from .registry import MeshFrame, ReadOptions, SequenceFormat, WriteOptions


def read(path: Path, options: ReadOptions) -> MeshSequence:
    """The sequence of a .glb/.gltf file; ``object_path`` names the mesh node or mesh, ``fps``
    the sampling rate."""
    return read_gltf(path, object_path=options.object_path, fps=options.fps)


def write(seq: MeshSequence, path: Path, options: WriteOptions) -> None:
    """Write the sequence as morph targets (polygons split into triangle fans)."""
    write_sequence_gltf(seq, path, overwrite=options.overwrite)


def read_frame(path: Path, reference: MeshFrame | None = None) -> MeshFrame:
    """One frame from one glTF file of a folder of frames: its mesh as shown at rest; a file
    holding an animation of several frames is refused (load it on its own)."""
    seq = read_gltf(path)
    if seq.frame_count != 1:
        raise InputError(
            f"holds an animation of {seq.frame_count} frames, not one frame: load it on its own",
            path=path,
        )
    return MeshFrame(seq.vertices[0], seq.faces, path=str(path))


FORMAT = SequenceFormat(
    name="gltf",
    suffixes=(".glb", ".gltf"),
    description="glTF 2.0 morph animation (frame 0 the mesh, frames as morph targets)",
    read=read,
    write=write,
    read_frame=read_frame,
    read_options=frozenset({"object_path", "fps"}),
    carries=frozenset({"faces", "frame_names", "frame_rate", "time_codes"}),
)
