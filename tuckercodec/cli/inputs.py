"""What the verbs read: a sequence named on the command line, with its reading options; and
the one output option that depends on the format written (--precision)."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from ..decoder import Decoder
from ..files import SUFFIX, is_compressed_file
from ..io import format_of, load_sequence
from ..io.samples import sample_path
from ..model.sequence import MeshSequence


def sequence_source(name: str) -> str | Path:
    """What a verb's INPUT names: the built-in sample for ``sample``, else the path itself."""
    return sample_path() if name == "sample" else name


def read_options(args: argparse.Namespace) -> dict[str, Any]:
    """The reading options a verb was given (--prim, --object, --faces, --fps, --max-memory),
    as the keywords of :func:`tuckercodec.io.load_sequence`."""
    names = ("prim", "object_path", "faces", "fps", "max_memory")
    return {name: getattr(args, name) for name in names if getattr(args, name, None) is not None}


def is_compressed(source: str) -> bool:
    """Whether ``source`` names a compressed file (by its signature, or by its suffix, so that
    a damaged one is reported as such)."""
    return source != "sample" and (
        is_compressed_file(source) or Path(source).suffix.lower() == SUFFIX
    )


def load_input(source: str, args: argparse.Namespace) -> MeshSequence:
    """A sequence from a path, 'sample', or a compressed file (decoded); errors name the path."""
    if is_compressed(source):
        return Decoder(source).sequence()
    return load_sequence(sequence_source(source), progress=source != "sample", **read_options(args))


def check_precision(precision: int | None, output: Path) -> None:
    """Refuse ``--precision`` for an output that is not OBJ text: binary formats store their
    numbers exactly, and an option that silently does nothing misleads."""
    found = format_of(output)
    if precision is not None and found is not None and found.write is not None:
        raise ValueError(
            f"{output}: --precision applies to OBJ frames (text); {found.name} files store "
            "binary numbers exactly"
        )
