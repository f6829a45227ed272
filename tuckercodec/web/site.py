"""The viewer's folder: the page, the scripts it loads, the compressed file and, optionally, the
original's positions to compare with. ``tuckercodec view`` serves such a folder
(:mod:`tuckercodec.web.server`) and ``--export-html`` writes one; both are built here, so the
page served is the page exported. Its layout::

    index.html                  opens viewer/index.html?file=...&reference=... (a redirect)
    viewer/                     the page: index.html, viewer.js, measure.js, viewer.css
    tkc/                        the JavaScript decoder
    three/                      TKCLoader, which the page plays the file with, and its normals
    vendor/three/, vendor/fzstd/   three.js and fzstd, each with its LICENSE
    data/NAME.tkc               the compressed file, byte for byte
    data/reference.json         with a reference: what data/reference.bin holds
    data/reference.bin          F*K*3 little-endian float32, frame by frame, vertex by vertex
    .tuckercodec-output.json    an exported folder only: the manifest of every folder output
                                (:func:`tuckercodec.system.atomic.refuse_unless_ours`)

The reference is the original's positions rounded to float32 (half the size of float64, and
what the GPU draws anyway); ``reference.json`` says so, and also carries two numbers measured
here with the Python decoder against those float32 positions: the largest vertex distance over
all frames (the page's fixed colour scale) and the whole sequence's KG error.
"""

from __future__ import annotations

import html
import json
import re
from collections.abc import Iterator
from dataclasses import dataclass
from importlib import resources
from importlib.resources.abc import Traversable
from pathlib import Path, PurePosixPath
from typing import BinaryIO, Protocol
from urllib.parse import quote

import numpy as np

from ..decoder import Decoder
from ..errors import InputError
from ..measures.distortion import KG_DEFINITION

#: Where the page lives in the folder; the URL to open is this with its query.
PAGE = "viewer/index.html"
#: The folders of the package's web files the page needs, and which of their files.
SHIPPED = {
    "viewer": (".html", ".js", ".css"),
    "tkc": (".js", ".mjs"),
    "three": (".js",),
    "vendor": (".js", ".mjs", ".md", "LICENSE"),
}
REFERENCE_JSON = "data/reference.json"
REFERENCE_BIN = "data/reference.bin"
#: Frames of the reference read, converted and compared at a time.
CHUNK_FRAMES = 32


class ReferenceFrames(Protocol):
    """What a reference is read through: a :class:`tuckercodec.io.FrameSource`, or a decoded
    compressed file adapted to it."""

    frame_count: int
    vertex_count: int

    def read(self, start: int, stop: int) -> np.ndarray:
        """Frames ``start`` to ``stop`` - 1, (n, K, 3) float64."""
        ...


@dataclass(frozen=True)
class Site:
    """A built folder: its files (POSIX paths relative to it) and the URL to open, relative to
    the folder's root (``viewer/index.html?file=...``)."""

    files: tuple[str, ...]
    entry: str
    reference: ReferenceSummary | None = None


@dataclass(frozen=True)
class ReferenceSummary:
    """What comparing the decoded file with the reference measured (float32 reference)."""

    max_distance: float
    kg: float | None


def web_root() -> Traversable:
    """The package's web files (``tuckercodec/web``)."""
    return resources.files("tuckercodec.web")


def page_files() -> list[str]:
    """The packaged files a folder gets (POSIX paths relative to ``tuckercodec/web``), sorted."""
    found: list[str] = []

    def walk(node: Traversable, path: PurePosixPath, endings: tuple[str, ...]) -> None:
        for child in node.iterdir():
            if child.name.startswith((".", "__")):
                continue
            if child.is_dir():
                walk(child, path / child.name, endings)
            elif child.name.endswith(endings):
                found.append(str(path / child.name))

    root = web_root()
    for folder, endings in SHIPPED.items():
        node = root / folder
        if node.is_dir():
            walk(node, PurePosixPath(folder), endings)
    return sorted(found)


def page_policy() -> str:
    """The Content-Security-Policy of the page (its meta tag), which the server also sends as
    an HTTP header: one policy, written once, in the page."""
    page = (web_root() / PAGE).read_text(encoding="utf-8")
    found = re.search(r'http-equiv="Content-Security-Policy" content="([^"]+)"', page)
    if found is None:
        raise RuntimeError(f"{PAGE} has no Content-Security-Policy")  # a broken installation
    return html.unescape(found.group(1))


def data_name(path: str | Path) -> str:
    """The compressed file's name in the folder: its own name where that is a plain, safe URL
    segment, else one with every other character replaced by ``_``; always ending ``.tkc``."""
    stem = re.sub(r"[^A-Za-z0-9._-]", "_", Path(path).stem).lstrip(".") or "file"
    return f"{stem}.tkc"


def build_site(
    folder: Path,
    data: bytes,
    name: str,
    *,
    decoder: Decoder | None = None,
    reference: ReferenceFrames | None = None,
    reference_name: str | None = None,
) -> Site:
    """Write the viewer's folder into ``folder`` (which must exist, empty): the page, its
    scripts, ``data`` (the compressed file, already validated) as ``data/<name>`` and, with
    ``reference``, the original's positions (its frame and vertex counts checked against the
    file's by the caller), measured against ``decoder`` (``data`` opened; opened here if None).

    Raises:
        InputError: a reference position beyond float32's range (it would become infinite).
    """
    root = web_root()
    files = page_files()
    for relative in files:
        target = folder / relative
        target.parent.mkdir(parents=True, exist_ok=True)
        target.write_bytes((root / relative).read_bytes())
    (folder / "data").mkdir(exist_ok=True)
    (folder / "data" / name).write_bytes(data)
    files.append(f"data/{name}")
    query = f"file={quote('../data/' + name)}"
    summary = None
    if reference is not None:
        summary = write_reference(folder, decoder or Decoder(data), reference, reference_name or "")
        files += [REFERENCE_JSON, REFERENCE_BIN]
        query += f"&reference={quote('../' + REFERENCE_JSON)}"
    entry = f"{PAGE}?{query}"
    (folder / "index.html").write_text(redirect_page(entry), encoding="utf-8")
    files.append("index.html")
    return Site(tuple(sorted(files)), entry, summary)


def redirect_page(entry: str) -> str:
    """A page that sends a browser to ``entry`` (a URL, relative or not): the folder's own
    index.html, and the private file ``view --open`` gives the browser."""
    entry = html.escape(entry)
    return (
        '<!doctype html>\n<html lang="en">\n<head>\n<meta charset="utf-8">\n'
        f'<meta http-equiv="refresh" content="0; url={entry}">\n'
        '<title>tuckercodec viewer</title>\n<link rel="icon" href="data:,">\n</head>\n<body>\n'
        f'<p><a href="{entry}">Open the viewer</a>.</p>\n</body>\n</html>\n'
    )


def write_reference(
    folder: Path, decoder: Decoder, reference: ReferenceFrames, name: str
) -> ReferenceSummary:
    """Write ``data/reference.bin`` (the reference rounded to float32, little-endian) and
    ``data/reference.json``, reading the reference a few frames at a time; measure the decoded
    file against the float32 positions as it goes."""
    frames, vertices = reference.frame_count, reference.vertex_count
    with (folder / REFERENCE_BIN).open("wb") as handle:
        summary = _write_positions(handle, decoder, reference, name)
    description = {
        "format": "tuckercodec viewer reference",
        "vertices": vertices,
        "frames": frames,
        "dtype": "float32",
        "byteOrder": "little",
        "data": PurePosixPath(REFERENCE_BIN).name,
        "layout": "frame by frame, vertex by vertex, x y z",
        "source": name,
        "rounding": "the original's positions rounded to float32 (round to nearest even)",
        "maxDistance": summary.max_distance,
        "maxDistanceNote": (
            "the largest distance between a vertex of the decoded file (the Python decoder, "
            "binary64) and the same vertex of these float32 positions, over all frames"
        ),
        "kg": summary.kg,
        "kgDefinition": f"{KG_DEFINITION}; A = these float32 positions, B = the decoded file",
    }
    (folder / REFERENCE_JSON).write_text(json.dumps(description, indent=1), encoding="utf-8")
    return summary


def _chunks(count: int) -> Iterator[tuple[int, int]]:
    for start in range(0, count, CHUNK_FRAMES):
        yield start, min(start + CHUNK_FRAMES, count)


def _write_positions(
    handle: BinaryIO, decoder: Decoder, reference: ReferenceFrames, name: str
) -> ReferenceSummary:
    largest = 0.0
    difference = spread = 0.0
    for start, stop in _chunks(reference.frame_count):
        with np.errstate(over="ignore"):
            rounded = reference.read(start, stop).astype("<f4")
        bad = ~np.isfinite(rounded)
        if bad.any():
            frame = start + int(np.argwhere(bad)[0][0])
            raise InputError(
                "a position is beyond float32's range, where the viewer draws the original",
                path=name or None,
                frame=frame,
            )
        handle.write(rounded.tobytes())
        original = rounded.astype(np.float64)
        decoded = decoder.positions(range(start, stop))
        squared = np.square(original - decoded).sum(axis=2)
        largest = max(largest, float(np.sqrt(squared.max())))
        difference += float(squared.sum())
        centred = original - original.mean(axis=1, keepdims=True)
        spread += float(np.square(centred).sum())
    kg = 100.0 * float(np.sqrt(difference)) / float(np.sqrt(spread)) if spread > 0 else None
    return ReferenceSummary(largest, kg)
