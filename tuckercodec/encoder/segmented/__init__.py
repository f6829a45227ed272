"""The segmented encoder: a sequence larger than memory, read in passes, to a file of format 1.1.

The frames are cut into segments (:mod:`..plan`), each its own decomposition with its own U3,
core, centroids and U2, and one U1 shared by all of them (``basis="shared"``, the default) or
one per segment (``basis="own"``). Three passes read the input, a segment per task, on any
executor (:mod:`tuckercodec.system.parallel`; :mod:`.passes`):

1. the centroids, the energies and a randomized range finder's sketch of the mode-1 space;
2. the projection of every frame on the sketch's orthonormal basis Q, which leaves the whole
   sequence in r dimensions (:mod:`.model`): the ranks, the steps and even the decoded error
   are then found in memory;
3. the decoded error measured on the input with the decoder's own reconstruction, which the
   file must meet (a fourth pass, with finer steps, in the rare case that it does not).

:class:`.workspace.SegmentedWorkspace` offers all this to the encoder's one search
(:mod:`..search`). The KG guarantee holds for the whole sequence: the squared errors of the
segments add, and so do their KG denominators, since each frame's centroid is its own. One
quantization parameter D serves every segment (equal slopes, the split of a total error that
costs the fewest bits), and the ranks are the cheapest whose truncation errors add up to the
truncation's share of the budget. :mod:`.basis` gives or fits a shared U1 instead of finding one.
"""

from .basis import fit_basis, shared_basis_of
from .workspace import SegmentedWorkspace, SharedBasis

__all__ = ["SegmentedWorkspace", "SharedBasis", "fit_basis", "shared_basis_of"]
