"""tests/support/png.py reads every PNG row filter; tests/support/browser.py drives Chromium over
the DevTools pipe: values, exact typed arrays, thrown errors, console messages, deadlines, a browser
that dies, and closing that leaves no process and no profile behind. The browser tests skip, naming
what is missing, where chromium is not installed."""

from __future__ import annotations

import struct
import subprocess
import time
import zlib

import numpy as np
import pytest

from tests.support.browser import Browser, BrowserDied, BrowserError, BrowserTimeout, find_chromium
from tests.support.png import decode_png

CHROMIUM = find_chromium()
needs_chromium = pytest.mark.skipif(
    CHROMIUM is None,
    reason="chromium not found (at /usr/bin/chromium, or chromium, chromium-browser or "
    "google-chrome on PATH); Debian: apt-get install chromium",
)


def encode_png(image: np.ndarray, filters: list[int]) -> bytes:
    """A PNG of ``image`` (height, width, channels) with row y filtered by ``filters[y]``,
    written here from the PNG specification so that the reader meets every filter."""
    height, width, channels = image.shape
    colour = {1: 0, 2: 4, 3: 2, 4: 6}[channels]
    rows = image.reshape(height, width * channels).astype(int)
    raw = bytearray()
    for y in range(height):
        line, above = rows[y], rows[y - 1] if y else np.zeros_like(rows[0])
        left = np.concatenate([np.zeros(channels, int), line[:-channels]])
        corner = np.concatenate([np.zeros(channels, int), above[:-channels]])
        kind = filters[y]
        if kind == 0:
            predicted = np.zeros_like(line)
        elif kind == 1:
            predicted = left
        elif kind == 2:
            predicted = above
        elif kind == 3:
            predicted = (left + above) // 2
        else:
            p = left + above - corner
            pa, pb, pc = np.abs(p - left), np.abs(p - above), np.abs(p - corner)
            predicted = np.where((pa <= pb) & (pa <= pc), left, np.where(pb <= pc, above, corner))
        raw += bytes([kind]) + bytes(((line - predicted) % 256).astype(np.uint8))

    def chunk(kind: bytes, body: bytes) -> bytes:
        crc = zlib.crc32(kind + body)
        return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", crc)

    header = struct.pack(">IIBBBBB", width, height, 8, colour, 0, 0, 0)
    compressed = zlib.compress(bytes(raw))
    return (
        b"\x89PNG\r\n\x1a\n"
        + chunk(b"IHDR", header)
        + chunk(b"IDAT", compressed[:10])  # a picture may span several IDAT chunks
        + chunk(b"IDAT", compressed[10:])
        + chunk(b"IEND", b"")
    )


@pytest.mark.parametrize("channels", [1, 2, 3, 4])
def test_png_every_filter(channels):
    rng = np.random.default_rng(channels)
    image = rng.integers(0, 256, (10, 7, channels), dtype=np.uint8)
    image[5:] = image[4]  # runs, where the filters' sums wrap differently than on noise
    filters = [0, 1, 2, 3, 4, 4, 3, 2, 1, 0]
    decoded = decode_png(encode_png(image, filters))
    assert decoded.dtype == np.uint8
    np.testing.assert_array_equal(decoded, image)


def test_png_refuses_what_it_cannot_read():
    with pytest.raises(ValueError, match="not a PNG"):
        decode_png(b"GIF89a")
    sixteen = bytearray(encode_png(np.zeros((2, 2, 3), np.uint8), [0, 0]))
    sixteen[24] = 16  # IHDR's bit depth
    with pytest.raises(ValueError, match="depth 16"):
        decode_png(bytes(sixteen))


@pytest.fixture(scope="module")
def browser():
    with Browser.launch(CHROMIUM) as running:
        yield running


PAGE = (
    "data:text/html,<title>t</title><script>console.log('hello', 42); "
    "console.warn('careful')</script>"
)


@needs_chromium
def test_evaluate_values_arrays_and_errors(browser):
    page = browser.new_page(PAGE)
    try:
        assert page.evaluate("1 + 1") == 2
        assert page.evaluate("Promise.resolve({a: [1, 'x', null]})") == {"a": [1, "x", None]}
        assert page.evaluate("document.title") == "t"
        values = page.typed_array("new Float64Array([0.1, -0, 1e-300, 2 ** 53 + 2, NaN])")
        assert values.dtype == np.float64
        assert values[:4].tolist() == [0.1, -0.0, 1e-300, 2.0**53 + 2] and np.isnan(values[4])
        assert np.signbit(values[1])  # bit for bit, not through JSON numbers
        assert page.typed_array("new Uint32Array([4294967295])").tolist() == [4294967295]
        with pytest.raises(BrowserError, match="RangeError: nope"):
            page.evaluate("Promise.reject(new RangeError('nope'))")
        with pytest.raises(BrowserError, match="not a typed array"):
            page.typed_array("[1, 2]")
        assert [(e.level, e.text) for e in page.console] == [
            ("log", "hello 42"),
            ("warning", "careful"),
        ]
        assert page.problems() == []
        page.evaluate("console.error('bad'); setTimeout(() => { throw new Error('boom'); }); 0")
        page.wait_for("new Promise((done) => setTimeout(() => done(true), 50))")
        problems = page.problems()
        assert [p.source for p in problems] == ["console", "exception"]
        assert "bad" in problems[0].text and "boom" in problems[1].text
        png = page.screenshot(clip=(0, 0, 40, 30))
        assert decode_png(png).shape[:2] == (30, 40)
    finally:
        page.close()


@needs_chromium
def test_a_call_without_an_answer_times_out(browser):
    page = browser.new_page()
    try:
        began = time.monotonic()
        with pytest.raises(BrowserTimeout):
            page.evaluate("new Promise(() => {})", timeout=0.5)
        assert time.monotonic() - began < 10
        with pytest.raises(BrowserTimeout, match="still false"):
            page.wait_for("false", timeout=0.3)
        assert page.evaluate("'still answering'") == "still answering"
    finally:
        page.close()


@needs_chromium
def test_a_browser_that_dies_is_reported_and_cleaned_up():
    browser = Browser.launch(CHROMIUM)
    home = browser.home
    assert home.is_dir()
    browser.process.kill()
    with pytest.raises(BrowserDied, match="exited"):
        browser.new_page()
    browser.close()
    browser.close()  # twice is harmless
    assert not home.exists()
    with pytest.raises(BrowserError, match="closed"):
        browser.version()


@needs_chromium
def test_closing_stops_every_process_and_removes_the_profile():
    with Browser.launch(CHROMIUM) as browser:
        browser.new_page("data:text/html,<p>x</p>")
        home, group = browser.home, browser.process.pid
    assert browser.process.returncode is not None
    assert not home.exists()
    # none of its processes is left running (a zombie awaits only its reaping)
    time.sleep(0.2)
    for pid, pgid, state in _processes():
        assert pgid != group or state.startswith("Z"), (pid, state)


def _processes() -> list[tuple[int, int, str]]:
    listing = subprocess.run(
        ["ps", "-eo", "pid=,pgid=,stat="], capture_output=True, text=True, check=True
    ).stdout
    return [(int(a), int(b), c) for a, b, c in (line.split() for line in listing.splitlines())]


def test_no_chromium_is_a_clear_error(tmp_path):
    missing = tmp_path / "no-such-browser"
    with pytest.raises(BrowserError, match=f"{missing}: no such executable"):
        Browser.launch(str(missing))
