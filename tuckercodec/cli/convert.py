"""The ``convert`` verb: a sequence from one file format to another; ``formats`` lists them."""

from __future__ import annotations

import argparse
import sys
import time

import numpy as np

from ..errors import EXIT_OK
from ..files import SUFFIX
from ..io import format_named, format_of, formats, save_sequence
from ..io.dispatch import FOLDER_FORMAT
from ..io.registry import OPTION_FLAGS
from ..model.sequence import MeshSequence, default_frame_names
from ..system.atomic import refuse_existing
from ..system.optional import extra_installed
from .inputs import check_precision, load_input

#: How the parts a format may keep (SequenceFormat.carries) are named to the user.
_PARTS = {
    "float64": "float64 positions",
    "faces": "faces",
    "polygons": "polygons",
    "frame_names": "frame names",
    "frame_rate": "frame rate",
    "time_codes": "time codes",
    "meters_per_unit": "unit (metres per unit)",
    "up_axis": "up axis",
}
#: What becomes of a part that the output's format does not keep.
_LOSSES = {"float64": " (rounded to float32)", "polygons": " (split into triangles)"}


def run_convert(args: argparse.Namespace) -> int:
    destination = format_of(args.output)
    if args.output.suffix.lower() == SUFFIX:
        raise ValueError(f"{args.output}: to write a compressed file, use 'tuckercodec encode'")
    check_precision(args.precision, args.output)
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
    written = target or format_named(FOLDER_FORMAT)
    for item in written.cannot_keep(sequence) if written.cannot_keep else []:
        print(f"note: {written.name.upper()} cannot keep {item}; dropped", file=sys.stderr)
    kept = written.carries
    lost = [what for what, present in _contents(sequence).items() if present and what not in kept]
    if lost:
        named = ", ".join(_PARTS[what] + _LOSSES.get(what, "") for what in lost)
        print(f"not carried by the output's format: {named}")
    return EXIT_OK


def _contents(sequence: MeshSequence) -> dict[str, bool]:
    """Which parts of a sequence hold information an output format might not carry."""
    return {
        "float64": sequence.compact_vertices().dtype != np.float32,
        "faces": sequence.faces.shape[0] > 0,
        "polygons": bool((sequence.faces[:, 3:] >= 0).any()),
        "frame_names": sequence.frame_names != default_frame_names(sequence.frame_count),
        "frame_rate": sequence.frame_rate is not None,
        "time_codes": sequence.time_codes is not None,
        "meters_per_unit": sequence.meters_per_unit is not None,
        "up_axis": sequence.up_axis is not None,
    }


def run_formats(args: argparse.Namespace) -> int:
    """Print every registered format: suffixes, reading options, what it keeps, its extra."""
    for found in formats():
        modes = [
            m
            for m, f in (
                ("read", found.open or found.read_frame),
                ("write", found.write or found.write_frame),
            )
            if f
        ]
        print(f"{found.name}: {' '.join(found.suffixes)} ({' and '.join(modes)})")
        print(f"    {found.description}")
        if found.read_options:
            flags = ", ".join(sorted(OPTION_FLAGS[name] for name in found.read_options))
            print(f"    reading options: {flags}")
        if found.open is not None:
            print("    streams: read a range of frames at a time (encodes larger than memory)")
        elif found.read_frame is not None:
            print("    streams: a folder or list of these files is read file by file")
        if found.write is not None or found.write_frame is not None:
            kept = ", ".join(_PARTS[part] for part in _PARTS if part in found.carries)
            print(f"    keeps beyond float32 positions: {kept or 'nothing'}")
        if found.extra is not None:
            state = "installed" if extra_installed(found.extra) else "NOT installed"
            print(f"    needs: pip install 'tuckercodec[{found.extra}]' ({state})")
    return EXIT_OK
