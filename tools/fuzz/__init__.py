"""Coverage-guided fuzzing of every door into tuckercodec with atheris, so that a crafted
input ends in a clear error, never a crash, a hang or a flood of memory.

    python -m tools.fuzz --list                                  # the targets, one line each
    python -m tools.fuzz --target obj --seconds 600              # a long run, one process
    python -m tools.fuzz --target decoder --runs 20000           # a fixed number of inputs
    python -m tools.fuzz --target npz --replay                   # re-check its saved inputs
    python -m tools.fuzz --target gltf --seconds 600 --merge     # then fold new coverage in
    python -m tools.fuzz --target vtk --make-seeds               # (re)write its valid seeds
    python -m tools.fuzz --target obj --line-coverage /tmp/work  # Python lines: seeds, + a run
    python -m tools.fuzz --js-replay /tmp/work/decoder           # the JavaScript decoder on them

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

A run reports libFuzzer's coverage at its start (the seeds: libFuzzer's ``INITED`` line) and
its end: ``cov``, the distinct edges (bytecode branches) reached, ``ft``, the features (edges
with hit counts, comparisons), and the corpus kept. A run fails (exit 1, saying why) if it saw
no coverage at all, if its corpus never grew past its seeds (``--no-growth-ok`` for a run too
short to grow), or if a module of the package was first imported after the instrumentation.

No module of this package imports tuckercodec (or :mod:`tools.common`, which does) at its top:
the worker must import the package for the first time under atheris' instrumentation, or the
fuzzer runs blind to its coverage. And since the package imports its modules when first used
(``import tuckercodec`` loads ``__init__`` and ``_version`` alone), the worker imports, inside
the instrumented block, each target's ``modules`` (every module below each) and runs the first
inputs of its corpus there, so that what the check imports lazily is instrumented too
(:func:`.worker.instrument_target`).

The JavaScript decoder (``tuckercodec/web/tkc/``) runs in node, out of libFuzzer's sight: it is
given the .tkc inputs the decoders' runs kept, and mutations of them, and must agree with the
Python decoder on accepting each (:mod:`.javascript`).
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
