"""What a format version lets the encoder write: :attr:`.options.EncodeOptions.format_version`.

Each minor version of format 1 adds features (spec/FORMAT.md §10): 1.1 segments, 1.2 the coding
tools (faces-traverse, predictors 2 and 3), 1.3 corrections, 1.4 the time and scene header keys,
1.5 attributes, face sets, fields and the faces' given order, 1.6 adaptive coding and predictor
2's pushes, 1.7 the corrections' chunks through the adaptive coder, 1.8 the corrections'
codebooks, 1.9 the walk's new vertices in a uniform stream. The encoder uses each
where it makes the file smaller, and the file says the minor version of the newest one it
uses. :class:`Features` holds an encode to the features of one
version and before, so that decoders of that version read every file it writes; what cannot be
written without a newer feature is refused (:func:`Features.require`), never dropped.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from ..errors import FormatVersionError
from ..format.adaptive import ADAPTIVE_MINOR
from ..format.attachments import ATTACHMENTS_MINOR
from ..format.container import FORMAT_MAJOR, SCENE_MINOR
from ..format.residual import ADAPTIVE_CORRECTIONS_MINOR, CODEBOOKS_MINOR, CORRECTIONS_MINOR
from ..format.sections import CODING_TOOLS_MINOR
from ..format.segments import SEGMENTED_MINOR
from ..format.traversal import UNIFORM_RANKS_MINOR

#: The newest minor version this encoder writes, and so its default.
NEWEST_MINOR = UNIFORM_RANKS_MINOR
#: Every version ``format_version`` may name, oldest first.
VERSIONS = tuple(f"{FORMAT_MAJOR}.{minor}" for minor in range(NEWEST_MINOR + 1))

_VERSION = re.compile(r"\s*(\d+)(?:\.(\d+))?\s*")


def parse_format_version(value: object) -> str:
    """A format version as ``"1.N"``: ``"1.2"`` or ``"1"`` (1.0), one this encoder writes;
    ``ValueError`` naming it otherwise. A float (``1.2``) is refused: ``1.10`` would read as
    1.1."""
    match = _VERSION.fullmatch(value) if isinstance(value, str) else None
    if match is not None:
        major, minor = int(match.group(1)), int(match.group(2) or 0)
        if major == FORMAT_MAJOR and minor <= NEWEST_MINOR:
            return f"{major}.{minor}"
    raise ValueError(
        f"format_version must be one of {', '.join(VERSIONS)} (a string), got {value!r}"
    )


@dataclass(frozen=True)
class Features:
    """The features a file may use: those of format ``1.minor`` and before (default: every
    one this encoder knows)."""

    minor: int = NEWEST_MINOR

    @classmethod
    def of(cls, format_version: str | None) -> Features:
        """The features of a checked ``format_version`` (``None``: the newest)."""
        if format_version is None:
            return cls()
        return cls(int(parse_format_version(format_version).split(".")[1]))

    @property
    def version(self) -> str:
        """``"1.minor"``."""
        return f"{FORMAT_MAJOR}.{self.minor}"

    @property
    def segments(self) -> bool:
        """Segmented files (1.1, §6.7)."""
        return self.minor >= SEGMENTED_MINOR

    @property
    def coding_tools(self) -> bool:
        """faces-traverse, U1's predictor 2 and U3's and CENT's predictor 3 (1.2, §6.8, §6.2)."""
        return self.minor >= CODING_TOOLS_MINOR

    @property
    def corrections(self) -> bool:
        """RESD sections: a bound on every vertex, or lossless (1.3, §6.9)."""
        return self.minor >= CORRECTIONS_MINOR

    @property
    def scene(self) -> bool:
        """The header keys ``time_codes``, ``meters_per_unit`` and ``up_axis`` (1.4, §4)."""
        return self.minor >= SCENE_MINOR

    @property
    def attachments(self) -> bool:
        """ORDER, attributes, face sets and fields (1.5, §6.10 to §6.13)."""
        return self.minor >= ATTACHMENTS_MINOR

    @property
    def adaptive(self) -> bool:
        """The adaptive coder (``coder`` 1) and predictor 2's ``mean_push`` (1.6, §6.14)."""
        return self.minor >= ADAPTIVE_MINOR

    @property
    def adaptive_corrections(self) -> bool:
        """RESD chunks as adaptive streams (``coder`` 1, 1.7, §6.9)."""
        return self.minor >= ADAPTIVE_CORRECTIONS_MINOR

    @property
    def codebooks(self) -> bool:
        """RESD codebooks: lossless corrections as positions in each axis's values (1.8, §6.9)."""
        return self.minor >= CODEBOOKS_MINOR

    @property
    def uniform_ranks(self) -> bool:
        """faces-traverse's new vertices as places among the unseen in a uniform stream
        (``ranks`` 1, 1.9, §6.8)."""
        return self.minor >= UNIFORM_RANKS_MINOR

    def require(self, minor: int, feature: str, what: str, instead: str) -> None:
        """Refuse ``feature`` (what the caller asked for or gave) if it needs format
        ``1.minor`` and this encode is held below it: ``what`` says what of that version it
        needs, ``instead`` what else the caller can do."""
        if minor <= self.minor:
            return
        needs = f"{FORMAT_MAJOR}.{minor}"
        raise FormatVersionError(
            f"{feature} needs format {needs} ({what}), and format_version is {self.version}: "
            f"give format_version {needs} or later, or {instead}",
            feature=feature,
            needs=needs,
            format_version=self.version,
        )


#: Every feature: an encode's default.
NEWEST = Features()

__all__ = [
    "NEWEST",
    "NEWEST_MINOR",
    "VERSIONS",
    "Features",
    "parse_format_version",
]
