"""One VTK XML file (tuckercodec/io/vtk/datasets.py and arrays.py), read and written in plain numpy.

Every layout VTK writes (ascii; base64 inline; appended raw and base64; zlib blocks or none;
UInt32 and UInt64 block headers; big-endian) is read exactly from files VTK itself wrote
(tests/data/vtk, made by its make.py), and written by us in each layout and read back exactly,
by us and, where pyvista is installed, by VTK's own reader, bit for bit. Every hostile file (a
zlib bomb, counts far beyond the file, truncated base64 or appended data, broken structure, or
any random damage) ends in an InputError naming the file and frame, with nothing allocated or
inflated beyond what the file's size allows.
"""

from __future__ import annotations

import base64
import re
import shutil
import zlib
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from tests.support.inputs import expect_input_error, measure
from tests.support.properties import PROPERTY, mutations, report_examples, scratch_folder
from tests.support.sequences import wave_sequence
from tuckercodec import InputError, load_sequence
from tuckercodec.cli import main
from tuckercodec.io.vtk.arrays import MAX_INFLATION, Layout
from tuckercodec.io.vtk.datasets import DatasetWriter, read_dataset

DATA = Path(__file__).parent / "data" / "vtk"
# tests/data/vtk/make.py's PolyData: sevenths, which float32 cannot hold
SURFACE = (
    np.array(
        [
            [0, 0, 0],
            [1, 0, 0],
            [1, 1, 0],
            [0, 1, 0],
            [2, 0, 0],
            [2, 1, 0],
            [3, 0.5, 0],
            [3, 2, 0],
            [4, 1, 0],
        ],
        dtype=np.float64,
    )
    + np.arange(27).reshape(9, 3) / 7
)
# its polygons, then its strip 0 2 3 5 7 split as VTK splits it; its vertex cell is no face
SURFACE_FACES = [
    [0, 1, 2, -1, -1],
    [1, 4, 5, 2, -1],
    [4, 6, 7, 5, 2],
    [0, 2, 3, -1, -1],
    [3, 2, 5, -1, -1],
    [3, 5, 7, -1, -1],
]
ENCODINGS = sorted(path.name for path in (DATA / "encodings").glob("*.vtp"))
FACES = np.array([[0, 1, 4, -1, -1], [1, 2, 5, 4, -1], [3, 4, 7, 6, -1], [4, 5, 8, 7, 6]])
NO_FACES = np.zeros((0, 3), dtype=np.int64)
KINDS = {"PolyData": ".vtp", "UnstructuredGrid": ".vtu"}
LAYOUTS = {
    "paraview": Layout(),
    "appended-raw": Layout(compress=False),
    "appended-base64-zlib": Layout(base64=True),
    "appended-base64": Layout(base64=True, compress=False),
    "binary-zlib-uint32-blocks": Layout("binary", header="UInt32", block_size=64),
    "binary": Layout("binary", compress=False),
    "binary-uint32": Layout("binary", compress=False, header="UInt32"),
    "bigendian-zlib": Layout(byte_order="BigEndian", block_size=96),
    "bigendian-binary": Layout("binary", compress=False, byte_order="BigEndian"),
    "ascii": Layout("ascii", compress=False),
}


def exact(a: np.ndarray, b: np.ndarray) -> bool:
    """Bit for bit equal arrays of one dtype."""
    return a.dtype == b.dtype and a.tobytes() == b.tobytes()


def frame_file(tmp_path: Path, data: bytes | Path, suffix: str = ".vtp") -> tuple[Path, Path]:
    """A .pvd of one frame: ``data`` written to f/0<suffix>, or a copy of the file ``data``."""
    (tmp_path / "f").mkdir(exist_ok=True)
    if isinstance(data, Path):  # copied: a .pvd lists only files inside its folder
        suffix = data.suffix
        data = data.read_bytes()
    frame = tmp_path / "f" / f"0{suffix}"
    frame.write_bytes(data)
    pvd = tmp_path / "one.pvd"
    pvd.write_text(
        '<VTKFile type="Collection"><Collection>'
        f'<DataSet timestep="0" file="f/{frame.name}"/></Collection></VTKFile>'
    )
    return pvd, frame


def refused(tmp_path: Path, data: bytes, match: str, suffix: str = ".vtp") -> InputError:
    """Reading a series of the one frame ``data`` fails naming the frame's file and 0."""
    pvd, frame = frame_file(tmp_path, data, suffix)
    return expect_input_error(lambda: load_sequence(pvd), frame, frame=0, match=match)


def written(points: np.ndarray, faces: np.ndarray, kind: str, layout: Layout) -> bytes:
    return DatasetWriter(faces, len(points), kind, layout)(points)


# ------------------------------------------------------------------------------------------
# files VTK wrote


@pytest.mark.parametrize("name", ENCODINGS)
def test_every_layout_vtk_writes_is_read_exactly(tmp_path, name):
    pvd, _ = frame_file(tmp_path, DATA / "encodings" / name)
    seq = load_sequence(pvd)
    assert exact(seq.vertices[0], SURFACE) and seq.faces.tolist() == SURFACE_FACES


def test_the_layouts_vtk_wrote_are_all_there():
    assert len(ENCODINGS) == 12  # see tests/data/vtk/README.md
    headers = [(DATA / "encodings" / name).read_bytes()[:200] for name in ENCODINGS]
    assert sum(b'header_type="UInt32"' in head for head in headers) == 4
    assert sum(b"BigEndian" in head for head in headers) == 2


def test_a_vtp_series_vtk_wrote_is_read_exactly():
    seq = load_sequence(DATA / "surface.pvd")
    assert seq.time_codes is not None
    assert seq.time_codes.tolist() == [0.0, 0.1, 0.2]
    for number, step in enumerate([0.0, 0.1, 0.2]):
        moved = (SURFACE + np.array([0.5, -0.25, 1.0]) * step).astype(np.float32)
        assert exact(seq.vertices[number], moved.astype(np.float64))
    assert seq.faces.tolist() == SURFACE_FACES


def test_every_surface_cell_type_of_an_unstructured_grid_vtk_wrote():
    pvd_data = DATA / "cells.vtu"
    points, faces = read_dataset(pvd_data.read_bytes())
    assert exact(points, SURFACE)
    # triangle; pixel 0 1 3 2 as the quad 0 1 2 3; strip 2 3 4 5 6; pentagon; the vertex and
    # poly-vertex cells mark points only; quad
    assert faces.tolist() == [
        [0, 1, 2, -1, -1],
        [0, 1, 2, 3, -1],
        [2, 3, 4, -1, -1],
        [4, 3, 5, -1, -1],
        [4, 5, 6, -1, -1],
        [4, 6, 7, 5, 2],
        [1, 4, 5, 2, -1],
    ]


def test_strips_are_split_as_vtk_splits_them(tmp_path):
    pyvista = pytest.importorskip("pyvista", reason="pyvista (VTK) is not installed")
    points = np.random.default_rng(1).standard_normal((12, 3))
    strips = np.array([7, 0, 1, 2, 3, 4, 5, 6, 5, 7, 8, 9, 10, 11])
    pyvista.PolyData(points, strips=strips).save(tmp_path / "s.vtp")
    _, faces = read_dataset((tmp_path / "s.vtp").read_bytes())
    triangles = pyvista.read(tmp_path / "s.vtp").triangulate().faces.reshape(-1, 4)[:, 1:]
    assert faces.tolist() == triangles.tolist()


# ------------------------------------------------------------------------------------------
# what we write, in every layout


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("layout", LAYOUTS.values(), ids=LAYOUTS.keys())
def test_our_writer_round_trips_in_every_layout(kind, layout):
    for points in (wave_sequence(1, 3)[0], wave_sequence(1, 3)[0].astype(np.float32)):
        for faces in (FACES, NO_FACES):
            back, back_faces = read_dataset(written(points, faces, kind, layout))
            assert exact(back, points.astype(np.float64)) and np.array_equal(back_faces, faces)


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("layout", LAYOUTS.values(), ids=LAYOUTS.keys())
def test_vtks_own_reader_reads_what_we_write_bit_for_bit(tmp_path, kind, layout):
    pyvista = pytest.importorskip("pyvista", reason="pyvista (VTK's own readers) is not installed")
    for points in (wave_sequence(1, 3)[0], wave_sequence(1, 3)[0].astype(np.float32)):
        for faces in (FACES, NO_FACES):
            path = tmp_path / f"w{KINDS[kind]}"
            path.write_bytes(written(points, faces, kind, layout))
            mesh = pyvista.read(path)
            assert exact(np.asarray(mesh.points), points)  # the same type, the same bits
            cells = [list(mesh.get_cell(i).point_ids) for i in range(mesh.n_cells)]
            expected = [[i for i in row if i >= 0] for row in faces.tolist()]
            assert cells == (expected or [[i] for i in range(len(points))])


def test_a_header_encoded_apart_from_its_data_is_read():
    # meshio writes base64 blocks so, with the header's own padding, even when uncompressed
    ascii = written(SURFACE, FACES[:0], "PolyData", Layout("ascii", compress=False))
    data = SURFACE.astype("<f8").tobytes()
    encoded = base64.b64encode(np.array([len(data)], "<u4").tobytes()) + base64.b64encode(data)
    assert encoded[:8].endswith(b"==")
    text = re.sub(
        rb'format="ascii">[^<]*</DataArray>\s*</Points>',
        b'format="binary">' + encoded + b"</DataArray></Points>",
        ascii.replace(b'header_type="UInt64"', b'header_type="UInt32"'),
        count=1,
    )
    points, _ = read_dataset(text)
    assert exact(points, SURFACE)


def test_several_pieces_are_joined_in_order(tmp_path):
    one = written(SURFACE[:4], np.array([[0, 1, 2, 3]]), "PolyData", Layout("ascii"))
    two = written(SURFACE[4:], np.array([[0, 1, 2]]), "PolyData", Layout("ascii"))
    piece = re.compile(rb"<Piece.*</Piece>", re.S)
    first, second = piece.search(one), piece.search(two)
    assert first is not None and second is not None
    both = piece.sub(lambda _: first[0] + second[0], one)
    points, faces = read_dataset(both)
    assert exact(points, SURFACE) and faces.tolist() == [[0, 1, 2, 3], [4, 5, 6, -1]]
    stray = both.replace(b"0 1 2 3", b"0 1 2 4", 1)  # a point of the next piece
    refused(tmp_path, stray, "piece 0: a cell has the point index 4, outside 0..3")


# ------------------------------------------------------------------------------------------
# hostile files


def points_only(record: bytes, count: int, compressed: bool, base64_data: bool = False) -> bytes:
    """A PolyData of ``count`` Float64 points whose appended data is ``record``."""
    compressor = ' compressor="vtkZLibDataCompressor"' if compressed else ""
    encoding = "base64" if base64_data else "raw"
    return (
        (
            f'<VTKFile type="PolyData" version="1.0" header_type="UInt64"{compressor}><PolyData>'
            f'<Piece NumberOfPoints="{count}"><Points><DataArray type="Float64" '
            'NumberOfComponents="3" format="appended" offset="0"/></Points></Piece></PolyData>'
            f'<AppendedData encoding="{encoding}">\n_'
        ).encode()
        + record
        + b"\n</AppendedData></VTKFile>"
    )


def zlib_record(sizes: list[int], blocks: bytes) -> bytes:
    return np.array(sizes, "<u8").tobytes() + blocks


def test_a_zlib_bomb_is_refused_without_inflating_beyond_its_declared_size(tmp_path):
    bomb = zlib.compress(bytes(200_000_000), 9)  # 194 KB that inflate to 200 MB
    data = points_only(zlib_record([1, 216, 0, len(bomb)], bomb), 9, compressed=True)
    pvd, _ = frame_file(tmp_path, data)
    load_sequence(DATA / "surface.pvd")  # the formats' modules imported before measuring
    error, _, peak = measure(lambda: load_sequence(pvd))
    assert isinstance(error, InputError), error
    assert "block 0 inflates beyond the 216 bytes its header declares" in str(error)
    assert peak < 4 * len(data), peak  # memory, which holds on any machine; not seconds


def test_a_block_larger_than_zlib_can_expand_is_refused_before_inflating(tmp_path):
    small = zlib.compress(bytes(1000), 9)
    count = 10**8  # 2.4 GB of points, declared by a file of a few hundred bytes
    data = points_only(zlib_record([1, count * 24, 0, len(small)], small), count, True)
    pvd, _ = frame_file(tmp_path, data)
    load_sequence(DATA / "surface.pvd")  # the formats' modules imported before measuring
    error, _, peak = measure(lambda: load_sequence(pvd))
    assert isinstance(error, InputError) and f"({MAX_INFLATION}x): refused" in str(error)
    assert peak < 1_000_000, peak


def zeros_block(size: int) -> bytes:
    """One zlib stream of ``size`` zero bytes, made a MiB at a time (never ``size`` at once)."""
    packer, piece = zlib.compressobj(9), bytes(min(size, 2**20))
    packed = [packer.compress(piece[: min(len(piece), size - at)]) for at in range(0, size, 2**20)]
    return b"".join(packed) + packer.flush()


def test_an_honest_bomb_is_refused_beyond_max_memory_before_inflating(tmp_path, capsys):
    """A decompression bomb: a block of zeros that declares, consistently, the size it inflates
    to (a 467 KB .vtp was 1.06 GB of points) is bounded by --max-memory, not by the file."""
    count = 2**22  # 96 MiB of Float64 points, from a block of 98 KB
    block = zeros_block(count * 24)
    data = points_only(zlib_record([1, count * 24, 0, len(block)], block), count, True)
    pvd, frame = frame_file(tmp_path, data)
    load_sequence(DATA / "surface.pvd")  # the formats' modules imported before measuring
    limit = 16 * 2**20
    error, _, peak = measure(lambda: load_sequence(pvd, max_memory=limit))
    assert isinstance(error, InputError) and (error.path, error.frame) == (str(frame), 0), error
    assert "Points: inflates to 101 MB, beyond the 16.8 MB a read may decompress" in str(error)
    assert peak < 4 * len(data), peak  # nothing inflated: the file's bytes and no more
    assert load_sequence(pvd, max_memory=count * 24).vertex_count == count  # what it holds
    out = tmp_path / "out.npz"
    assert main(["convert", str(pvd), str(out), "--max-memory", "16MiB"]) == 4
    said = capsys.readouterr().err
    assert said.count("\n") == 1 and said.startswith(f"tuckercodec: bad input: {frame}"), said
    assert "beyond the 16.8 MB a read may decompress" in said and not out.exists()


def test_the_ceiling_holds_for_a_files_arrays_together(tmp_path):
    points = np.zeros((2**16, 3))
    faces = np.zeros((2**16, 3), dtype=np.int64)  # compresses as well as the points
    data = written(points, faces, "PolyData", Layout(block_size=2**20))
    pvd, frame = frame_file(tmp_path, data)
    inflated = points.nbytes + faces.size * 4 + len(faces) * 4  # connectivity, offsets: Int32
    assert load_sequence(pvd, max_memory=inflated).vertex_count == 2**16
    expect_input_error(
        lambda: load_sequence(pvd, max_memory=inflated - 1),
        frame,
        frame=0,
        match=r"Polys \w+: inflates to .* beside the .* inflated before it",
    )


def test_declared_counts_far_beyond_the_file_are_refused_before_allocating(tmp_path):
    count = 10**11
    data = points_only(np.array([count * 24], "<u8").tobytes() + bytes(24), count, False)
    pvd, _ = frame_file(tmp_path, data)
    load_sequence(DATA / "surface.pvd")  # the formats' modules imported before measuring
    error, _, peak = measure(lambda: load_sequence(pvd))
    assert isinstance(error, InputError) and "truncated" in str(error), error
    assert peak < 1_000_000, peak
    header = np.array([216], "<u8").tobytes()
    refused(tmp_path, points_only(header + bytes(216), count, False), "not the 300000000000")
    ascii = written(SURFACE, FACES, "PolyData", Layout("ascii"))
    refused(tmp_path, ascii.replace(b'Points="9"', b'Points="900000000000"'), "holds 27 numbers")


def test_truncated_base64_and_appended_data_are_refused(tmp_path):
    inline = written(SURFACE, FACES, "PolyData", Layout("binary", compress=False))
    start = inline.index(b'format="binary">\n') + 17
    refused(tmp_path, inline[:start] + inline[start + 20 :], "truncated")
    damaged = inline[: start + 5] + b"*" + inline[start + 6 :]
    refused(tmp_path, damaged, "not valid base64")
    for layout in (Layout(), Layout(compress=False), Layout(base64=True)):
        data = written(SURFACE, FACES, "PolyData", layout)
        cut = data[: data.rindex(b"\n</AppendedData>") - 10]
        refused(tmp_path, cut, "truncated")
        refused(tmp_path, cut[: cut.index(b"\n_") + 4], "truncated|beyond")
    record = np.array([10**6], "<u8").tobytes()
    refused(tmp_path, points_only(base64.b64encode(record + bytes(30)), 9, False, True), "holds")


def test_compressors_other_than_zlib_are_refused_by_name(tmp_path):
    data = written(SURFACE, FACES, "PolyData", Layout())
    lzma = data.replace(b"vtkZLibDataCompressor", b"vtkLZMADataCompressor")
    refused(tmp_path, lzma, "compressed with vtkLZMADataCompressor, which is not read here")


ASCII = written(SURFACE, FACES, "PolyData", Layout("ascii"))
GRID = written(SURFACE, FACES, "UnstructuredGrid", Layout("ascii"))
FIRST_OFFSETS = re.compile(rb'(Name="offsets" format="ascii">\n)3 7')


@pytest.mark.parametrize(
    ("data", "message"),
    [
        (ASCII.replace(b'type="PolyData"', b'type="ImageData"', 1), "reads UnstructuredGrid"),
        (ASCII.replace(b"Piece", b"Peace"), r"has no <PolyData><Piece>"),
        (ASCII.replace(b'NumberOfPoints="9"', b'NumberOfPoints="-1"'), "not a count"),
        (ASCII.replace(b'Components="3"', b'Components="2"'), "NumberOfComponents='2', not 3"),
        (ASCII.replace(b'type="Float64"', b'type="Float16"'), "'Float16' is not a number type"),
        (ASCII.replace(b'format="ascii"', b'format="hex"', 1), "has format 'hex'"),
        (ASCII.replace(b"LittleEndian", b"MiddleEndian"), "byte_order 'MiddleEndian'"),
        (ASCII.replace(b'"UInt64"', b'"UInt16"'), "header_type 'UInt16'"),
        (ASCII.replace(b" 0.", b" x.", 1), "a value is not a float64 number"),
        (FIRST_OFFSETS.sub(rb"\g<1>3 2", ASCII), "the offset of cell 1 is less than"),
        (ASCII.replace(b"7 11 16", b"7 11 15"), "the offsets end at 15 but the connectivity"),
        (FIRST_OFFSETS.sub(rb"\g<1>2 7", ASCII), "Polys: cell 0 has 2 points, fewer than 3"),
        (ASCII.replace(b'NumberOfLines="0"', b'NumberOfLines="2"'), "holds 2 line cells"),
        (ASCII.replace(b'Name="offsets"', b'Name="ends"'), "no DataArray named 'offsets'"),
        (
            ASCII.replace(b'type="Int32" Name="connectivity"', b'type="Float32" Name="c"').replace(
                b'Name="c"', b'Name="connectivity"'
            ),
            "holds float32 values, not integers",
        ),
        (GRID.replace(b"5 9 9 7", b"5 5 9 7"), "cell 1 is a triangle of 4 points"),
    ],
)
def test_a_broken_file_is_refused_saying_why(tmp_path, data, message):
    assert data not in (ASCII, GRID), "the edit must change the file"
    refused(tmp_path, data, message)


def test_broken_appended_data_is_refused_saying_why(tmp_path):
    data = written(SURFACE, FACES, "PolyData", Layout())
    refused(tmp_path, data.replace(b"\n_", b"\n"), "does not begin with the _ marker")
    refused(tmp_path, data.replace(b'encoding="raw"', b'encoding="hex"'), "'hex', not raw or")
    refused(tmp_path, data.replace(b'offset="0"', b'offset="999999"'), "beyond the")
    refused(tmp_path, data.replace(b'offset="0"', b'offset="x"'), "needs an offset")
    ascii = ASCII.replace(b'format="ascii"', b'format="appended" offset="0"', 1)
    refused(tmp_path, ascii, "the file has no <AppendedData>")
    big = ASCII.replace(b'type="Int32" Name="connectivity"', b'type="UInt64" Name="connectivity"')
    refused(tmp_path, big.replace(b">\n0 1 4 ", b">\n18446744073709551615 1 4 ", 1), "Int64")


# ------------------------------------------------------------------------------------------
# property test: any damage is an InputError naming the frame, or a valid mesh

BASES = [written(SURFACE, FACES, "PolyData", layout) for layout in LAYOUTS.values()] + [
    written(SURFACE, FACES, "UnstructuredGrid", Layout()),
    (DATA / "encodings" / "appended-base64-zlib32.vtp").read_bytes(),
]
TOKENS = [b"<Piece>", b'offset="0"', b"_", b"=", b"AAAA", b'"UInt32"', b"</DataArray>", b"9"]
EXAMPLES_RUN: dict[str, int] = {}
SCRATCH = scratch_folder()


@PROPERTY
@given(data=st.one_of(*(mutations(BASES[n], TOKENS) for n in (0, 4, 9, 10, 11))))
def test_damaged_frames_are_input_errors_or_valid_meshes(data: bytes) -> None:
    EXAMPLES_RUN["damaged frame"] = EXAMPLES_RUN.get("damaged frame", 0) + 1
    pvd, frame = frame_file(SCRATCH, data)
    try:
        seq = load_sequence(pvd)
    except InputError as error:
        refusal: InputError | None = error
    else:
        refusal = None
        assert seq.vertex_count > 0 and np.isfinite(seq.vertices).all()
    assert refusal is None or (refusal.path, refusal.frame) == (str(frame), 0), str(refusal)


def teardown_module() -> None:
    """Remove the scratch folder; report how many examples each property test ran (``-s``)."""
    shutil.rmtree(SCRATCH, ignore_errors=True)
    report_examples(EXAMPLES_RUN)
