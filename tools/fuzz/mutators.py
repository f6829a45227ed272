"""How an input of several files is written in one byte string, and the mutations that know a
format's structure: libFuzzer's byte mutations alone rarely get past a zip member's CRC, a
GLB chunk's length or a JSON document's syntax, so these edit one value inside and put the
container back together, as the .tkc mutator re-signs a file (:mod:`.container`).

Every mutator takes ``(data, rng, mutate_bytes)``, where ``mutate_bytes(data, max_size)`` is
libFuzzer's own mutation (``atheris.Mutate``), and returns the new bytes or ``None`` when the
input is not of its kind. None of them imports tuckercodec.
"""

from __future__ import annotations

import io
import json
import random
import re
import struct
import warnings
import zipfile
from collections.abc import Callable
from typing import Any

#: A bundle: this magic, then for each file a u8 name length, the name (UTF-8, a relative
#: path of at most two parts), a u32 little-endian length and the bytes.
BUNDLE_MAGIC = b"TKCFUZZ1"
_NAME_PART = re.compile(r"[A-Za-z0-9_][A-Za-z0-9._-]{0,63}")

MutateBytes = Callable[[bytes, int], bytes]

EDGE_INTS = [0, 1, -1, 2, 3, 4, 7, 8, 255, 256, 65535, 65536, 2**24, 2**31 - 1, 2**31]
EDGE_INTS += [2**32 - 1, 2**32, 2**53 + 1, 2**63 - 1, -(2**31), -(2**63), 10**9, 10**12]
EDGE_NUMBERS = [str(n) for n in EDGE_INTS] + ["0.0", "-0.0", "1e308", "-1e308", "5e-324"]
EDGE_NUMBERS += ["nan", "NaN", "inf", "-inf", "Infinity", "1e400", "0x10", "1_0", "", "-", "."]


def bundle(files: list[tuple[str, bytes]]) -> bytes:
    """One byte string holding ``files`` (name, bytes), the first being the one read."""
    out = bytearray(BUNDLE_MAGIC)
    for name, data in files:
        encoded = name.encode()
        out += bytes([len(encoded)]) + encoded + struct.pack("<I", len(data)) + data
    return bytes(out)


def safe_name(name: str, index: int) -> str:
    """``name`` if it is a harmless relative path (at most a folder and a file, no ``..``,
    no hidden parts), else ``f{index}``: a fuzzed bundle never writes outside its folder."""
    parts = name.split("/")
    if 1 <= len(parts) <= 2 and all(_NAME_PART.fullmatch(p) and p != ".." for p in parts):
        return name
    return f"f{index}"


def unbundle(data: bytes) -> list[tuple[str, bytes]] | None:
    """The files of a bundle, leniently (a cut length takes what is there), or ``None`` when
    ``data`` is not one. Names are made safe (:func:`safe_name`) and unique."""
    if not data.startswith(BUNDLE_MAGIC):
        return None
    files: list[tuple[str, bytes]] = []
    names: set[str] = set()
    at = len(BUNDLE_MAGIC)
    while at < len(data) and len(files) < 16:
        size = data[at]
        name = data[at + 1 : at + 1 + size].decode("utf-8", "replace")
        at += 1 + size
        (length,) = struct.unpack("<I", data[at : at + 4].ljust(4, b"\0"))
        body = data[at + 4 : at + 4 + length]
        at += 4 + length
        name = safe_name(name, len(files))
        if name in names:
            name = f"f{len(files)}"
        names.add(name)
        files.append((name, body))
    return files or None


# ------------------------------------------------------------------------------------------
# value-level edits


def edge_number(rng: random.Random) -> str:
    return rng.choice(EDGE_NUMBERS)


_NUMBER = re.compile(rb"-?\d+(?:\.\d*)?(?:[eE][-+]?\d+)?")


def mutate_number_token(data: bytes, rng: random.Random) -> bytes | None:
    """Replace one number written in text (OBJ, XML attributes and data, JSON, an .npy
    header) with an edge value: a count, an index, an offset at its limits."""
    found = list(_NUMBER.finditer(data[:65536]))
    if not found:
        return None
    match = rng.choice(found)
    return data[: match.start()] + edge_number(rng).encode() + data[match.end() :]


_ATTRIBUTE = re.compile(rb'([A-Za-z_:][\w:.-]*)="([^"]*)"')


def mutate_xml_attribute(data: bytes, rng: random.Random) -> bytes | None:
    """Set one XML attribute to an edge number, an empty or odd string, or another attribute's
    value; or drop it."""
    found = list(_ATTRIBUTE.finditer(data[:65536]))
    if not found:
        return None
    match = rng.choice(found)
    what = rng.randrange(5)
    if what == 0:
        return data[: match.start()] + data[match.end() :]
    if what == 1:
        value = rng.choice(found).group(2)
    elif what == 2:
        value = rng.choice([b"", b" ", b"../x", b"/etc/passwd", b"x.h5:/", b"Float", b"8", b"a"])
    else:
        words = match.group(2).split()
        if words:
            words[rng.randrange(len(words))] = edge_number(rng).encode()
            value = b" ".join(words)
        else:
            value = edge_number(rng).encode()
    return data[: match.start(2)] + value + data[match.end(2) :]


def _json_paths(value: Any, path: tuple[Any, ...] = ()) -> list[tuple[Any, ...]]:
    out = [path]
    if isinstance(value, dict):
        for key, item in value.items():
            out += _json_paths(item, (*path, key))
    elif isinstance(value, list):
        for index, item in enumerate(value[:64]):
            out += _json_paths(item, (*path, index))
    return out


def _hostile_json(rng: random.Random, current: Any) -> Any:
    kind = rng.randrange(8)
    if kind == 0 and isinstance(current, int) and not isinstance(current, bool):
        return current + rng.choice([-1, 1, current, -current, 4, -4])
    if kind <= 2:
        return rng.choice(EDGE_INTS)
    if kind == 3:
        return rng.choice([None, True, False, 0.5, -1.5, 1e308, "", "x", [], {}])
    if kind == 4 and isinstance(current, list) and current:
        return current[: rng.randrange(len(current))] or current * 2
    if kind == 5:
        return rng.choice(["SCALAR", "VEC3", "MAT4", "data:,", "../x.bin", "a.bin", "LINEAR"])
    if kind == 6:
        return [rng.choice(EDGE_INTS) for _ in range(rng.choice([0, 1, 3, 16]))]
    return rng.choice([5120, 5121, 5122, 5123, 5125, 5126, 34962, 34963, 4, 0, 1])


def mutate_json(data: bytes, rng: random.Random) -> bytes | None:
    """Parse a JSON document, change, drop or add one value anywhere, and write it again."""
    try:
        document = json.loads(data)
    except (ValueError, RecursionError):
        return None
    paths = [p for p in _json_paths(document) if p]
    if not paths:
        return None
    path = rng.choice(paths)
    parent = document
    for key in path[:-1]:
        parent = parent[key]
    if isinstance(parent, dict) and rng.random() < 0.15:
        del parent[path[-1]]
    elif isinstance(parent, list) and rng.random() < 0.1:
        parent.append(parent[path[-1]])
    else:
        parent[path[-1]] = _hostile_json(rng, parent[path[-1]])
    return json.dumps(document, separators=(",", ":")).encode()


def mutate_binary_int(data: bytes, rng: random.Random) -> bytes | None:
    """Write an edge integer, 4 or 8 bytes, either byte order, over bytes of a binary header
    (most often within its first 128 bytes): counts, offsets and lengths."""
    if len(data) < 4:
        return None
    width = rng.choice([4, 4, 8])
    span = min(len(data), 128) if rng.random() < 0.7 else len(data)
    at = rng.randrange(max(1, span - width + 1))
    value = rng.choice(EDGE_INTS) % (1 << (8 * width))
    packed = value.to_bytes(width, rng.choice(["little", "big"]))
    return data[:at] + packed[: len(data) - at] + data[at + width :]


# ------------------------------------------------------------------------------------------
# containers: edit a part, put the whole back together


def mutate_zip(data: bytes, rng: random.Random, inner: Callable[[bytes], bytes]) -> bytes | None:
    """An .npz: change one member with ``inner`` (or rename, drop or repeat one), and write the
    archive again with right CRCs and sizes, each member stored or deflated as it was."""
    try:
        with zipfile.ZipFile(io.BytesIO(data)) as archive:
            members = [(info, archive.read(info)) for info in archive.infolist()]
    except Exception:  # any damage means "not a zip we can rebuild", never a crash here
        return None
    if not members:
        return None
    index = rng.randrange(len(members))
    info, body = members[index]
    what = rng.randrange(10)
    if what == 0:
        name = rng.choice(["V.npy", "F.npy", "frame_files.npy", "frame_rate.npy", "x.npy", "V"])
        members[index] = (zipfile.ZipInfo(name), body)
    elif what == 1 and len(members) > 1:
        del members[index]
    elif what == 2:
        members.append((info, body))
    else:
        members[index] = (info, inner(body))
    out = io.BytesIO()
    with warnings.catch_warnings(), zipfile.ZipFile(out, "w") as archive:
        warnings.simplefilter("ignore")  # a name twice, on purpose: zipfile warns
        for member, content in members:
            method = member.compress_type if member.compress_type in (0, 8) else 8
            archive.writestr(member.filename, content, compress_type=method)
    return out.getvalue()


def mutate_glb(data: bytes, rng: random.Random, inner: Callable[[bytes], bytes]) -> bytes | None:
    """A GLB: change its JSON chunk (as JSON, or with ``inner``) or its BIN chunk with
    ``inner``, and write the header and chunk lengths again."""
    if len(data) < 20 or data[:4] != b"glTF":
        return None
    chunks: list[tuple[int, bytes]] = []
    at = 12
    while at + 8 <= len(data) and len(chunks) < 4:
        length, kind = struct.unpack_from("<II", data, at)
        chunks.append((kind, data[at + 8 : at + 8 + length]))
        at += 8 + length
    if not chunks:
        return None
    index = rng.randrange(len(chunks))
    kind, body = chunks[index]
    new = mutate_json(body, rng) if kind == 0x4E4F534A and rng.random() < 0.7 else None
    chunks[index] = (kind, new if new is not None else inner(body))
    out = bytearray()
    for kind, body in chunks:
        if rng.random() < 0.97:  # now and then keep a stale padding, to reach the checks
            body += (b" " if kind == 0x4E4F534A else b"\0") * (-len(body) % 4)
        out += struct.pack("<II", len(body), kind) + body
    version = struct.unpack_from("<I", data, 4)[0]
    return b"glTF" + struct.pack("<II", version, 12 + len(out)) + bytes(out)


def text_or_bytes(
    data: bytes, rng: random.Random, max_size: int, mutate_bytes: MutateBytes
) -> bytes:
    """One edit of a file: for text, an XML attribute, a JSON value or a number token often;
    a binary header integer now and then; else libFuzzer's byte mutation."""
    choice = rng.random()
    out: bytes | None = None
    if choice < 0.15:
        out = mutate_json(data, rng)
    elif choice < 0.3:
        out = mutate_xml_attribute(data, rng)
    elif choice < 0.45:
        out = mutate_number_token(data, rng)
    elif choice < 0.55:
        out = mutate_binary_int(data, rng)
    if out is None or len(out) > max_size:
        out = mutate_bytes(data, max_size)
    return out


def mutate_file(data: bytes, rng: random.Random, max_size: int, mutate_bytes: MutateBytes) -> bytes:
    """One structure-aware edit of one file of any of the readers' formats."""
    edit: Callable[[bytes], bytes] = lambda body: text_or_bytes(  # noqa: E731
        body, rng, max(len(body) + 64, 256), mutate_bytes
    )
    out: bytes | None = None
    if data[:2] == b"PK" and rng.random() < 0.6:
        out = mutate_zip(data, rng, edit)
    elif data[:4] == b"glTF" and rng.random() < 0.6:
        out = mutate_glb(data, rng, edit)
    if out is None or len(out) > max_size:
        out = text_or_bytes(data, rng, max_size, mutate_bytes)
    return out


def mutate_bundle(data: bytes, max_size: int, seed: int, mutate_bytes: MutateBytes) -> bytes:
    """libFuzzer's custom mutator for the readers: one file of a bundle (or the single file)
    edited with :func:`mutate_file`, now and then a file dropped, repeated or renamed."""
    rng = random.Random(seed)
    files = unbundle(data)
    if files is None:
        return mutate_file(data, rng, max_size, mutate_bytes)
    index = rng.randrange(len(files))
    name, body = files[index]
    what = rng.random()
    if what < 0.03 and len(files) > 1:
        del files[index]
    elif what < 0.05:
        files.append((name + rng.choice(["", ".h5", ".vtp", ".bin"]), body))
    elif what < 0.08:
        files[index] = (rng.choice(["x.h5", "a.bin", "d/frame_00000.vtp", "a.vtu", name]), body)
    else:
        others = sum(len(n) + 5 + len(b) for n, b in files) - len(body) + len(BUNDLE_MAGIC)
        files[index] = (name, mutate_file(body, rng, max(16, max_size - others), mutate_bytes))
    out = bundle(files)
    return out if len(out) <= max_size else mutate_bytes(data, max_size)
