"""A glTF morph animation as a sequence: :class:`GltfFrames` samples the animation a range of frames
at a time, and :func:`write_gltf` writes one."""

from __future__ import annotations

from pathlib import Path
from typing import ClassVar

import numpy as np

from ...errors import InputError
from ...model.sequence import MeshSequence
from ...model.sources import FrameSource
from ..registry import MeshFrame, ReadOptions, WriteOptions
from .reader import METERS_PER_UNIT, UP_AXIS, Scene, read_gltf
from .timing import timing
from .writer import write_sequence_gltf


class GltfFrames(FrameSource):
    """The frames of a glTF animation, evaluated a range at a time: the file is read and
    checked once and held (its buffers hold every target anyway), and each range's frames are
    evaluated when read, the same numbers as :func:`.reader.read_gltf` gives them."""

    _transient: ClassVar[tuple[str, ...]] = ("_scene",)
    _scene: Scene | None = None

    def __init__(self, path: Path, options: ReadOptions):
        self._file, self._options = path, options
        scene = self._opened()
        rate, codes, names = timing(scene.times, scene.animated, scene.extras, options.fps)
        self._describe(
            path,
            len(scene.times),
            _vertex_count(scene),
            scene.faces,
            names,
            rate,
            codes,
            METERS_PER_UNIT,
            UP_AXIS,
            scene.attributes,
            scene.face_sets,
        )

    def _opened(self) -> Scene:
        if self._scene is None:
            options = self._options
            self._scene = Scene(
                self._file,
                object_path=options.object_path,
                fps=options.fps,
                inflation=options.inflation(),
            )
        return self._scene

    def _read(self, start: int, stop: int) -> np.ndarray:
        return self._opened().evaluate(start, stop)


def _vertex_count(scene: Scene) -> int:
    """The merged meshes' vertex count, without evaluating a frame."""
    return sum(len(scene.meshes[scene.doc.array("nodes")[n]["mesh"]].base) for n in scene.chosen)


def write_gltf(seq: MeshSequence, path: Path, options: WriteOptions) -> None:
    """Write the sequence as morph targets (polygons split into triangle fans)."""
    write_sequence_gltf(seq, path, overwrite=options.overwrite)


def read_gltf_frame(
    path: Path, reference: MeshFrame | None = None, options: ReadOptions | None = None
) -> MeshFrame:
    """One frame from one glTF file of a folder of frames: its mesh as shown at rest; a file
    holding an animation of several frames is refused (load it on its own). Its compressed
    views inflate within ``options.max_memory``."""
    seq = read_gltf(path, inflation=(options or ReadOptions()).inflation())
    if seq.frame_count != 1:
        raise InputError(
            f"holds an animation of {seq.frame_count} frames, not one frame: load it on its own",
            path=path,
        )
    return MeshFrame(seq.vertices[0], seq.faces, path=str(path))
