"""XML parsed with every declaration refused by the parser itself, not by a byte filter.

A DOCTYPE's internal subset may declare entities that expand a few hundred bytes into
gigabytes (billion laughs), or attribute defaults that change what elements say. Looking for
``<!ENTITY`` in the bytes is not enough: a comment, or an encoding other than UTF-8 (UTF-16),
hides it. Here expat reports each declaration as it parses it, whatever the encoding or what
comes before, and the first one ends the parse with an :class:`InputError` (without a path: the
caller names the file). The tree is built as ElementTree builds it (``{uri}name`` tags, comments
and processing instructions dropped).
"""

from __future__ import annotations

import re
from typing import Any, NoReturn
from xml.etree import ElementTree
from xml.parsers import expat

from ...errors import InputError

#: The encodings expat reads itself. For any other it asks Python's codecs, which fail in many
#: ways on a crafted name: LookupError ("utf4", "rot13"), ValueError (every multi-byte one),
#: UnicodeError ("idna"), a DeprecationWarning ("unicode_escape"). Found by fuzzing (tools.fuzz).
EXPAT_ENCODINGS = frozenset({"utf-8", "utf-16", "utf-16be", "utf-16le", "iso-8859-1", "us-ascii"})
_DECLARED = re.compile(r"<\?xml\s[^>]*?\bencoding\s*=\s*(['\"])(.*?)\1", re.DOTALL)


def declared_encoding(data: bytes) -> str | None:
    """The encoding the XML declaration at the start of ``data`` names, or None: read as
    UTF-16 when the bytes start so (with or without a byte-order mark), else byte by byte
    (after UTF-8's mark, if any)."""
    head = data[:512].removeprefix(b"\xef\xbb\xbf")  # UTF-8's byte-order mark
    if head[:2] in (b"\xff\xfe", b"<\x00"):
        text = head.decode("utf-16-le", "replace")
    elif head[:2] in (b"\xfe\xff", b"\x00<"):
        text = head.decode("utf-16-be", "replace")
    else:
        text = head.decode("latin-1")
    found = _DECLARED.match(text.lstrip("\ufeff"))
    return found.group(2) if found else None


def parse_xml(data: bytes, kind: str, doctype: bool = False) -> ElementTree.Element:
    """The root element of the XML ``data`` of a ``kind`` file ("VTK", "XDMF"). A DOCTYPE is
    refused unless ``doctype`` (XDMF files written by VTK carry ``<!DOCTYPE Xdmf SYSTEM
    "Xdmf.dtd" []>``, which is never fetched); any declaration inside one (ENTITY, ELEMENT,
    ATTLIST, NOTATION) is refused always, and so is a reference to an entity not declared, and
    an encoding other than expat's own (:data:`EXPAT_ENCODINGS`)."""
    encoding = declared_encoding(data)
    if encoding is not None and encoding.lower() not in EXPAT_ENCODINGS:
        raise InputError(
            f"declares the encoding {encoding[:40]!r}: {kind} files are read in UTF-8, UTF-16, "
            "ISO-8859-1 or US-ASCII"
        )
    builder = ElementTree.TreeBuilder()
    parser = expat.ParserCreate(namespace_separator="}")
    parser.SetParamEntityParsing(expat.XML_PARAM_ENTITY_PARSING_NEVER)
    parser.buffer_text = True

    def refuse(declaration: str) -> NoReturn:
        raise InputError(
            f"declares {declaration}, which {kind} files never need: refused, as the way to an "
            "entity-expansion attack"
        )

    def start_doctype(*_: Any) -> None:
        if not doctype:
            refuse("!DOCTYPE")

    def skipped(name: str, *_: Any) -> NoReturn:
        raise InputError(f"refers to the entity &{name}; which it does not declare")

    def fix(name: str) -> str:
        return "{" + name if "}" in name else name

    def start(tag: str, attributes: dict[str, str]) -> None:
        builder.start(fix(tag), {fix(key): value for key, value in attributes.items()})

    parser.StartDoctypeDeclHandler = start_doctype
    parser.EntityDeclHandler = lambda *_: refuse("!ENTITY")
    parser.UnparsedEntityDeclHandler = lambda *_: refuse("!ENTITY")
    parser.ElementDeclHandler = lambda *_: refuse("!ELEMENT")
    parser.AttlistDeclHandler = lambda *_: refuse("!ATTLIST")
    parser.NotationDeclHandler = lambda *_: refuse("!NOTATION")
    parser.SkippedEntityHandler = skipped
    parser.ExternalEntityRefHandler = lambda *_: refuse("an external entity")
    parser.StartElementHandler = start
    parser.EndElementHandler = lambda tag: builder.end(fix(tag))
    parser.CharacterDataHandler = builder.data
    try:
        parser.Parse(data, True)
    except expat.ExpatError as error:
        raise InputError(f"is not well-formed XML: {error}") from None
    return builder.close()
