"""The codec on files: encode a sequence on disk into a file, decode a file onto disk.

The in-memory functions are :func:`tuckercodec.encode`, :func:`tuckercodec.decode` and
:func:`tuckercodec.info`; these helpers add reading, writing (atomically, never replacing a file
without ``overwrite=True``) and the choice of output format.
"""

from __future__ import annotations

import os
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from .decoder import Decoder, FrameSelection
from .encoder import EncodeOptions, Encoder, EncodeReport, resolve_options
from .errors import InputError
from .format.container import SIGNATURE
from .format.limits import DEFAULT_LIMITS, Limits
from .gltf_export import DEFAULT_COMPRESSION, Compression, write_decomposition_gltf
from .io import format_named, format_of, open_frames, save_sequence
from .io.dispatch import Source
from .model.sequence import MeshSequence
from .system.atomic import refuse_existing, write_atomic
from .system.parallel import Executor
from .system.reading import open_regular_file

#: The suffix of compressed files.
SUFFIX = ".tkc"
#: The name of a sequence format that can be written ("obj", "npz", "usd"...: see
#: :func:`tuckercodec.io.formats`).
OutputFormat = str


def is_compressed_file(path: str | os.PathLike[str]) -> bool:
    """Whether ``path`` is a file that starts with the format's signature."""
    try:
        with open_regular_file(path, "a tuckercodec file") as handle:
            return handle.read(len(SIGNATURE)) == SIGNATURE
    except (InputError, OSError):  # a folder, a pipe, a missing or unreadable file
        return False


def encode_file(
    source: Source,
    output: str | os.PathLike[str],
    options: EncodeOptions | None = None,
    *,
    overwrite: bool = False,
    progress: bool = False,
    executor: Executor | None = None,
    prim: str | None = None,
    object_path: str | None = None,
    faces: str | os.PathLike[str] | None = None,
    fps: float | None = None,
    **fields: Any,
) -> EncodeReport:
    """Read a sequence (folder of OBJ files, glob, .npz...), encode it and write ``output``.

    The output is checked before any work (it must not exist unless ``overwrite``) and written
    atomically. The encoder's options are given whole (``options``, an
    :class:`~tuckercodec.encoder.EncodeOptions`), as keywords named as its fields
    (``target_kg``, ``ranks``, ``target_bpfv``, ``max_error``, ``lossless``, ``level``,
    ``max_memory``...), or both, the keywords put over ``options`` as :func:`dataclasses.replace`
    does (:func:`~tuckercodec.encoder.resolve_options`; any other keyword is a ``TypeError``). A
    sequence whose whole encode would not fit ``max_memory`` (or given ``segment_frames``) is read
    a range of frames at a time and written in segments (format 1.1,
    :meth:`tuckercodec.encoder.Encoder.encode_source`). ``prim``, ``object_path``, ``faces`` and
    ``fps`` are the reading options of :func:`tuckercodec.io.load_sequence` (``faces`` gives a
    ``.npy``, PC2 or MDD cache its faces); ``max_memory`` bounds what the read may decompress as
    well. ``progress`` prints a line on standard error as each pass of a segmented encode
    starts; ``executor``: where a segmented encode's passes run. Returns the encoder's report.
    """
    options = resolve_options(options, **fields)
    encoder = Encoder(options, executor=executor, progress=_say if progress else None)
    reading = {"prim": prim, "object_path": object_path, "faces": faces, "fps": fps}
    reading["max_memory"] = options.max_memory  # what the read may inflate, too
    return write_encoded(encoder, source, output, overwrite=overwrite, **reading).report


def write_encoded(
    encoder: Encoder,
    source: Source,
    output: str | os.PathLike[str],
    *,
    overwrite: bool = False,
    **reading: Any,
) -> EncodedFile:
    """Read ``source`` (``reading``: the options of :func:`tuckercodec.io.open_frames`),
    encode it with ``encoder`` and write ``output`` atomically, refused before any work if it
    exists and not ``overwrite``. The encoder's result, and what was read."""
    refuse_existing([Path(output)], overwrite)
    with open_frames(source, **reading) as frames:
        result = encoder.encode_source(frames)
        write_atomic(output, result.data, overwrite=overwrite)
        return EncodedFile(
            result.data, result.report, frames.frame_count, frames.vertex_count, frames.time_codes
        )


@dataclass(frozen=True)
class EncodedFile:
    """What :func:`write_encoded` wrote: the file's bytes and report, and the source's frames,
    vertices and time codes (which the format does not keep)."""

    data: bytes
    report: EncodeReport
    frame_count: int
    vertex_count: int
    time_codes: np.ndarray | None


def _say(line: str) -> None:
    print(line, file=sys.stderr, flush=True)


def read_compressed(path: str | os.PathLike[str], *, limits: Limits = DEFAULT_LIMITS) -> Decoder:
    """Open a compressed file from disk: the same as ``Decoder(path, limits=limits)``."""
    return Decoder(os.fsdecode(path), limits=limits)  # a bytes path is a path, not a file


def decoded_output_path(output: str | os.PathLike[str], output_format: OutputFormat | None) -> Path:
    """Where :func:`decode_file` writes: ``output`` itself, or with the format's suffix added
    (``.npz`` for the npz format...) when the name lacks it. Without ``output_format``, the
    format is the one ``output``'s suffix names, else a folder of OBJ files."""
    output = Path(output)
    if output_format is None:
        return output
    chosen = format_named(output_format)  # ValueError naming the formats
    named = format_of(output)
    if chosen.write is None:  # one file per frame: a folder
        if chosen.write_frame is None:
            raise ValueError(f"the {chosen.name} format can be read but not written")
        if named is not None and named.write is not None:
            raise ValueError(
                f"{output}: an {chosen.name.upper()} output is a folder, not a {output.suffix} file"
            )
        return output
    if output.suffix.lower() not in chosen.suffixes:
        return Path(f"{output}{chosen.suffixes[0]}")
    return output


def is_gltf_output(output: Path) -> bool:
    """Whether ``output`` names a glTF file, which gets the decomposition as morph targets."""
    found = format_of(output)
    return found is not None and found.name == "gltf"


def decode_file(
    path: str | os.PathLike[str],
    output: str | os.PathLike[str],
    *,
    frames: FrameSelection = None,
    output_format: OutputFormat | None = None,
    overwrite: bool = False,
    precision: int | None = None,
    progress: bool = False,
    glb_compress: Compression | None = None,
) -> MeshSequence:
    """Decode a compressed file and write the frames: a folder of OBJ files, or a sequence
    file (``.npz``, ``.usd``...). A glTF output (``.glb``/``.gltf``) holds the decomposition
    itself as a morph animation (:func:`tuckercodec.gltf_export.write_decomposition_gltf`),
    compressed as ``glb_compress`` says ("none", "quantize" (default), "meshopt"); a segmented
    file (format 1.1) has one decomposition per segment, so its glTF holds the decoded frames as
    any sequence written to glTF does (frame 0 the mesh, each other frame a morph target).

    ``output_format`` defaults to the format ``output``'s suffix names, else a folder of OBJ
    files; the format's suffix is added to the name if missing (:func:`decoded_output_path`).
    Returns the decoded sequence.
    """
    output = decoded_output_path(output, output_format)
    decoder = Decoder(os.fsdecode(path))
    sequence = decoder.sequence(frames)
    if is_gltf_output(output) and not decoder.segmented:
        output.parent.mkdir(parents=True, exist_ok=True)  # as save_sequence does
        compress = glb_compress or DEFAULT_COMPRESSION
        write_decomposition_gltf(
            decoder, output, frames=frames, compress=compress, overwrite=overwrite
        )
        return sequence
    if glb_compress is not None:
        raise ValueError(
            f"{output}: glb_compress applies only to the decomposition of a file of one segment "
            "written as .glb or .gltf"
        )
    save_sequence(sequence, output, overwrite=overwrite, precision=precision, progress=progress)
    return sequence
