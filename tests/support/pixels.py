"""The original of a sequence and its ``.tkc`` drawn alike by three.js in headless Chromium, to
compare their pixels (tests/test_attributes_pixels_browser.py, ``python -m tools.pixels``).

A folder is laid out as the viewer's (:func:`tuckercodec.web.site.page_files`: ``three/``,
``tkc/``, ``vendor/``...) with tests/js/pixels.html and its script as ``pixels/``, the
compressed file as ``data/NAME.tkc`` and the source's arrays for one frame as
``data/original.json`` + ``data/original.bin``: the frame's positions rounded to float32 (what
the GPU draws), the faces, the UV and the colour of every corner (the source's attribute of
role ``uv`` and of role ``color`` read through their domain and indices: the values as they
are) and each ``materialBind`` face set's faces. The viewer's server
(:class:`tuckercodec.web.server.ViewerServer`) serves it; the page draws the original, built
from those arrays, or the file through TKCLoader (tests/js/pixels_page.mjs says how).

:func:`loader_corners` is what the loader's geometry must hold, triangle corner by triangle
corner, computed here from the sequence alone (faces fanned, grouped by material as the loader's
README says), for the exact comparison.
"""

from __future__ import annotations

import json
import shutil
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from tests.support.browser import Browser, Page
from tests.support.png import decode_png
from tuckercodec import Attribute, MeshSequence
from tuckercodec.model.attributes import corner_faces, corner_vertices, face_corner_starts
from tuckercodec.web.server import ViewerServer
from tuckercodec.web.site import page_files, web_root

ROOT = Path(__file__).resolve().parents[2]
#: The page and its script, from tests/js, and where the folder holds them.
PAGE_FILES = {
    "pixels/index.html": "tests/js/pixels.html",
    "pixels/page.mjs": "tests/js/pixels_page.mjs",
}
#: Seconds the page may take to fetch and open everything.
OPEN_SECONDS = 60.0


def per_corner(sequence: MeshSequence, attribute: Attribute) -> np.ndarray:
    """The attribute's value at every corner (corner order), in its own dtype."""
    faces = sequence.faces
    element = {
        "vertex": corner_vertices(faces),
        "corner": np.arange(int((faces >= 0).sum())),
        "face": corner_faces(faces),
    }[attribute.domain]
    rows = element if attribute.indices is None else np.asarray(attribute.indices)[element]
    return np.asarray(attribute.values)[rows]


def first_of_role(sequence: MeshSequence, role: str) -> Attribute:
    """The sequence's first attribute of ``role``: the one the loader draws."""
    for attribute in sequence.attributes:
        if attribute.role == role:
            return attribute
    raise ValueError(f"the sequence has no attribute of role {role!r}")


def materials(sequence: MeshSequence) -> list[tuple[str, np.ndarray]]:
    """(name, faces) of each ``materialBind`` face set, in the sequence's order."""
    return [
        (face_set.name, np.asarray(face_set.faces))
        for face_set in sequence.face_sets
        if face_set.family == "materialBind"
    ]


@dataclass(frozen=True)
class LoaderCorners:
    """What TKCLoader's geometry must show at each index entry (triangle corner), in its order:
    the corner of the sequence each is (corner order), and the groups (start, count, material
    number) and material names."""

    corners: np.ndarray
    groups: list[tuple[int, int, int]]
    material_names: list[str | None]


def loader_corners(sequence: MeshSequence) -> LoaderCorners:
    """The triangles as the loader's README describes them: each face fanned from its first
    corner, the faces of each ``materialBind`` set in the file's order (a face in two sets with
    the first), then the faces of none, each material one group."""
    faces = sequence.faces
    starts = face_corner_starts(faces)
    sets = materials(sequence)
    material = np.full(faces.shape[0], len(sets))
    for number in range(len(sets) - 1, -1, -1):
        material[sets[number][1]] = number
    corners: list[int] = []
    groups = []
    for number in range(len(sets) + 1):
        start = len(corners)
        for face in np.flatnonzero(material == number):
            first, end = int(starts[face]), int(starts[face + 1])
            for corner in range(first + 1, end - 1):
                corners += [first, corner, corner + 1]
        if sets and len(corners) > start:
            groups.append((start, len(corners) - start, number))
    names: list[str | None] = [name for name, _ in sets]
    if sets and (material == len(sets)).any():
        names.append(None)
    return LoaderCorners(np.array(corners, dtype=np.int64), groups, names)


def write_folder(folder: Path, sequence: MeshSequence, data: bytes, frame: int) -> list[str]:
    """Lay out the page's folder in ``folder`` (empty); its files, relative to it."""
    root = web_root()
    files = page_files()
    for relative in files:
        target = folder / relative
        target.parent.mkdir(parents=True, exist_ok=True)
        target.write_bytes((root / relative).read_bytes())
    for served, source in PAGE_FILES.items():
        (folder / served).parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(ROOT / source, folder / served)
    (folder / "data").mkdir()
    (folder / "data" / "file.tkc").write_bytes(data)
    arrays = {
        "positions": sequence.vertices[frame].astype("<f4"),
        "faces": sequence.faces.astype("<i4"),
        "uv": per_corner(sequence, first_of_role(sequence, "uv")).astype("<f4"),
        "color": per_corner(sequence, first_of_role(sequence, "color")).astype("<f4"),
        **{f"set:{name}": faces.astype("<i4") for name, faces in materials(sequence)},
    }
    described, blob, offset = {}, bytearray(), 0
    for name, array in arrays.items():
        raw = np.ascontiguousarray(array).tobytes()
        described[name] = {"dtype": array.dtype.name, "offset": offset, "length": array.size}
        blob += raw
        offset += len(raw)
    description = {
        "tkc": "file.tkc",
        "frame": frame,
        "faces": int(sequence.faces.shape[0]),
        "width": int(sequence.faces.shape[1]),
        "materials": [name for name, _ in materials(sequence)],
        "arrays": described,
    }
    (folder / "data" / "original.bin").write_bytes(bytes(blob))
    (folder / "data" / "original.json").write_text(json.dumps(description), encoding="utf-8")
    return [*files, *PAGE_FILES, "data/file.tkc", "data/original.bin", "data/original.json"]


@contextmanager
def pixels_page(
    browser: Browser, folder: Path, sequence: MeshSequence, data: bytes, frame: int
) -> Iterator[Page]:
    """The page, ready, for ``sequence`` and its compressed file ``data`` at ``frame``."""
    files = write_folder(folder, sequence, data, frame)
    with ViewerServer(folder, files) as server:
        page = browser.new_page(server.address("pixels/index.html"), timeout=OPEN_SECONDS)
        try:
            page.evaluate("window.tkcPixels.ready.then(() => true)", timeout=OPEN_SECONDS)
            yield page
        finally:
            page.close()


def draw(page: Page, which: str, control: str | None = None) -> tuple[np.ndarray, bytes]:
    """Draw ``original`` or ``decoded`` (with a negative ``control``: ``reversed-uv`` or
    ``next-uv``); the canvas's pixels (height, width, 3) int16 and its screenshot's PNG."""
    size = page.evaluate(f"window.tkcPixels.draw({json.dumps(which)}, {json.dumps(control)})")
    png = page.screenshot(clip=(0, 0, size["width"], size["height"]))
    return decode_png(png).astype(np.int16)[..., :3], png


@dataclass(frozen=True)
class Difference:
    """How two pictures differ: the fraction of pixels whose largest channel difference is over
    ``threshold`` (of 255), and the mean absolute difference over every channel of every pixel
    (of 255)."""

    threshold: int
    fraction: float
    mean: float


def difference(a: np.ndarray, b: np.ndarray, threshold: int) -> Difference:
    """Compare two pictures of one size (see :class:`Difference`)."""
    absolute = np.abs(a.astype(np.int16) - b.astype(np.int16))
    return Difference(
        threshold, float((absolute.max(axis=2) > threshold).mean()), float(absolute.mean())
    )


def covered(picture: np.ndarray) -> float:
    """The fraction of the picture that is not the background (its corner pixel's colour)."""
    return float((np.abs(picture - picture[0, 0]).max(axis=2) > 8).mean())
