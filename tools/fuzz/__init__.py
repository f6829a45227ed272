"""Coverage-guided fuzzing of every door into tuckercodec with atheris, so that a crafted
input ends in a clear error, never a crash, a hang or a flood of memory.

    python -m tools.fuzz --list                                  # the targets, one line each
    python -m tools.fuzz --target obj --seconds 600              # a long run, one process
    python -m tools.fuzz --target decoder --runs 20000           # a fixed number of inputs
    python -m tools.fuzz --target npz --replay                   # re-check its saved inputs
    python -m tools.fuzz --target gltf --seconds 600 --merge     # then fold new coverage in
    python -m tools.fuzz --target vtk --make-seeds               # (re)write its valid seeds

A *target* is one door: the decoder (``decode``, ``info``, frame 0), the segmented decoder
(the same on format 1.1 files, plus a range across a segment boundary and a read from a path),
the FACE section's decoder fed directly with its params and payload, the zarr codec's chunk
decoder, and one per file reader (OBJ, ``.npz``, ``.npy``, PC2, MDD, glTF, GLB, VTK ``.pvd``,
XDMF; USD and Alembic through their isolated child, one process per input). :mod:`.targets`
says for each how bytes become an input and what its oracle accepts: success, or the
documented error (``FormatError`` for compressed data, ``InputError`` for the readers, the
codec's ``ValueError`` for zarr chunks). Anything else is a crash: another exception, a warning
(the test suite turns warnings into errors), an input slower than ``--timeout`` seconds, a
process beyond ``--memory-mb`` (an input that allocates more than ``--report-mb`` is saved too,
as ``bigmem-``), or a broken promise between two ways of reading the same input.

Folders, per target: seeds and inputs kept by ``--merge`` for the coverage they reach in
``tests/fuzz/corpus/<target>/`` (the decoders' seeds also include ``spec/vectors/``); crashing
inputs are written to ``tests/fuzz/crashes/<target>/``, one per distinct failure (exception
type and place); once fixed each is moved to ``tests/fuzz/regressions/<target>/`` with a name
saying what it broke. ``tests/test_fuzz.py`` replays all three.

The fuzzing runs in a child process (``--worker``) so that the driver can stop it on time,
restart it after a hang or an out-of-memory (libFuzzer exits on those), and sum the inputs
tried over the restarts from libFuzzer's final statistics.

No module of this package imports tuckercodec (or :mod:`tools.common`, which does) at its top:
the worker must import the package for the first time under atheris' instrumentation, or the
fuzzer runs blind to its coverage.
"""

from __future__ import annotations

from .container import check_input, resign, signature_of, structural_mutation
from .paths import CORPUS, CRASHES, FUZZ_DIR, NOT_INPUTS, REGRESSIONS, ROOT, VECTORS, saved_inputs
from .targets import TARGETS, Target, target_named

__all__ = [
    "CORPUS",
    "CRASHES",
    "FUZZ_DIR",
    "NOT_INPUTS",
    "REGRESSIONS",
    "ROOT",
    "TARGETS",
    "VECTORS",
    "Target",
    "check_input",
    "resign",
    "saved_inputs",
    "signature_of",
    "structural_mutation",
    "target_named",
]
