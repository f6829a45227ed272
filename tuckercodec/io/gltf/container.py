"""The glTF 2.0 container: a ``.glb`` (12-byte header, a JSON chunk, a BIN chunk) or a ``.gltf``
(JSON, its buffers in data: URIs or in files beside it), taken apart and put together.

Written with :mod:`json`, :mod:`struct` and numpy rather than pygltflib: reading hostile files
needs every size checked against the bytes that are really there before anything is
allocated, and every bad field named, which a permissive object mapper does not do; and the
few parts of the JSON this package writes are plain dictionaries.

Reading checks, in this order: the GLB header (magic, version 2, declared length against the
file's size), each chunk's length against what is left, the JSON (UTF-8, an object), then each
buffer on first use: the BIN chunk, a data: URI (base64, at most :data:`MAX_DATA_URI` characters)
or a file in the same folder as the ``.gltf`` (absolute paths, ``..`` and links leading out of
the folder are refused), at least as long as its ``byteLength``.
"""

from __future__ import annotations

import base64
import binascii
import json
import struct
import urllib.parse
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ...errors import InputError
from ...system.reading import inside_folder, open_input, open_regular_file
from ..common.budget import Inflation, memory_ceiling

GLB_MAGIC = b"glTF"
JSON_CHUNK = 0x4E4F534A
BIN_CHUNK = 0x004E4942
_HEADER = struct.Struct("<4sII")
_CHUNK = struct.Struct("<II")
#: A data: URI longer than this many characters is refused (it would decode to about 192 MiB):
#: beyond that a .glb or a .bin file beside the .gltf is the way to store the data.
MAX_DATA_URI = 256 << 20
_BASE64_PREFIX = ";base64,"


@dataclass
class Document:
    """A parsed glTF: its JSON, the BIN chunk of a .glb, and where it came from.

    ``fail(message)`` makes the :class:`InputError` that names the file; every part of the
    package that finds a problem in the file raises through it.
    """

    path: Path
    gltf: dict[str, Any]
    glb_bin: bytes | None = None
    _buffers: dict[int, memoryview] = field(default_factory=dict)
    #: buffer views decompressed once (EXT_meshopt_compression), by index
    decoded_views: dict[int, memoryview] = field(default_factory=dict)
    #: what those views may still inflate to, together (``--max-memory``)
    inflation: Inflation = field(default_factory=lambda: Inflation(memory_ceiling(None)))
    #: what readers derive once from the file (meshes merged from their primitives...)
    cache: dict[Any, Any] = field(default_factory=dict)

    def fail(self, message: str, frame: int | None = None) -> InputError:
        """An InputError about this file."""
        return InputError(message, path=self.path, frame=frame)

    def array(self, key: str) -> list[Any]:
        """The top-level list ``key`` ("meshes", "accessors"...), empty if absent."""
        value = self.gltf.get(key, [])
        if not isinstance(value, list):
            raise self.fail(f"'{key}' must be a list, got {type(value).__name__}")
        return value

    def item(self, key: str, index: Any, what: str) -> dict[str, Any]:
        """Element ``index`` of the list ``key``, checked to exist and be an object; ``what``
        names who refers to it, for the message."""
        items = self.array(key)
        if not isinstance(index, int) or isinstance(index, bool) or not 0 <= index < len(items):
            raise self.fail(f"{what} refers to {key}[{index!r}], but the file has {len(items)}")
        value = items[index]
        if not isinstance(value, dict):
            raise self.fail(f"{key}[{index}] must be an object")
        return value

    def buffer(self, index: int, what: str) -> memoryview:
        """The bytes of buffer ``index``, loaded once, at least its ``byteLength`` long."""
        if index in self._buffers:
            return self._buffers[index]
        buffer = self.item("buffers", index, what)
        length = integer(self, buffer, "byteLength", f"buffers[{index}]", minimum=1)
        uri = buffer.get("uri")
        if uri is None:
            if index != 0 or self.glb_bin is None:
                raise self.fail(
                    f"buffers[{index}] has no uri and is not the BIN chunk of a .glb"
                    + (" (it may be a fallback of a compression extension)" if index else "")
                )
            data = self.glb_bin
        elif not isinstance(uri, str):
            raise self.fail(f"buffers[{index}].uri must be a string")
        elif uri.startswith("data:"):
            data = _data_uri(self, uri, f"buffers[{index}]")
        else:
            data = _external(self, uri, f"buffers[{index}]")
        if len(data) < length:
            raise self.fail(
                f"buffers[{index}] declares {length} bytes but holds {len(data)}: the file or its "
                "buffer is truncated"
            )
        view = memoryview(data)[:length]
        self._buffers[index] = view
        return view


def integer(
    doc: Document,
    obj: dict[str, Any],
    key: str,
    where: str,
    *,
    default: int | None = None,
    minimum: int = 0,
) -> int:
    """``obj[key]`` as an int >= ``minimum`` (``default`` if absent and one is given)."""
    value = obj.get(key, default)
    if value is None:
        raise doc.fail(f"{where} lacks '{key}'")
    if not isinstance(value, int) or isinstance(value, bool) or value < minimum:
        raise doc.fail(f"{where}.{key} must be an integer >= {minimum}, got {value!r}")
    return value


def read_document(path: Path, inflation: Inflation | None = None) -> Document:
    """Parse a .glb or .gltf file (by its first bytes, not its name); InputError if damaged.
    Its compressed views inflate within ``inflation`` (default: half the machine's memory)."""
    with open_input(path, "a glTF file") as stream:
        data = stream.read()
    if not data.strip():
        raise InputError("the file is empty", path=path)
    if data[:4] == GLB_MAGIC:
        gltf, glb_bin = _parse_glb(data, path)
    else:
        gltf, glb_bin = _parse_json(data, path), None
    doc = Document(path, gltf, glb_bin)
    if inflation is not None:
        doc.inflation = inflation
    asset = gltf.get("asset")
    version = asset.get("version") if isinstance(asset, dict) else None
    if not isinstance(version, str) or not version.startswith("2."):
        raise doc.fail(f"is not glTF 2.0 (asset.version is {version!r})")
    return doc


def _parse_glb(data: bytes, path: Path) -> tuple[dict[str, Any], bytes | None]:
    if len(data) < _HEADER.size + _CHUNK.size:
        raise InputError(f"a .glb of {len(data)} bytes is truncated (no JSON chunk)", path=path)
    _, version, length = _HEADER.unpack_from(data)
    if version != 2:
        raise InputError(f"GLB container version {version}, not 2", path=path)
    if length != len(data):
        raise InputError(
            f"the GLB header declares {length} bytes but the file has {len(data)}: "
            + ("truncated" if length > len(data) else "trailing bytes"),
            path=path,
        )
    offset, chunks = _HEADER.size, []
    while offset < length:
        if length - offset < _CHUNK.size:
            raise InputError(f"a GLB chunk header at byte {offset} is cut short", path=path)
        size, kind = _CHUNK.unpack_from(data, offset)
        start = offset + _CHUNK.size
        if size > length - start:
            raise InputError(
                f"the GLB chunk at byte {offset} declares {size} bytes, beyond the end of the "
                f"file ({length - start} left): the file is truncated",
                path=path,
            )
        chunks.append((kind, data[start : start + size]))
        offset = start + size
    if chunks[0][0] != JSON_CHUNK:
        raise InputError("the first GLB chunk is not JSON", path=path)
    # readers must ignore chunks of unknown types; the BIN chunk, if any, comes second
    glb_bin = chunks[1][1] if len(chunks) > 1 and chunks[1][0] == BIN_CHUNK else None
    return _parse_json(chunks[0][1], path), glb_bin


def _parse_json(text: bytes, path: Path) -> dict[str, Any]:
    try:
        # glTF's JSON has no NaN or Infinity: refuse them rather than let them into positions
        gltf = json.loads(text.decode("utf-8").rstrip(" \0"), parse_constant=_no_constant)
    except (UnicodeDecodeError, ValueError, RecursionError) as error:
        raise InputError(f"the glTF JSON cannot be parsed: {error}", path=path) from None
    if not isinstance(gltf, dict):
        raise InputError("the glTF JSON is not an object", path=path)
    return gltf


def _no_constant(name: str) -> Any:
    raise ValueError(f"{name} is not a JSON number")


def _data_uri(doc: Document, uri: str, where: str) -> bytes:
    if len(uri) > MAX_DATA_URI:
        raise doc.fail(
            f"{where}: a data: URI of {len(uri)} characters, beyond the {MAX_DATA_URI} this "
            "reader accepts (store large buffers in a .glb or a .bin file)"
        )
    head, marker, payload = uri.partition(_BASE64_PREFIX)
    if not marker or "," in head:
        raise doc.fail(f"{where}: a data: URI that is not base64")
    try:
        return base64.b64decode(payload, validate=True)
    except (binascii.Error, ValueError) as error:
        raise doc.fail(f"{where}: bad base64 in its data: URI ({error})") from None


def _external(doc: Document, uri: str, where: str) -> bytes:
    """The bytes of a buffer's file, which must lie inside the .gltf's folder (an absolute
    path, a URL, or one that leads out through ``..`` or a link is refused, as for every
    reader: :func:`~tuckercodec.system.reading.inside_folder`)."""
    name = urllib.parse.unquote(uri)
    try:
        target = inside_folder(doc.path.parent, name)
    except InputError as error:
        raise doc.fail(f"{where}: its uri {error.reason}") from None
    if ("file", target) in doc.cache:  # several buffers of one file: read once, shared
        data: bytes = doc.cache["file", target]
        return data
    if not target.exists():
        raise doc.fail(f"{where}: its file {name!r} is missing (looked for {target})")
    try:
        with open_regular_file(target, f"the buffer file of {where}") as stream:
            data = doc.cache["file", target] = stream.read()
            return data
    except OSError as error:
        raise doc.fail(f"{where}: cannot read {name!r}: {error.strerror or error}") from None


def pack_glb(gltf: dict[str, Any], binary: bytes) -> bytes:
    """A .glb: the JSON chunk (padded with spaces) and the BIN chunk (padded with zeros)."""
    text = json.dumps(gltf, separators=(",", ":"), allow_nan=False).encode()
    text += b" " * (-len(text) % 4)
    binary += b"\0" * (-len(binary) % 4)
    chunks = _CHUNK.pack(len(text), JSON_CHUNK) + text
    if binary:
        chunks += _CHUNK.pack(len(binary), BIN_CHUNK) + binary
    return _HEADER.pack(GLB_MAGIC, 2, _HEADER.size + len(chunks)) + chunks


def pack_gltf(gltf: dict[str, Any], binary: bytes) -> bytes:
    """A self-contained .gltf: the buffer in a base64 data: URI (one file, written atomically)."""
    if binary:
        gltf = dict(gltf)
        encoded = base64.b64encode(binary).decode("ascii")
        first = {**gltf["buffers"][0], "uri": f"data:application/octet-stream;base64,{encoded}"}
        gltf["buffers"] = [first, *gltf["buffers"][1:]]
    return json.dumps(gltf, indent=1, allow_nan=False).encode()
