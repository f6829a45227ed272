"""The ``convert`` verb: a sequence from one file format to another."""

from __future__ import annotations

import argparse
import time

import numpy as np

from ..atomic import refuse_existing
from ..errors import EXIT_OK
from ..files import SUFFIX
from ..format.names import default_frame_names
from ..io import FOLDER_FORMAT, format_named, format_of, save_sequence
from ..sequence import MeshSequence
from .inputs import load_input

#: How the parts a format may not carry (SequenceFormat.carries) are named to the user.
_PARTS = {
    "float64": "positions beyond float32 precision (rounded to float32)",
    "faces": "faces",
    "frame_names": "frame names",
    "frame_rate": "frame rate",
    "time_codes": "time codes",
}


def run_convert(args: argparse.Namespace) -> int:
    destination = format_of(args.output)
    if args.output.suffix.lower() == SUFFIX:
        raise ValueError(f"{args.output}: to write a compressed file, use 'tuckercodec encode'")
    if destination is not None and destination.write is not None:
        refuse_existing([args.output], args.force)  # before the work, not after it
    start = time.perf_counter()
    sequence = load_input(args.input, args)
    save_sequence(sequence, args.output, overwrite=args.force, precision=args.precision)
    target = destination if destination is not None and destination.write else None
    print(
        f"{args.input}: {sequence.frame_count} frames, {sequence.vertex_count} vertices, "
        f"{sequence.faces.shape[0]} faces -> {args.output} "
        f"({target.name if target else 'a folder of OBJ files'}) in "
        f"{time.perf_counter() - start:.2f} s"
    )
    kept = target.carries if target else format_named(FOLDER_FORMAT).carries
    lost = [what for what, present in _contents(sequence).items() if present and what not in kept]
    if lost:
        print(f"not carried by the output's format: {', '.join(_PARTS[what] for what in lost)}")
    return EXIT_OK


def _contents(sequence: MeshSequence) -> dict[str, bool]:
    """Which parts of a sequence hold information an output format might not carry."""
    vertices = sequence.vertices
    return {
        "float64": not np.array_equal(vertices.astype(np.float32), vertices),
        "faces": sequence.faces.shape[0] > 0,
        "frame_names": sequence.frame_names != default_frame_names(sequence.frame_count),
        "frame_rate": sequence.frame_rate is not None,
        "time_codes": sequence.time_codes is not None,
    }
