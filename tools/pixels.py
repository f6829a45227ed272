"""Draw a textured sequence's original and its ``.tkc`` with three.js, as pictures to look at.

    python -m tools.pixels character.usdc character.tkc --frame 6 -o pictures/

writes ``original.png`` (the source's frame, built in the page from its arrays) and
``decoded.png`` (the file's frame, as TKCLoader gives it), drawn in headless Chromium at one
fixed camera, unlit, with a checker texture on one material per ``materialBind`` face set,
tinted per material and multiplied by the vertex colours: the page and the driver of
tests/test_attributes_pixels_browser.py (tests/support/pixels.py, tests/js/pixels.html). It
prints how the two differ (the fraction of pixels with a channel off by more than 16 of 255,
and the mean absolute difference), and so for the decoded mesh drawn with its UVs broken on
purpose (each drawn vertex with the next one's, or their rows reversed): the scale a real
difference has. The source needs an attribute of role ``uv`` and one of role ``color``.
Needs chromium (Debian: ``apt-get install chromium``).
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

from tests.support.browser import Browser, BrowserError, find_chromium
from tests.support.pixels import difference, draw, pixels_page
from tuckercodec import InputError, load_sequence
from tuckercodec.internal import refuse_existing, write_atomic

#: A pixel differs when one of its channels differs by more than this (of 255).
THRESHOLD = 16
CONTROLS = ("next-uv", "reversed-uv")


def render(source: Path, tkc: Path, frame: int | None, output: Path, force: bool) -> list[str]:
    """Draw and compare; write the two pictures into ``output``; the lines to print."""
    pictures = [output / "original.png", output / "decoded.png"]
    output.mkdir(exist_ok=True)
    refuse_existing(pictures, force)
    sequence = load_sequence(source)
    chosen = sequence.frame_count // 2 if frame is None else frame
    if not 0 <= chosen < sequence.frame_count:
        raise ValueError(f"{source} has frames 0..{sequence.frame_count - 1}, not {chosen}")
    chromium = find_chromium()
    if chromium is None:
        raise BrowserError("chromium not found; Debian: apt-get install chromium")
    lines = []
    with (
        Browser.launch(chromium) as browser,
        tempfile.TemporaryDirectory() as folder,
        pixels_page(browser, Path(folder), sequence, tkc.read_bytes(), chosen) as page,
    ):
        original, original_png = draw(page, "original")
        decoded, decoded_png = draw(page, "decoded")
        for name, picture in [("decoded", decoded)] + [
            (control, draw(page, "decoded", control)[0]) for control in CONTROLS
        ]:
            found = difference(original, picture, THRESHOLD)
            lines.append(
                f"{name:<12} {found.fraction:8.4%} of pixels differ by more than "
                f"{THRESHOLD}/255; mean absolute difference {found.mean:.4f}/255"
            )
        problems = page.problems()
    if problems:
        raise BrowserError(f"the page reported: {problems}")
    write_atomic(pictures[0], original_png, overwrite=force)
    write_atomic(pictures[1], decoded_png, overwrite=force)
    return [f"frame {chosen} of {source} against {tkc}:", *lines, *(f"wrote {p}" for p in pictures)]


def main(argv: list[str] | None = None) -> int:
    """The command line; returns the exit status."""
    parser = argparse.ArgumentParser(
        prog="python -m tools.pixels", description=__doc__.split("\n")[0]
    )
    parser.add_argument("source", type=Path, help="the original sequence (any format read)")
    parser.add_argument("tkc", type=Path, help="its compressed file")
    parser.add_argument("--frame", type=int, help="the frame to draw (default: the middle one)")
    parser.add_argument("-o", "--output", type=Path, required=True, help="the pictures' folder")
    parser.add_argument("--force", action="store_true", help="replace existing pictures")
    args = parser.parse_args(argv)
    try:
        lines = render(args.source, args.tkc, args.frame, args.output, args.force)
    except (InputError, BrowserError, ValueError, OSError) as error:
        print(f"error: {error}", file=sys.stderr)
        return 1
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main())
