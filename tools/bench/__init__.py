"""The benchmarks, one command: ``python -m tools.bench SUITE [options]``, run from the
repository root; ``python -m tools.bench SUITE --help`` lists a suite's options. Each suite is a
module of this package (the peers suite a package, one module per peer) and prints Markdown
ready for BENCHMARKS.md, with the machine and the command that made it.

- ``peers``: the rate-distortion comparison with PCA, Draco, meshoptimizer, SZ3, zfp, TTHRESH
  and zstd, every coder measured in one run;
- ``codec``: rate against the reference, encode and decode speed, memory;
- ``analysis``: the exact rate-distortion table against plain SVDs;
- ``bpfv``: how well a size target uses its budget;
- ``size``: this checkout's sizes against the package at a baseline revision;
- ``rate``: whole-file sizes against two baselines (the rate work's reference and the previous
  commit), on the shared sequences and generated ones;
- ``entropy``: entropy coders of the sections' streams against zstd, and what RDO gains;
- ``scale``: large encodes, one frame from disk, one or two workers, forced segments;
- ``read``: reading a whole sequence, as it is (a folder of OBJ frames) or ``--formats``, from
  every format it can be written in;
- ``streaming``: reading a large file range by range (``open_frames``), and USD and Alembic
  through their isolated child;
- ``gltf``: the decomposition as a glTF morph animation, against gltfpack;
- ``zarr``: a sequence as a zarr array of .tkc chunks, against one .tkc;
- ``viewer``: the viewer page in headless Chromium;
- ``faces``: the faces-traverse encoder and decoder on fans of triangles sharing one edge;
- ``bounds``: size against a bound on every vertex, against SZ3 and zfp with the same
  guarantee, and a bound beside a KG target;
- ``lossless``: the lossless mode against fpzip, pcodec, zstd and Blosc2, bit for bit, and its
  decoding speed;
- ``fields``: the animated fields' codec in each mode, against SZ3 and zfp at the same bound,
  on fields made from positions, a series' own fields, or (``--simulation``) a real solver's;
- ``speed``: encode, decode, OBJ output and a large file's first frame against a baseline
  revision, both run alternately in one run.

The options several suites take mean the same in each (:mod:`tools.bench.arguments`): the
sequences measured (positional: files, folders of OBJ frames, or ``sample``, the built-in
cloth), ``--repeat N`` timed runs with the median reported, and ``--out``/``--force`` where
results are written.
"""

from tools.bench.runner import SUITES, main

__all__ = ["SUITES", "main"]
