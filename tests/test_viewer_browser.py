"""The viewer page in a real browser (headless Chromium, driven by tests/support/browser.py over the
DevTools protocol), served by the project's own server, as ``tuckercodec view`` serves it.

The page plays the file with TKCLoader (tuckercodec/web/three, the npm package's loader), so what
is checked here is the loader in a browser: the positions drawn are its mesh's position
attribute. For the built-in cloth and for samba (../shared/data), both encoded at KG 0.1 with the
original as the reference, the page steps to a few frames; at each, through ``window.tkcViewer``:

- the positions drawn (float32, in the file's vertex order) are the Python decode of that frame
  within spec §8's tolerance plus float32 rounding, and the JavaScript decoder's binary64 frame
  within §8's tolerance alone;
- the frame's KG error the page shows is the one Python computes from the same float32 original
  and drawn positions (relative 1e-6), and so is its largest vertex distance;
- a screenshot of the canvas shows a mesh around its centre, which changes with the frame;
- the console holds no error and no exception.

The cloth encoded with corrections (format 1.3, lossless and with --max-error) decodes in the
page to the Python decoder's bits, and the panel shows the bound its header claims.

A truncated file shows its rule (the Python decoder's) on the page and logs it, its one console
error. And the conformance vectors of spec/vectors are decoded in the browser by
tests/js/conformance.html with the observations test_js_conformance.py judges in node.
Skips, naming what is missing, where chromium is not installed (Debian: ``apt-get install
chromium``) or ../shared/data is absent (samba only).
"""

from __future__ import annotations

import json
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import tuckercodec
from tests.support.browser import Browser, Page, find_chromium
from tests.support.compressed import chunked_file
from tests.support.js_decoder import (
    EXPECTED,
    INVALID,
    VALID,
    check_every_vector_observed,
    check_invalid_observation,
    check_valid_observation,
)
from tests.support.png import decode_png
from tests.support.sequences import shared_encoded, shared_sequence
from tuckercodec import Decoder, EncodeOptions, FormatError, MeshSequence
from tuckercodec.web.server import ViewerServer
from tuckercodec.web.site import build_site

ROOT = Path(__file__).resolve().parents[1]
CHROMIUM = find_chromium()
pytestmark = pytest.mark.skipif(
    CHROMIUM is None,
    reason="chromium not found (at /usr/bin/chromium, or chromium, chromium-browser or "
    "google-chrome on PATH): the viewer's browser tests run it; Debian: apt-get install chromium",
)

TARGET_KG = 0.1
#: Seconds any one page may take to open (samba's 21 MB reference included).
OPEN_SECONDS = 60.0


class Frames:
    """An array of frames as the site's reference (a ReferenceFrames)."""

    def __init__(self, positions: np.ndarray) -> None:
        self.positions = positions
        self.frame_count, self.vertex_count = positions.shape[:2]

    def read(self, start: int, stop: int) -> np.ndarray:
        return np.asarray(self.positions[start:stop], dtype=np.float64)


@pytest.fixture(scope="module")
def browser() -> Iterator[Browser]:
    with Browser.launch(CHROMIUM) as running:
        yield running


@contextmanager
def serve(folder: Path, data: bytes, name: str, original: np.ndarray | None) -> Iterator[str]:
    """Build the viewer's folder for ``data`` and serve it; yields the page's URL."""
    reference = None if original is None else Frames(original)
    site = build_site(folder, data, name, reference=reference, reference_name=name)
    with ViewerServer(folder, site.files) as server:
        yield server.address(site.entry)


def open_page(browser: Browser, url: str) -> Page:
    page = browser.new_page(url, timeout=OPEN_SECONDS)
    page.wait_for("window.tkcViewer !== undefined", timeout=OPEN_SECONDS)
    return page


# ------------------------------------------------------------------------------------------
# the page against the Python decoder


def frame_kg(original: np.ndarray, drawn: np.ndarray) -> tuple[float, float]:
    """The page's definition of a frame's error (FRAME_KG_DEFINITION in measure.js): A the
    original rounded to float32, B the drawn float32 positions, sums in binary64."""
    a = original.astype(np.float32).astype(np.float64).reshape(-1, 3)
    b = drawn.astype(np.float64).reshape(-1, 3)
    difference = np.linalg.norm(a - b)
    spread = np.linalg.norm(a - a.mean(axis=0))
    return float(100.0 * difference / spread), float(np.sqrt(np.square(a - b).sum(axis=1)).max())


def mesh_pixels(page: Page) -> np.ndarray:
    """A screenshot of the canvas: True where a pixel is not the background (the colour of
    most of the canvas's border), the legend's box masked out."""
    boxes = page.evaluate(
        "(() => { const box = (e) => { if (!e || e.hidden) return null;"
        " const r = e.getBoundingClientRect(); return [r.left, r.top, r.width, r.height]; };"
        " return {canvas: box(document.getElementById('canvas')),"
        " legend: box(document.getElementById('legend'))}; })()"
    )
    x, y, width, height = boxes["canvas"]
    image = decode_png(page.screenshot(clip=(x, y, width, height))).astype(np.int16)[..., :3]
    border = np.concatenate([image[0], image[-1], image[:, 0], image[:, -1]])
    colours, counts = np.unique(border, axis=0, return_counts=True)
    background = colours[np.argmax(counts)]
    changed = np.abs(image - background).max(axis=2) > 8
    if boxes["legend"] is not None:
        lx, ly, lw, lh = boxes["legend"]
        changed[int(ly - y) - 2 : int(ly - y + lh) + 3, int(lx - x) - 2 : int(lx - x + lw) + 3] = 0
    return changed


def check_picture(changed: np.ndarray) -> None:
    """The canvas shows something sizeable around its centre (the camera frames the box of
    several frames, so one frame need not cover the centre itself)."""
    height, width = changed.shape
    assert changed.mean() > 0.02, f"only {changed.mean():.2%} of the canvas is not background"
    rows, columns = np.nonzero(changed)
    centre = (rows.mean() / height, columns.mean() / width)
    assert abs(centre[0] - 0.5) < 0.25 and abs(centre[1] - 0.5) < 0.25, centre
    assert max(np.ptp(rows) / height, np.ptp(columns) / width) > 0.3, "a small blob"


def check_frames(page: Page, data: bytes, original: np.ndarray) -> None:
    """Step the page through a few frames; compare each with the Python decoder."""
    info = page.evaluate("window.tkcViewer.ready.then(() => window.tkcViewer.info)")
    decoder = Decoder(data)
    frames = decoder.frame_count
    assert (info["frames"], info["vertices"]) == (frames, decoder.info.vertices)
    pictures = {}
    for t in (0, frames // 2, frames - 1, 1):
        page.evaluate(f"window.tkcViewer.setFrame({t})")
        expected = decoder.frame(t).reshape(-1)
        tolerance = 1e-9 * np.abs(expected).max() + 1e-12  # spec §8
        decoded = page.typed_array(f"window.tkcViewer.decodedPositions({t})")
        assert decoded.dtype == np.float64 and decoded.shape == expected.shape
        assert np.abs(decoded - expected).max() <= tolerance, t
        drawn = page.typed_array("window.tkcViewer.drawnPositions()")
        assert drawn.dtype == np.float32 and drawn.shape == expected.shape
        rounding = (np.abs(expected) + tolerance) * 2.0**-24  # round to nearest float32
        excess = np.abs(drawn - expected) - (tolerance + rounding)
        assert excess.max() <= 0, f"frame {t}: drawn positions off by {excess.max():.3g} more"
        kg, largest = frame_kg(original[t], drawn)
        shown = page.evaluate("window.tkcViewer.frameError()")
        assert shown["kg"] == pytest.approx(kg, rel=1e-6), t
        assert shown["maxError"] == pytest.approx(largest, rel=1e-6), t
        pictures[t] = mesh_pixels(page)
        check_picture(pictures[t])
    moved = (pictures[0] != pictures[frames // 2]).mean()
    assert moved > 0.001, "the picture did not change from frame 0 to the middle frame"
    assert page.problems() == []


@pytest.fixture(scope="module")
def cloth_file(cloth: MeshSequence) -> bytes:
    return tuckercodec.encode(cloth, target_kg=TARGET_KG)


def test_cloth_sample_frames_match_python(browser, cloth, cloth_file, tmp_path):
    with serve(tmp_path, cloth_file, "cloth.tkc", cloth.vertices) as url:
        page = open_page(browser, url)
        try:
            check_frames(page, cloth_file, cloth.vertices)
        finally:
            page.close()


@pytest.mark.slow
@pytest.mark.xdist_group("samba.npz")  # with the other tests of shared_encoded("samba.npz")
def test_samba_frames_match_python(browser, tmp_path):
    sequence, data = shared_sequence("samba.npz"), shared_encoded("samba.npz").data  # KG 0.1
    assert TARGET_KG == 0.1
    with serve(tmp_path, data, "samba.tkc", sequence.vertices) as url:
        page = open_page(browser, url)
        try:
            check_frames(page, data, sequence.vertices)
        finally:
            page.close()


def test_a_file_beyond_web_limits_opens_in_the_viewer(browser, tmp_path):
    """The viewer shows the file its user chose, at the decoder's own limits: TKCLoader's
    WEB_LIMITS (for pages that play files from anywhere) would refuse this one."""
    vertices = 2**18 + 4  # over WEB_LIMITS' max_vertices
    data = chunked_file(vertices, 2, chunk_frames=1)
    with serve(tmp_path, data, "large.tkc", None) as url:
        page = open_page(browser, url)
        try:
            info = page.evaluate(
                "window.tkcViewer.ready.then(() => window.tkcViewer.info, (e) => String(e))"
            )
            assert isinstance(info, dict), info
            assert (info["vertices"], info["frames"]) == (vertices, 2)
        finally:
            page.close()


def test_truncated_file_shows_its_rule(browser, cloth_file, tmp_path):
    truncated = cloth_file[: len(cloth_file) // 2]
    with pytest.raises(FormatError) as raised:
        tuckercodec.decode(truncated)
    rule = raised.value.rule
    with serve(tmp_path, truncated, "truncated.tkc", None) as url:
        page = open_page(browser, url)
        try:
            failure = page.evaluate(
                "window.tkcViewer.ready.then(() => null, (e) => ({rule: e.rule, kind: e.kind}))"
            )
            assert failure == {"rule": rule, "kind": type(raised.value).__name__}
            shown = page.evaluate(
                "(() => { const e = document.getElementById('error');"
                " return e.hidden ? '' : e.textContent; })()"
            )
            assert rule in shown
            problems = page.problems()
            assert len(problems) == 1 and rule in problems[0].text, problems
        finally:
            page.close()


# ------------------------------------------------------------------------------------------
# the conformance vectors, in the browser


@pytest.fixture(scope="module")
def observed(browser: Browser) -> Iterator[dict[str, Any]]:
    """What the JavaScript decoder makes of every vector in Chromium (tests/js/conformance.html
    running tests/js/conformance_observe.mjs, the module the node test runs)."""
    files = [
        "tests/js/conformance.html",
        "tests/js/conformance_page.mjs",
        "tests/js/conformance_observe.mjs",
        *(str(p.relative_to(ROOT)) for p in (ROOT / "tuckercodec/web/tkc").glob("*.js")),
        *(str(p.relative_to(ROOT)) for p in (ROOT / "tuckercodec/web/vendor/fzstd").glob("*")),
        *(str(p.relative_to(ROOT)) for p in (ROOT / "spec/vectors").iterdir()),
    ]
    folder = "../../spec/vectors/"
    vectors = [
        [name, folder + e["file"], folder + e["reference"] if e["valid"] else None]
        for name, e in EXPECTED.items()
    ]
    with ViewerServer(ROOT, files) as server:
        page = browser.new_page(server.address("tests/js/conformance.html"))
        try:
            page.wait_for("window.observeVectors !== undefined")
            yield page.evaluate(f"window.observeVectors({json.dumps(vectors)})", timeout=120)
            assert page.problems() == []
        finally:
            page.close()


def test_every_vector_observed_in_the_browser(observed):
    check_every_vector_observed(observed)


@pytest.mark.parametrize("name", VALID)
def test_valid_vector_in_the_browser(observed, name):
    check_valid_observation(observed, name)


@pytest.mark.parametrize("name", INVALID)
def test_invalid_vector_in_the_browser(observed, name):
    check_invalid_observation(observed, name)


# ------------------------------------------------------------------------------------------
# files with corrections (format 1.3): the same bits as Python, and the bound on show


@pytest.mark.parametrize(
    ("mode", "options", "shown"),
    [
        ("lossless", EncodeOptions(lossless=True), "lossless"),
        ("max-error", EncodeOptions(max_error="0.1%"), "every vertex within"),
    ],
)
def test_corrections_same_bits_and_bound_shown(browser, cloth, tmp_path, mode, options, shown):
    """The built-in cloth encoded with corrections: every frame the page decodes is the Python
    decoder's, bit for bit (§8.1), the drawn positions those rounded to float32 once, and the
    panel shows the bound the header claims."""
    data = tuckercodec.encode(cloth, options=options)
    decoder = Decoder(data)
    assert decoder.corrections is not None, "the encoder wrote no corrections"
    with serve(tmp_path, data, f"{mode}.tkc", cloth.vertices) as url:
        page = open_page(browser, url)
        try:
            info = page.evaluate("window.tkcViewer.ready.then(() => window.tkcViewer.info)")
            # 1.3, 1.6 where the encoder found a position factor smaller adaptively coded, 1.7
            # where it found the corrections so (§6.9), 1.9 where the faces' new vertices are
            # a uniform stream (§6.8: the cloth's vertex order is random)
            assert info["version"] == tuckercodec.info(data).format_version
            assert info["version"] in ("1.3", "1.6", "1.7", "1.9")
            assert info["corrections"]["domain"] == decoder.corrections
            assert shown in info["bound"]
            panel = page.evaluate("document.getElementById('facts-list').textContent")
            assert info["bound"] in panel and "KG error" in panel
            for t in (0, 31, decoder.frame_count - 1):
                page.evaluate(f"window.tkcViewer.setFrame({t})")
                expected = decoder.frame(t).reshape(-1)
                decoded = page.typed_array(f"window.tkcViewer.decodedPositions({t})")
                assert np.array_equal(decoded.view(np.uint64), expected.view(np.uint64)), t
                drawn = page.typed_array("window.tkcViewer.drawnPositions()")
                assert np.array_equal(drawn, expected.astype(np.float32)), t
                if mode == "lossless":  # the original itself, so no distance to it
                    assert page.evaluate("window.tkcViewer.frameError()")["maxError"] == 0
            assert page.problems() == []
        finally:
            page.close()


# ------------------------------------------------------------------------------------------
# a file with attributes and face sets (format 1.5)


def cloth_with_attributes(cloth: MeshSequence) -> MeshSequence:
    """The cloth with UVs per corner (a seam: the corners of every fifth face have a row of
    their own), a colour per face and two materials."""
    from tuckercodec import Attribute, FaceSet
    from tuckercodec.model.attributes import corner_vertices

    faces = cloth.faces
    corners = corner_vertices(faces)
    first = cloth.vertices[0]
    uv_vertex = ((first[:, [0, 2]] - first[:, [0, 2]].min(0)) / np.ptp(first[:, [0, 2]])).astype(
        np.float32
    )
    degrees = (faces >= 0).sum(axis=1)
    face_of = np.repeat(np.arange(faces.shape[0]), degrees)
    own = face_of % 5 == 0
    uv_index = np.where(own, cloth.vertex_count + np.arange(corners.size), corners)
    uv_rows = np.concatenate([uv_vertex, uv_vertex[corners] * np.float32(0.5)])
    rng = np.random.default_rng(2)
    count = faces.shape[0]
    return MeshSequence(
        cloth.vertices,
        faces,
        attributes=[
            Attribute("st", "corner", uv_rows, uv_index, "uv"),
            Attribute("Cd", "face", rng.random((count, 3)).astype(np.float32), None, "color"),
        ],
        face_sets=[
            FaceSet("cotton", np.arange(count // 2), "materialBind"),
            FaceSet("silk", np.arange(count // 2, count), "materialBind"),
        ],
    )


def test_a_file_with_attributes_plays_and_lists_them(browser, cloth, tmp_path):
    """The drawn positions of the file's vertices, the error colours and the KG are right
    although its vertices are split for the UVs and colours; the panel lists the attributes
    and face sets, and the UV toggle puts a checker texture on the mesh."""
    sequence = cloth_with_attributes(cloth)
    data = tuckercodec.encode(sequence, target_kg=TARGET_KG)
    with serve(tmp_path, data, "cloth-uv.tkc", sequence.vertices) as url:
        page = open_page(browser, url)
        try:
            check_frames(page, data, sequence.vertices)
            listed = page.evaluate("document.getElementById('attached-list').textContent")
            assert "st" in listed and "uv per corner" in listed and "cotton" in listed, listed
            assert page.evaluate("document.getElementById('attached').hidden") is False
            assert page.evaluate("document.getElementById('uv-control').hidden") is False
            plain = page.screenshot()
            page.evaluate(
                "(() => { const box = document.getElementById('uv'); box.click();"
                " return box.checked; })()"
            )
            page.evaluate("window.tkcViewer.setFrame(0)")
            assert page.screenshot() != plain, "the checker texture changed nothing"
            assert page.problems() == []
        finally:
            page.close()
