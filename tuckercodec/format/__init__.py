"""The file format of ``spec/FORMAT.md``, one module per part of the spec.

* :mod:`.container` (§2, §4, §5): signature, preamble, header map and the validation order;
  reading a file from disk;
* :mod:`.header` (§4): the header's fields, and :class:`~.header.FileInfo`;
* :mod:`.sections` (§3, §6.6): the section table, and which sections exist, with their codecs,
  criticality, order and shapes;
* :mod:`.streams` (§6.1): zigzag integers in byte planes, one zstd frame;
* :mod:`.prediction` (§6.2): residuals from parent rows (the mesh parents are
  :func:`tuckercodec.model.topology.mesh_parents`);
* the section codecs: :mod:`.qmat` (§6.3, quantized matrices), :mod:`.faces` (§6.4,
  connectivity), :mod:`.names` (§6.5, frame names);
* :mod:`.limits` (§7): what a decoder accepts before allocating;
* :mod:`.reconstruction` (§8): the positions from the factors.

The encoder and the decoder are siblings over this package; neither imports the other. Every
:class:`~tuckercodec.errors.FormatError` raised here carries the identifier of the rule of §11
that the file breaks.
"""
