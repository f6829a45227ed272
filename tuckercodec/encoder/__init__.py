"""The encoder: a mesh sequence to a compressed file that meets the error asked for.

Three modes, one at a time: a target KG error (the default, 0.1), fixed ranks (i, k), or a target
size in bpfv (the smallest error that fits).

How a target KG error is met (errors are squared norms; E is the KG denominator's square):

1. The exact table (:mod:`tuckercodec.decomposition.analysis`) gives the truncation error of
   every (i, k).
2. Quantization adds error. An error e in column a of U1 reaches the tensor multiplied by the
   norm of core slice a, so column a gets the step sqrt(D) / ||CORE[a, :, :]||; likewise U3's
   column b with ||CORE[:, :, b]||, the core gets sqrt(D), the centroids sqrt(D / K) (an error
   there moves all K vertices). Every stored number then adds about D/12 to the squared error,
   which is also the split that minimises the bits for a given error (reverse water-filling),
   so one number D sets the whole quantizer.
3. For a few splits of the error budget between truncation and quantization, the encoder picks
   the cheapest ranks whose truncation error fits the truncation share (by the exact table, or by
   the paper's bound with ``select="bound"``), sets D from the remaining share, and packs the
   result to count its real bytes. The smallest wins.
4. It then reconstructs exactly what the decoder will return, measures the KG error, and
   tightens D (or loosens it once, if there is room) until the decoded error is at most the
   target. The decoded error is never above the target.

The modules follow that path: :mod:`.options` (what is asked), :mod:`.encoder` (whole or
segmented: the one decision), :mod:`.whole` and :mod:`.segmented` (the two workspaces a search
runs on, behind the protocol of :mod:`.trial`), :mod:`.search` and :mod:`.fill` (the one
search), :mod:`.rdo` (rate-distortion rounding), :mod:`.results` (what an encode returns) and
:mod:`.shorthands` (the one-call encodes).
"""

from .encoder import Encoder
from .options import DEFAULT_TARGET_KG, EncodeOptions, Mode, resolve_options
from .results import EncodeReport, EncodeResult
from .shorthands import encode, encode_frames, encode_source, encode_with_report

__all__ = [
    "DEFAULT_TARGET_KG",
    "EncodeOptions",
    "EncodeReport",
    "EncodeResult",
    "Encoder",
    "Mode",
    "encode",
    "encode_frames",
    "encode_source",
    "encode_with_report",
    "resolve_options",
]
