"""The project's own tools: benchmarks, the seed paper's experiments, the conformance-vector
writer and the decoder fuzzer. Run each from the repository root as ``python -m tools.NAME``.

They import only the public API (:mod:`tuckercodec`) and :mod:`tuckercodec.internal`; what
several of them share (the shared data, timing, memory, the machine, writing results) lives in
:mod:`tools.common`.
"""
