"""The point and cell data of one VTK XML piece (``<PointData>``, ``<CellData>``): read as
:class:`~tuckercodec.io.common.data_arrays.SourceArray`\\ s, and written.

Each ``<DataArray>`` of a number type with a ``Name`` is read, one row per point or cell, with
its ``NumberOfComponents``; the active attributes of the section (``Normals="..."``,
``TCoords="..."``) give roles, as does the tag this package's writer adds
(:data:`~tuckercodec.io.common.data_arrays.ROLE_TAG`). Arrays not read are noted (a string or
bit array, one without a name, one of more than 4 components: never decoded). Errors are
:class:`InputError`\\ s without a path (the caller names the file).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from xml.etree import ElementTree

from ...errors import InputError
from ...model.attributes import FACE, NORMAL, ROLES, UV, VERTEX
from ..common.data_arrays import ROLE_TAG, STATIC_TAG, SourceArray, TargetArray
from .arrays import TYPES, Encoding, read_array

#: The sections of a piece and the domain of their arrays.
SECTIONS = {"PointData": VERTEX, "CellData": FACE}
#: VTK's active attributes that name a role.
_ACTIVE_ROLES = {"Normals": NORMAL, "TCoords": UV}
_ROLE_NAMES = (*ROLES, "velocity")


@dataclass(frozen=True)
class PieceData:
    """The arrays read from one piece, by (domain, name), and the notes of those left out."""

    arrays: dict[tuple[str, str], SourceArray]
    skipped: list[str]


def read_piece_data(
    piece: ElementTree.Element,
    encoding: Encoding,
    counts: dict[str, int],
    wanted: set[tuple[str, str]] | None,
) -> PieceData:
    """The point and cell arrays of ``piece`` (``counts``: its points and cells); only those
    in ``wanted`` (by (domain, name)) when it is given."""
    arrays: dict[tuple[str, str], SourceArray] = {}
    skipped: list[str] = []
    for section, domain in SECTIONS.items():
        element = piece.find(section)
        if element is None:
            continue
        active = {element.get(key): role for key, role in _ACTIVE_ROLES.items() if element.get(key)}
        where = "point" if domain == VERTEX else "cell"
        for number, child in enumerate(element.findall("DataArray")):
            name = child.get("Name")
            if not name:
                skipped.append(f"{where} array {number}: it has no name")
                continue
            if wanted is not None and (domain, name) not in wanted:
                continue
            label = f"{where} array {name!r}"
            if (domain, name) in arrays:
                raise InputError(f"{label}: the piece holds two arrays of that name")
            kind = child.get("type", "")
            components = child.get("NumberOfComponents", "1").strip()
            if kind not in TYPES:
                skipped.append(f"{label}: of type {kind!r} (numbers are kept)")
                continue
            if components not in ("1", "2", "3", "4"):
                skipped.append(f"{label}: {components} components (1 to 4 are kept)")
                continue
            width = int(components)
            values = read_array(
                child, encoding, label, components=width, count=counts[domain]
            ).reshape(counts[domain], width)
            tag = child.get(ROLE_TAG)
            role = tag if tag in _ROLE_NAMES else active.get(name)
            static = child.get(STATIC_TAG) == "1"
            arrays[domain, name] = SourceArray(name, domain, values, role, static)
    return PieceData(arrays, skipped)


def data_xml(
    targets: list[TargetArray], frame: int, element: Callable[..., str], section: str
) -> str:
    """The ``<PointData>`` or ``<CellData>`` of ``targets`` at ``frame`` ("" without any);
    ``element(name, dtype, data, extra)`` writes one ``<DataArray>``."""
    if not targets:
        return ""
    active = {}
    for key, role in _ACTIVE_ROLES.items():
        found = next((t for t in targets if t.static and t.role == role), None)
        if found is not None:
            active[key] = found.name
    head = "".join(f' {key}="{quoted(name)}"' for key, name in active.items())
    arrays = []
    for target in targets:
        values = target.at(frame)
        extra = f' NumberOfComponents="{values.shape[1]}" {ROLE_TAG}="{target.role}"'
        if target.static:
            extra += f' {STATIC_TAG}="1"'
        arrays.append(element(target.name, values.dtype, values, extra))
    return f"<{section}{head}>\n" + "\n".join(arrays) + f"\n</{section}>\n"


def quoted(text: str) -> str:
    """``text`` as an XML attribute value between double quotes."""
    return (
        text.replace("&", "&amp;").replace("<", "&lt;").replace('"', "&quot;").replace(">", "&gt;")
    )
