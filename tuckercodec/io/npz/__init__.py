"""The ``.npz`` sequence format: one NumPy archive holding the whole sequence (and, in
:mod:`.npy`, the ``.npy`` array of positions, which shares its header checks).

Keys: ``V`` positions (frames, vertices, 3), optionally ``F`` faces (0-based, -1 padding),
``frame_files`` (one name per frame), ``frame_rate``, ``time_codes``, ``meters_per_unit`` (one
number) and ``up_axis`` (one string, ``Y`` or ``Z``); attributes, face sets and animated
fields, bit for bit, as the keys ``attribute/<i>/values``, ``attribute/<i>/indices``,
``face_set/<i>``, ``field/<i>`` and the JSON description ``attached`` that names them
(:mod:`~tuckercodec.io.common.attached_keys`; an archive without ``attached`` has none, as
those written before). It is read with
:mod:`zipfile` and ``numpy.lib.format``, never with pickle, and every declared size is checked
against the file before anything is allocated (:mod:`.archive`): a member must be a ``.npy``
array, stored or deflated (what ``np.savez`` and ``np.savez_compressed`` write), not
encrypted, and present once, and the shape and dtype in its header must account for exactly
the bytes of its member. What the deflated members read whole inflate to (the keys beside ``V``,
held from the opening, and ``V`` itself when read whole) is bounded by ``--max-memory``
(:attr:`~tuckercodec.io.registry.ReadOptions.max_memory`, :mod:`~tuckercodec.io.common.budget`),
checked against the sizes the members declare, which zipfile never inflates beyond, before a
byte is inflated: a 1 MB member of zeros declaring 1.1 GB is refused there when that is more.

:class:`NpzFrames` reads key ``V`` in place, a range of frames at a time: a stored member
(``np.savez``) by offset in the file, as a ``.npy`` is
(:class:`~tuckercodec.model.sources.RawFrames`); a deflated one (``np.savez_compressed``) by
decompressing forward from where the last read stopped, the member staying open between reads, so
that reading the ranges in order decompresses the member once (a range before the last one starts
again from the member's beginning). The other keys (faces, names, rate, time codes, attributes,
face sets) are read whole when the archive is opened; the fields on the first
:meth:`~NpzFrames.read_fields`, whole, then kept (their shapes are checked at opening). A range
read does not check a stored member's CRC (only reading every byte could); :meth:`NpzFrames.load`
reads ``V`` whole through zipfile, which does. A ``V`` in Fortran order, whose frames are
scattered over the member, is read whole on first use.
"""

from .sequence import (
    NpzFrames,
    write_npz,
)
from .sequence import cannot_keep as cannot_keep_npz

__all__ = [
    "NpzFrames",
    "cannot_keep_npz",
    "write_npz",
]
