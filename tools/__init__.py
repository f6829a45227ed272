"""The project's own tools, each run from the repository root:

- :mod:`tools.bench`: the benchmarks, ``python -m tools.bench SUITE [options]``;
- :mod:`tools.generate`: generated sequences and the conformance vectors,
  ``python -m tools.generate.sequence`` and ``python -m tools.generate.vectors``;
- :mod:`tools.paper`: the seed paper's experiments, ``python -m tools.paper``;
- :mod:`tools.fuzz`: the fuzzers of every door (decoders, readers, FACE, zarr chunks),
  ``python -m tools.fuzz``.

They import only the public API (:mod:`tuckercodec`) and :mod:`tuckercodec.internal`; what
several of them share (the shared data, timing, memory, the machine, writing results) lives in
:mod:`tools.common`.
"""
