"""Format 1.5: what a file carries beside positions and faces, as ancillary sections.

* ORDER (§6.10): the faces' given order, when FACE's walk reorders them;
* ATTR.n (§6.11): static attributes (UVs, normals, colours...), bit for bit;
* FSET (§6.12): face sets (materials, groups);
* FLD.n, with FLD.n.U1, FLD.n.U3, FLD.n.CORE and FLD.n.MEAN (§6.13): animated fields.

Every one is ancillary (``critical`` false): a decoder of 1.0 to 1.4 skips them and reads the
same positions and faces (in the walk's order), so no flag bit is needed (§10). A decoder of 1.5
knows them: it checks their criticality and codec like §6.6's sections, and every one it reads.

This module names the sections and checks the table (§5 step 19's first part). The codecs are
in :mod:`.face_order`, :mod:`.attributes`, :mod:`.face_sets` and :mod:`.fields`.
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from dataclasses import dataclass

from . import attributes, face_order, face_sets, fields
from .sections import QMAT, Section, check_kind

#: The minor version of a file with any of these sections.
ATTACHMENTS_MINOR = 5

FIELD_STEM = "FLD"
FIELD_CODEC = "field"
#: The factor sections of a field in mode ``tucker``, by suffix.
FIELD_FACTORS = ("U1", "U3", "CORE", "MEAN")

_NUMBER = r"(0|[1-9][0-9]*)"
_ATTRIBUTE_ID = re.compile(rf"{attributes.STEM}\.{_NUMBER}")
_FIELD_ID = re.compile(rf"{FIELD_STEM}\.{_NUMBER}")
_FIELD_FACTOR_ID = re.compile(rf"{FIELD_STEM}\.{_NUMBER}\.({'|'.join(FIELD_FACTORS)})")


def field_id(number: int, factor: str | None = None) -> str:
    """``FLD.n`` or, for a factor of a tucker field, ``FLD.n.U1``..."""
    return f"{FIELD_STEM}.{number}" if factor is None else f"{FIELD_STEM}.{number}.{factor}"


def attachment_codec(section_id: object) -> str | None:
    """The codec of a section of format 1.5 with this id, or None: not one of them."""
    if not isinstance(section_id, str):
        return None
    if section_id == face_order.SECTION_ID:
        return face_order.CODEC
    if section_id == face_sets.SECTION_ID:
        return face_sets.CODEC
    if _ATTRIBUTE_ID.fullmatch(section_id):
        return attributes.CODEC
    if _FIELD_ID.fullmatch(section_id):
        return FIELD_CODEC
    if _FIELD_FACTOR_ID.fullmatch(section_id):
        return QMAT
    return None


@dataclass(frozen=True)
class AttachedSections:
    """The sections of format 1.5 a file has, checked against the table's rules."""

    order: Section | None
    attributes: tuple[Section, ...]
    face_sets: Section | None
    fields: tuple[Section, ...]  # the FLD.n descriptors, in order
    factors: Mapping[str, Section]  # FLD.n.U1... by id

    @property
    def any(self) -> bool:
        return bool(self.order or self.attributes or self.face_sets or self.fields)


def find_attachments(table: tuple[Section, ...]) -> AttachedSections:
    """§5 step 19, first part: each section of 1.5 is ancillary (R27) with its codec (R25); the
    ATTR.n and FLD.n are numbered 0, 1, 2... without a gap (R43, R45), and every factor section
    belongs to a field that has one (R45)."""
    found: dict[str, Section] = {}
    for section in table:
        codec = attachment_codec(section.id)
        if codec is None:
            continue
        check_kind(section, False, (codec,))
        found[section.id] = section
    numbered = {
        stem: sorted(
            int(match.group(1)) for section_id in found if (match := pattern.fullmatch(section_id))
        )
        for stem, pattern in ((attributes.STEM, _ATTRIBUTE_ID), (FIELD_STEM, _FIELD_ID))
    }
    for stem, refuse in ((attributes.STEM, attributes.refuse), (FIELD_STEM, fields.refuse)):
        numbers = numbered[stem]
        if numbers != list(range(len(numbers))):
            gap = next(n for n in range(len(numbers) + 1) if n not in numbers)
            refuse(
                f"sections {stem}.n are numbered 0, 1, 2... without a gap: {stem}.{gap} is missing",
                f"section {stem}.{gap}",
            )
    factors = {}
    for section_id, section in found.items():
        match = _FIELD_FACTOR_ID.fullmatch(section_id)
        if match is None:
            continue
        if int(match.group(1)) >= len(numbered[FIELD_STEM]):
            fields.refuse(
                f"a factor of field {match.group(1)}, which has no section "
                f"{field_id(int(match.group(1)))}",
                f"section {section_id}",
            )
        factors[section_id] = section
    return AttachedSections(
        order=found.get(face_order.SECTION_ID),
        attributes=tuple(found[attributes.section_id(n)] for n in numbered[attributes.STEM]),
        face_sets=found.get(face_sets.SECTION_ID),
        fields=tuple(found[field_id(n)] for n in numbered[FIELD_STEM]),
        factors=factors,
    )


@dataclass(frozen=True)
class AttachmentSummary:
    """One attribute, the face sets or one field, as the section table describes it (read
    without decoding: the parameters are the file's claims, checked only when decoded).

    ``kind`` is ``"attribute"``, ``"face sets"``, ``"field"`` or ``"face order"``; ``bytes``
    counts every section it takes (a field's factors included); ``error`` is a field's
    ``(definition, value, target)`` as its encoder measured it, where recorded."""

    kind: str
    name: str
    description: str
    bytes: int
    error: tuple[str, float | None, float | None] | None = None


def summarize(table: tuple[Section, ...]) -> tuple[AttachmentSummary, ...]:
    """What a file carries beside positions and faces, for ``info``: never fails, whatever the
    parameters hold (a value of the wrong type is shown as it is, or left out)."""
    out: list[AttachmentSummary] = []
    sizes: dict[str, int] = {}
    for section in table:
        match = _FIELD_FACTOR_ID.fullmatch(section.id)
        if match is not None:
            owner = field_id(int(match.group(1)))
            sizes[owner] = sizes.get(owner, 0) + section.length
    for section in table:
        codec = attachment_codec(section.id)
        params = section.params
        if codec == face_order.CODEC:
            out.append(AttachmentSummary("face order", "", "kept as given", section.length))
        elif codec == attributes.CODEC:
            shape = params.get("shape")
            rows = shape[0] if isinstance(shape, list) and len(shape) == 2 else "?"
            cols = shape[1] if isinstance(shape, list) and len(shape) == 2 else "?"
            indexed = ", indexed" if params.get("indexed") is True else ""
            text = (
                f"{_shown(params.get('domain'))}, {_shown(params.get('role'))}, "
                f"{_shown(params.get('type'))} x {cols}, {rows} rows{indexed}"
            )
            out.append(
                AttachmentSummary("attribute", _shown(params.get("name")), text, section.length)
            )
        elif codec == face_sets.CODEC:
            sets = params.get("sets")
            count = len(sets) if isinstance(sets, list) else 0
            families = (
                sorted(
                    {str(entry[1]) for entry in sets if isinstance(entry, list) and len(entry) == 3}
                )
                if isinstance(sets, list)
                else []
            )
            text = f"{count} sets, families {', '.join(f or '(none)' for f in families) or '-'}"
            out.append(AttachmentSummary("face sets", "", text, section.length))
        elif codec == FIELD_CODEC:
            error = params.get("error")
            claim = None
            if isinstance(error, dict):
                claim = (
                    _shown(error.get("definition")),
                    _real(error.get("value")),
                    _real(error.get("target")),
                )
            text = (
                f"{_shown(params.get('domain'))}, {_shown(params.get('role'))}, "
                f"{_shown(params.get('type'))} x {_shown(params.get('components'))}, "
                f"mode {_shown(params.get('mode'))}"
            )
            total = section.length + sizes.get(section.id, 0)
            out.append(AttachmentSummary("field", _shown(params.get("name")), text, total, claim))
    return tuple(out)


def _shown(value: object) -> str:
    return value if isinstance(value, str) else repr(value)


def _real(value: object) -> float | None:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return None
    return float(value)
