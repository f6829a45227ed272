"""What an encode returns: the file's bytes and the report of what was chosen and measured."""

from __future__ import annotations

from dataclasses import dataclass, field

from ..decomposition.analysis import Selection
from ..format.attachments import attachment_codec
from ..measures.rate import bpfv as bits_per_frame_vertex
from .options import Mode


@dataclass(frozen=True)
class EncodeReport:
    """What the encoder did and measured. Errors are KG errors (Karni-Gotsman, per-frame mean)."""

    mode: Mode
    target: float | None  # the KG target (mode "kg") or bpfv target (mode "bpfv")
    select: Selection
    ranks: tuple[int, int]
    kg: float  # of the decoded sequence against the input
    truncation_kg: float  # of the truncation alone, before quantization
    exact_ranks: tuple[int, int] | None  # the cheapest ranks by the exact table (mode "kg")
    bound_ranks: tuple[int, int] | None  # what the paper's bound alone would pick (mode "kg")
    total_bytes: int
    section_bytes: dict[str, int] = field(default_factory=dict)
    vertices: int = 0
    frames: int = 0
    seconds: float = 0.0
    trials: int = 0
    segments: int = 1  # segments of frames, each its own decomposition (format 1.1)
    basis: str | None = None  # "shared" or "own" for a segmented file
    #: the largest Euclidean distance of a decoded vertex from the input's, in the sequence's
    #: units, and the (frame, vertex) where it is (the first such in frame order)
    max_distance: float | None = None
    max_distance_at: tuple[int, int] | None = None
    max_error: float | None = None  # the bound asked for, as a length (None: no bound)
    lossless: bool = False  # decoded values checked to be the input's, bit for bit
    corrections: str | None = None  # the domain of the file's corrections (§6.9), if it has any

    @property
    def bpfv(self) -> float:
        """Bits per frame per vertex of the whole file, header and connectivity included."""
        return bits_per_frame_vertex(self.total_bytes, self.frames, self.vertices)

    @property
    def connectivity_bpfv(self) -> float:
        """The faces section's share of :attr:`bpfv`."""
        return bits_per_frame_vertex(self.section_bytes.get("FACE", 0), self.frames, self.vertices)

    @property
    def attachments_bpfv(self) -> float:
        """The share of :attr:`bpfv` of the sections of format 1.5: the faces' order,
        attributes, face sets and fields."""
        attached = sum(
            size for name, size in self.section_bytes.items() if attachment_codec(name) is not None
        )
        return bits_per_frame_vertex(attached, self.frames, self.vertices)

    @property
    def raw_float32_bytes(self) -> int:
        """The positions as plain float32: F * K * 3 * 4 bytes (faces not counted)."""
        return self.frames * self.vertices * 12

    @property
    def ratio(self) -> float:
        """:attr:`raw_float32_bytes` over the whole file's size."""
        return self.raw_float32_bytes / self.total_bytes


@dataclass(frozen=True)
class EncodeResult:
    """The file's bytes and the report of how they were made."""

    data: bytes
    report: EncodeReport
