"""Generators: what the project makes rather than measures, each run from the repository root.

- :mod:`tools.generate.sequence`: large, realistic animated meshes at any size, deterministic
  from a seed (``python -m tools.generate.sequence --kind body --vertices 200000 ...``), the
  input of the scale benchmark;
- :mod:`tools.generate.vectors`: the conformance vectors of spec/FORMAT.md §12
  (``python -m tools.generate.vectors``), written once into spec/vectors/.
"""
