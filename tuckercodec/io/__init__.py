"""Reading and writing mesh sequences in the file formats where they live.

:func:`open_frames` and :func:`save_sequence` choose a format by the file name's suffix from
the registry (:mod:`.registry`), and :func:`load_sequence` is ``open_frames(...).load()``. One
module or package per format family: :mod:`.obj` (one OBJ file per frame), :mod:`.npz` (NumPy:
the ``.npz`` archive of a whole sequence, and :mod:`.npz.npy`, an array of positions),
:mod:`.usd`, :mod:`.alembic`, :mod:`.pointcache` (the PC2 and MDD animation caches),
:mod:`.gltf` (morph animations: the glTF container, reader and writer), :mod:`.vtk` and
:mod:`.xdmf` (simulation time series), :mod:`.zarr_store` (zarr arrays), and :mod:`.meshes`
(other one-frame mesh files, through trimesh). Folders, globs and lists of one-frame files are
:mod:`.frames`; ``tuckercodec formats`` lists them all. Which of them a source goes to is decided in
:mod:`.dispatch`. What the formats share: reading a range of frames at a time
(:class:`~tuckercodec.model.sources.FrameSource`), faces stored flat (:mod:`.common.polygons`),
the ceiling of what one read may inflate (:mod:`.common.budget`), XML without declarations
(:mod:`.common.safe_xml`), the shortest text of a float (:mod:`.common.float_text`), and reading
with a C++ library in a child process (:mod:`.isolation`, for USD and Alembic).
"""

from ..model.sources import FrameSource, SequenceFrames
from .dispatch import load_sequence, open_frames, save_sequence
from .frames import natural_sort_key
from .registry import ReadOptions, SequenceFormat, WriteOptions, format_named, format_of, formats

__all__ = [
    "FrameSource",
    "ReadOptions",
    "SequenceFormat",
    "SequenceFrames",
    "WriteOptions",
    "format_named",
    "format_of",
    "formats",
    "load_sequence",
    "natural_sort_key",
    "open_frames",
    "save_sequence",
]
