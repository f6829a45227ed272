"""Rate: bits per frame per vertex (bpfv), the size measure of the dynamic-mesh literature.

Kept apart from :mod:`tuckercodec.measures.distortion` so that reading a file's size never imports
the error measures (STED needs scipy.sparse).
"""

from __future__ import annotations


def bpfv(total_bytes: int, frames: int, vertices: int) -> float:
    """Bits per frame per vertex: 8 * total_bytes / (frames * vertices).

    Pass the size of the whole file (header and connectivity included) unless the figure is
    labelled otherwise.
    """
    if frames < 1 or vertices < 1:
        raise ValueError(f"frames and vertices must be positive, got {frames} and {vertices}")
    return 8.0 * total_bytes / (frames * vertices)
