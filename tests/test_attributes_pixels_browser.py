"""A textured, animated character through encode and decode, down to the pixels three.js draws.

The character is tools.generate.textured_character's USD stage (12 frames of the cloth:
indexed faceVarying ``st``, ``displayColor`` per face, two ``materialBind`` subsets, normals,
velocities), encoded by ``tuckercodec encode`` with its defaults. In headless Chromium (driven
by tests/support/browser.py, the page served by the viewer's server: tests/support/pixels.py),
frame 6 is drawn twice at one fixed camera, unlit, with a checker texture made in the page on
one MeshBasicMaterial per material, tinted per material and multiplied by the vertex colours:
the original, a BufferGeometry built in the page from the source's arrays, and the decoded
file, TKCLoader's mesh.

- Exact where the codec is exact: the Python decode has every attribute and face set bit for
  bit; from the geometry TKCLoader made, the UV and colour at every triangle corner are the
  source corner's, bit for bit (float32 against float32), every corner is the source's vertex,
  and each group is one face set's faces under its name.
- The pictures agree: the positions differ by the encode's KG error (about 0.1: at most 0.0072
  units on a sheet of 10 units drawn about 400 pixels wide, under a third of a pixel), so only
  pixels along the silhouette and the checker's edges change, as an edge moves by a fraction of a
  pixel across a pixel's centre. Measured: 0.15% of pixels differ by more than 16 (of 255),
  and the mean absolute difference is 0.08 (of 255).
- The comparison can fail: the decoded mesh drawn with its UVs broken (each drawn vertex
  given the next one's UV: neighbours, a small error; or the rows reversed) differs on 12% and
  17% of pixels, means 7.3 and 10.4.

The thresholds sit between the two with a wide margin each way (see the constants).
``python -m tools.pixels`` writes the two pictures for a person to look at; it is run here too.
Skips, naming what is missing, without chromium or usd-core.
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

import tuckercodec
from tests.support.browser import Browser, Page, find_chromium
from tests.support.pixels import (
    covered,
    difference,
    draw,
    first_of_role,
    loader_corners,
    per_corner,
    pixels_page,
)
from tests.support.png import decode_png
from tools import pixels as pixels_tool
from tuckercodec import Decoder, MeshSequence
from tuckercodec.cli import main as cli
from tuckercodec.model.attributes import corner_faces, corner_vertices

CHROMIUM = find_chromium()
pytestmark = [
    pytest.mark.skipif(
        CHROMIUM is None,
        reason="chromium not found (at /usr/bin/chromium, or chromium, chromium-browser or "
        "google-chrome on PATH): the pixel comparison runs it; Debian: apt-get install chromium",
    ),
    # one worker makes the character, encodes it and opens the page, for every test here
    pytest.mark.xdist_group("attributes-pixels"),
]

FRAMES = 12
FRAME = 6
#: A pixel "differs" when a channel differs by more than this (of 255): beyond the rounding of
#: colours interpolated over slightly moved triangles, a change of texel or of triangle.
THRESHOLD = 16
#: At most this fraction of pixels may differ: measured 0.15% (edges moving by a third of a
#: pixel at most); the broken UVs differ on 12% or more.
MOST_DIFFERING = 0.01
#: And the mean absolute difference (of 255) at most this: measured 0.08; broken UVs, 7 or more.
MOST_MEAN = 0.5
#: What a negative control must differ by, at least: a tenth of what the gentlest measured.
LEAST_CONTROL_DIFFERING, LEAST_CONTROL_MEAN = 0.05, 3.0


@pytest.fixture(scope="module")
def files(tmp_path_factory) -> tuple[Path, Path]:
    """The character's USD stage and its .tkc, made by the commands a user runs."""
    pytest.importorskip("pxr", reason="usd-core (the 'usd' extra) is not installed")
    from tools.generate import textured_character

    folder = tmp_path_factory.mktemp("character")
    usd, tkc = folder / "character.usdc", folder / "character.tkc"
    assert textured_character.main(["-o", str(usd), "--frames", str(FRAMES)]) == 0
    assert cli(["encode", str(usd), "-o", str(tkc)]) == 0
    return usd, tkc


@pytest.fixture(scope="module")
def character(files) -> tuple[MeshSequence, bytes]:
    """The source, as tuckercodec reads it, and its .tkc's bytes."""
    return tuckercodec.load_sequence(files[0]), files[1].read_bytes()


@pytest.fixture(scope="module")
def page(character, tmp_path_factory) -> Iterator[Page]:
    sequence, data = character
    with Browser.launch(CHROMIUM) as browser:
        folder = tmp_path_factory.mktemp("pixels")
        with pixels_page(browser, folder, sequence, data, FRAME) as opened:
            yield opened
            assert opened.problems() == []


def test_the_python_decode_keeps_every_attribute_and_face_set_bit_for_bit(character):
    sequence, data = character
    decoded = tuckercodec.decode(data)
    assert [a.name for a in decoded.attributes] == [a.name for a in sequence.attributes]
    for attribute in sequence.attributes:
        assert decoded.attribute_named(attribute.name).same_as(attribute), attribute.name
    assert len(decoded.face_sets) == len(sequence.face_sets) == 2
    for kept, source in zip(decoded.face_sets, sequence.face_sets, strict=True):
        assert kept.same_as(source), source.name
    assert np.array_equal(decoded.faces, sequence.faces)  # the face order is kept


def test_the_loaders_geometry_has_every_corners_uv_and_colour_bit_for_bit(character, page):
    sequence, data = character
    expected = loader_corners(sequence)
    uv, colour = first_of_role(sequence, "uv"), first_of_role(sequence, "color")
    assert uv.values.dtype == colour.values.dtype == np.float32  # so float32 bits are the source's
    for name, attribute in (("uv", uv), ("color", colour)):
        drawn = page.typed_array(f"window.tkcPixels.drawn('{name}')")
        want = per_corner(sequence, attribute)[expected.corners].reshape(-1)
        assert drawn.dtype == np.float32 and drawn.shape == want.shape, name
        differing = np.flatnonzero(drawn.view(np.uint32) != want.view(np.uint32))
        assert differing.size == 0, f"{name}: {differing.size} values differ, first {differing[:5]}"
    vertices = page.typed_array("window.tkcPixels.drawn('vertex')")
    assert np.array_equal(vertices, corner_vertices(sequence.faces)[expected.corners])
    # the positions drawn are the decoded frame's, rounded to float32 once (spec §8's tolerance)
    positions = page.typed_array("window.tkcPixels.drawn('position')").reshape(-1, 3)
    frame = Decoder(data).frame(FRAME)[vertices]
    tolerance = 1e-9 * np.abs(frame).max() + (np.abs(frame) + 1e-9) * 2.0**-24
    assert (np.abs(positions - frame) <= tolerance).all()


def test_the_loaders_groups_are_the_face_sets(character, page):
    sequence, _ = character
    expected = loader_corners(sequence)
    layout = page.evaluate("window.tkcPixels.layout()")
    assert layout["frame"] == FRAME
    groups = [(g["start"], g["count"], g["materialIndex"]) for g in layout["groups"]]
    assert groups == expected.groups
    assert layout["materialNames"] == expected.material_names == ["red", "blue"]
    # each group draws exactly its face set's faces, whatever order the loader chose
    vertices = page.typed_array("window.tkcPixels.drawn('vertex')")
    assert len(vertices) == sum(count for _, count, _ in groups)
    face_of_corner = corner_faces(sequence.faces)[expected.corners]
    for face_set, (start, count, number) in zip(sequence.face_sets, groups, strict=True):
        assert layout["materialNames"][number] == face_set.name
        drawn_faces = np.unique(face_of_corner[start : start + count])
        assert np.array_equal(drawn_faces, np.sort(face_set.faces)), face_set.name


def test_the_decoded_file_draws_the_originals_pixels(page, request):
    original, _ = draw(page, "original")
    decoded, _ = draw(page, "decoded")
    assert original.shape == decoded.shape == (480, 480, 3)
    assert 0.2 < covered(original) < 0.8, "the mesh does not fill a good part of the canvas"
    found = difference(original, decoded, THRESHOLD)
    request.node.user_properties.append(("decoded", repr(found)))  # in --junitxml
    assert found.fraction <= MOST_DIFFERING, found
    assert found.mean <= MOST_MEAN, found


@pytest.mark.parametrize("control", ["next-uv", "reversed-uv"])
def test_broken_uvs_change_the_pixels(page, control, request):
    """The negative controls: the comparison above fails on a mesh whose UVs are wrong."""
    original, _ = draw(page, "original")
    broken, _ = draw(page, "decoded", control)
    found = difference(original, broken, THRESHOLD)
    request.node.user_properties.append((control, repr(found)))
    assert found.fraction >= LEAST_CONTROL_DIFFERING, found
    assert found.mean >= LEAST_CONTROL_MEAN, found
    assert found.fraction > MOST_DIFFERING and found.mean > MOST_MEAN


def test_the_tool_writes_both_pictures_and_the_comparison(files, tmp_path, capsys):
    usd, tkc = files
    assert pixels_tool.main([str(usd), str(tkc), "--frame", str(FRAME), "-o", str(tmp_path)]) == 0
    printed = capsys.readouterr().out
    assert f"frame {FRAME}" in printed and "reversed-uv" in printed, printed
    original = decode_png((tmp_path / "original.png").read_bytes())
    decoded = decode_png((tmp_path / "decoded.png").read_bytes())
    assert original.shape[:2] == decoded.shape[:2] == (480, 480)
    assert not np.array_equal(original, decoded)  # not one picture twice: the edges moved
    assert pixels_tool.main([str(usd), str(tkc), "-o", str(tmp_path)]) == 1  # kept unasked
    assert "already exists" in capsys.readouterr().err
