"""Generators: what the project makes rather than measures, each run from the repository root.

- :mod:`tools.generate.sequence`: large, realistic animated meshes at any size, deterministic
  from a seed (``python -m tools.generate.sequence --kind body --vertices 200000 ...``), the
  input of the scale benchmark;
- :mod:`tools.generate.simulation`: a real simulation's animated point and cell data (SfePy's
  elastodynamics example, run in a scratch environment with SfePy and meshio) as a ``.pvd``
  series in the benchmarks' cache, the input of ``python -m tools.bench fields --simulation``;
- :mod:`tools.generate.textured_character`: a textured animated mesh authored with pxr from the
  shipped cloth (st, normals, displayColor, two material subsets, velocities), the input of the
  end-to-end demo of attributes (``python -m tools.generate.textured_character -o OUT.usdc``);
- :mod:`tools.generate.vectors`: the conformance vectors of spec/FORMAT.md §12
  (``python -m tools.generate.vectors``), written once into spec/vectors/.
"""
