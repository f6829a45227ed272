"""The tuckercodec codec for zarr (formats 2 and 3), numcodecs and dask.array.

The cloth sample as an array of 60 frames chunked by 20: every round trip's decoded KG over the
whole array is at most the target; dask reads one chunk for a slice inside it; a fresh process
opens the arrays without importing tuckercodec (entry points). The fitted mode (one basis in the
configuration) the same way, and every chunk on its own within the target. Needs the ``[zarr]``
extra; dask for its tests.
"""

from __future__ import annotations

import base64
import json
import math
import subprocess
import sys
import textwrap
from typing import Any

import numpy as np
import pytest

zarr = pytest.importorskip("zarr", reason="the zarr codec needs zarr: pip install '.[zarr]'")
numcodecs = pytest.importorskip(
    "numcodecs", reason="the zarr codec needs numcodecs: pip install '.[zarr]'"
)

import tuckercodec  # noqa: E402
from tuckercodec import InputError  # noqa: E402
from tuckercodec.encoder.segmented import SharedBasis  # noqa: E402
from tuckercodec.io.samples import sample_path  # noqa: E402
from tuckercodec.measures.distortion import kg_error  # noqa: E402
from tuckercodec.zarr_codec import FittedBasis, TuckerNumcodec, TuckerZarrCodec, chunk  # noqa: E402
from tuckercodec.zarr_codec import chunk as chunk_module  # noqa: E402
from tuckercodec.zarr_codec import numcodec as numcodec_module  # noqa: E402
from tuckercodec.zarr_codec import zarr3 as zarr3_module  # noqa: E402
from tuckercodec.zarr_codec.fitted import ArrayFrames, fitted_gap  # noqa: E402

TARGET = 0.1
FRAMES_PER_CHUNK = 20


@pytest.fixture(scope="module")
def cloth() -> np.ndarray:
    """The cloth sample's positions, float32 as shipped: (60, 3101, 3)."""
    with np.load(sample_path()) as data:
        return np.asarray(data["V"])


def _write_v3(path, positions, chunks=FRAMES_PER_CHUNK, codec=None):
    array = zarr.create_array(
        str(path),
        shape=positions.shape,
        chunks=(chunks, positions.shape[1], 3),
        dtype=positions.dtype,
        serializer=codec or TuckerZarrCodec(target_kg=TARGET),
        compressors=None,
    )
    array[:] = positions
    return array


def _write_v2(path, positions, chunks=FRAMES_PER_CHUNK, codec=None):
    array = zarr.create_array(
        str(path),
        shape=positions.shape,
        chunks=(chunks, positions.shape[1], 3),
        dtype=positions.dtype,
        zarr_format=2,
        compressors=codec or TuckerNumcodec(target_kg=TARGET, dtype=positions.dtype.str),
    )
    array[:] = positions
    return array


def _chunk_files(path):
    return sorted(p for p in path.rglob("*") if p.is_file() and not p.name.startswith((".", "z")))


@pytest.fixture(scope="module")
def stores(cloth, tmp_path_factory):
    """The cloth written once per zarr format and dtype (each write encodes 3 chunks)."""
    root = tmp_path_factory.mktemp("zarr")
    paths = {}
    for dtype in (np.float32, np.float64):
        positions = cloth.astype(dtype)
        name = np.dtype(dtype).name
        for zarr_format, write in ((3, _write_v3), (2, _write_v2)):
            paths[zarr_format, name] = root / f"v{zarr_format}-{name}.zarr"
            write(paths[zarr_format, name], positions)
    return paths


@pytest.mark.parametrize("zarr_format", [2, 3])
@pytest.mark.parametrize("dtype", ["float32", "float64"])
def test_round_trip_meets_the_target_over_the_whole_array(cloth, stores, zarr_format, dtype):
    path = stores[zarr_format, dtype]
    decoded = zarr.open_array(str(path))[:]
    assert decoded.dtype == np.dtype(dtype) and decoded.shape == cloth.shape
    original = cloth.astype(dtype)
    assert 0 < kg_error(original, decoded) <= TARGET
    files = _chunk_files(path)
    assert len(files) == 3
    # every chunk is a .tkc file of 20 frames that tuckercodec itself reads
    for file in files:
        header = tuckercodec.info(file.read_bytes())
        assert (header.frames, header.vertices) == (FRAMES_PER_CHUNK, cloth.shape[1])
    stored = sum(f.stat().st_size for f in files)
    assert stored < cloth.size * 4 / 5  # it compresses (about 10x here), not a raw copy


def test_the_chunks_configuration_is_in_the_array_metadata(stores):
    v3 = json.loads((stores[3, "float32"] / "zarr.json").read_text())
    assert v3["codecs"] == [{"name": "tuckercodec", "configuration": {"target_kg": TARGET}}]
    v2 = json.loads((stores[2, "float32"] / ".zarray").read_text())
    assert v2["compressor"] == {"id": "tuckercodec", "target_kg": TARGET, "dtype": "<f4"}


@pytest.mark.parametrize("zarr_format", [2, 3])
def test_a_partial_edge_chunk_round_trips(cloth, tmp_path, zarr_format):
    # 60 frames in chunks of 25: the last chunk holds 10 frames, padded by zarr to 25
    write = _write_v3 if zarr_format == 3 else _write_v2
    positions = cloth[:, :1000]  # a third of the vertices: the same paths, a third of the time
    write(tmp_path / "a.zarr", positions, chunks=25)
    array = zarr.open_array(str(tmp_path / "a.zarr"))
    assert kg_error(positions, array[:]) <= TARGET
    assert kg_error(positions[50:], array[50:]) <= TARGET  # the real frames of the padded chunk
    # format 3 stores the 10 real frames alone; format 2 cannot restore padding, so stores it
    edge = max(_chunk_files(tmp_path / "a.zarr"), key=str)  # c/2/0/0 or 2.0.0
    assert tuckercodec.info(edge.read_bytes()).frames == (10 if zarr_format == 3 else 25)


def test_zarr3_cuts_the_padding_of_vertex_chunks_too(cloth, tmp_path):
    positions = cloth[:20, :1000]
    array = zarr.create_array(
        str(tmp_path / "v.zarr"),
        shape=positions.shape,
        chunks=(20, 300, 3),  # the fourth chunk holds 100 vertices, padded to 300
        dtype=positions.dtype,
        serializer=TuckerZarrCodec(target_kg=TARGET),
        compressors=None,
    )
    array[:] = positions
    assert kg_error(positions, array[:]) <= TARGET
    last = tmp_path / "v.zarr" / "c" / "0" / "3" / "0"
    assert tuckercodec.info(last.read_bytes()).vertices == 100


def test_dask_reads_lazily_decoding_only_the_chunks_a_slice_needs(cloth, stores, monkeypatch):
    da = pytest.importorskip("dask.array", reason="the lazy read needs dask: pip install dask")
    calls: list[tuple[int, ...] | None] = []
    original = chunk_module.decode_chunk

    def counting(*args, **kwargs):
        calls.append(kwargs.get("shape"))
        return original(*args, **kwargs)

    monkeypatch.setattr(zarr3_module, "decode_chunk", counting)
    lazy = da.from_zarr(str(stores[3, "float32"]))
    assert lazy.chunks[0] == (20, 20, 20)
    assert calls == []  # opening decodes nothing
    part = lazy[45:50, :100].compute(scheduler="synchronous")
    assert len(calls) == 1  # frames 45..49 lie in the third chunk only
    direct = zarr.open_array(str(stores[3, "float32"]))[45:50, :100]
    np.testing.assert_array_equal(part, direct)
    calls.clear()
    whole = lazy.compute(scheduler="synchronous")
    assert len(calls) == 3
    assert kg_error(cloth, whole) <= TARGET


READER = textwrap.dedent(
    """
    import sys
    import numcodecs, numpy, zarr
    assert "tuckercodec" not in sys.modules
    codec = numcodecs.get_codec({"id": "tuckercodec", "target_kg": 0.5, "dtype": "<f4"})
    assert codec.get_config() == {"id": "tuckercodec", "target_kg": 0.5, "dtype": "<f4"}
    for name in sys.argv[1:]:
        numpy.save(name + ".npy", zarr.open_array(name)[:])
    print(type(codec).__name__)
    """
)


def test_a_fresh_process_reads_both_formats_without_importing_tuckercodec(stores, tmp_path):
    names = [str(stores[3, "float32"]), str(stores[2, "float64"])]
    done = subprocess.run(
        [sys.executable, "-c", READER, *names],
        cwd=tmp_path,  # not the repository: tuckercodec comes from the installation
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "TuckerNumcodec"
    for name in names:
        _assert_same_reading(np.load(name + ".npy"), zarr.open_array(name)[:])


def _assert_same_reading(theirs, ours):
    """The same decoded array, to float64's last bits: the reconstruction's matrix products
    round differently with another number of BLAS threads (a child started after a Dask
    nanny wrote OPENBLAS_NUM_THREADS=1 into os.environ has one, this process two)."""
    assert theirs.dtype == ours.dtype and theirs.shape == ours.shape
    np.testing.assert_allclose(theirs, ours, rtol=0, atol=1e-13 * np.abs(ours).max())


@pytest.mark.parametrize(
    "config",
    [{}, {"target_kg": 1.5}, {"ranks": [12, 5]}, {"target_bpfv": 2.0}, {"dtype": ">f4"}],
)
def test_the_numcodecs_configuration_round_trips(config):
    codec = numcodecs.get_codec({"id": "tuckercodec", **config})
    assert isinstance(codec, TuckerNumcodec)
    saved = json.loads(json.dumps(codec.get_config()))
    assert saved["id"] == "tuckercodec"
    assert {k: v for k, v in config.items() if k != "dtype"}.items() <= saved.items()
    assert numcodecs.get_codec(saved) == codec
    assert eval(repr(codec), {"TuckerNumcodec": TuckerNumcodec}) == codec


@pytest.mark.parametrize("config", [{}, {"target_kg": 1.5}, {"ranks": [12, 5]}, {"target_bpfv": 2}])
def test_the_zarr3_configuration_round_trips(config):
    codec = TuckerZarrCodec(**config)
    entry = json.loads(json.dumps(codec.to_dict()))
    assert entry["name"] == "tuckercodec"
    assert TuckerZarrCodec.from_dict(entry) == codec
    assert zarr.registry.get_codec_class("tuckercodec") is TuckerZarrCodec
    assert entry["configuration"] == (config or {"target_kg": 0.1})
    assert eval(repr(codec), {"TuckerZarrCodec": TuckerZarrCodec}) == codec


@pytest.mark.parametrize(
    ("config", "message"),
    [
        ({"target_kg": 0.1, "ranks": [3, 2]}, "not target_kg and ranks"),
        ({"target_kg": -1}, "positive finite"),
        ({"target_kg": float("nan")}, "positive finite"),
        ({"ranks": [0, 2]}, "two integers >= 1"),
        ({"ranks": [2.5, 2]}, "two integers >= 1"),
        ({"dtype": "int16"}, "floating-point positions, not int16"),
        ({"level": 3}, "unknown keys"),
    ],
)
def test_a_bad_numcodecs_configuration_is_refused(config, message):
    with pytest.raises(ValueError, match=message):
        numcodecs.get_codec({"id": "tuckercodec", **config})


def test_a_bad_zarr3_entry_is_refused():
    with pytest.raises(ValueError, match="unknown keys"):
        TuckerZarrCodec.from_dict({"name": "tuckercodec", "configuration": {"levl": 3}})
    with pytest.raises(ValueError, match="named 'tuckercodec'"):
        TuckerZarrCodec.from_dict({"name": "zstd"})


@pytest.mark.parametrize("shape", [(10, 5), (10, 5, 2), (2, 10, 5, 3), (0, 5, 3)])
def test_a_chunk_of_another_shape_is_refused_naming_its_shape(shape):
    with pytest.raises(InputError, match=r"shape \(frames, vertices, 3\).*" + f"{shape}"[1:-1]):
        TuckerNumcodec().encode(np.zeros(shape))


def test_zarr3_refuses_an_array_no_chunk_of_which_could_be_encoded(tmp_path):
    def create(shape, chunks, dtype="f4"):
        zarr.create_array(
            str(tmp_path / "bad.zarr"),
            shape=shape,
            chunks=chunks,
            dtype=dtype,
            serializer=TuckerZarrCodec(),
            compressors=None,
            overwrite=True,
        )

    with pytest.raises(ValueError, match=r"shape \(frames, vertices, 3\), not \(60, 100\)"):
        create((60, 100), (20, 100))
    with pytest.raises(ValueError, match="splits the last axis"):
        create((60, 100, 3), (20, 100, 1))
    with pytest.raises(ValueError, match="floating-point positions, not int32"):
        create((60, 100, 3), (20, 100, 3), dtype="i4")


def test_numcodecs_refuses_a_chunk_of_another_dtype_than_its_own(cloth):
    with pytest.raises(InputError, match=r"TuckerNumcodec\(dtype='<f4'\)"):
        TuckerNumcodec().encode(cloth[:5])


def test_numcodecs_refuses_a_fortran_ordered_chunk(cloth):
    with pytest.raises(InputError, match="order='C'"):
        TuckerNumcodec(dtype="<f4").encode(np.asfortranarray(cloth[:5]))


@pytest.mark.parametrize("dtype", ["<f2", "<f4", ">f4", "<f8"])
def test_numcodecs_round_trip_meets_the_target_in_each_dtype(cloth, dtype):
    # float16 rounding alone takes the decoded KG of these frames from 0.0993 to 0.1012: the
    # codec must see it and encode again, tighter
    positions = cloth[40:50, :500].astype(dtype)
    codec = TuckerNumcodec(target_kg=TARGET, dtype=dtype)
    decoded = codec.decode(codec.encode(positions))
    assert decoded.dtype == np.dtype(dtype) and decoded.shape == positions.shape
    assert kg_error(positions, decoded) <= TARGET


def test_numcodecs_decodes_into_out(cloth):
    positions = cloth[:10, :400]
    codec = TuckerNumcodec(dtype="<f4")
    data = codec.encode(positions)
    expected = codec.decode(data)
    floats = np.empty_like(positions)
    assert codec.decode(data, out=floats) is floats
    np.testing.assert_array_equal(floats, expected)
    raw = bytearray(positions.nbytes)  # zarr's flat buffer of bytes
    codec.decode(data, out=raw)
    np.testing.assert_array_equal(np.frombuffer(raw, "<f4").reshape(positions.shape), expected)
    with pytest.raises(ValueError, match="out has 8 bytes"):
        codec.decode(data, out=bytearray(8))


def _constant(frames, vertices):
    return np.broadcast_to(np.array([1.0, -2.0, 3.5]), (frames, vertices, 3)).copy()


@pytest.mark.parametrize(
    "positions",
    [
        _constant(8, 50),  # all one point everywhere
        np.zeros((8, 50, 3)),  # zarr's fill value, written with write_empty_chunks
        np.random.default_rng(1).normal(size=(8, 1, 3)),  # one vertex: each frame a point
        _constant(8, 50) * 1e9 + np.random.default_rng(2).normal(size=(8, 50, 3)) * 1e-3,
    ],
    ids=["constant", "zeros", "one-vertex", "shape-below-float64"],
)
def test_a_chunk_with_no_shape_is_stored_exactly(positions):
    codec = TuckerNumcodec()
    data = codec.encode(positions)
    assert data.startswith(chunk.POINT_MAGIC)
    np.testing.assert_array_equal(codec.decode(data), positions)


@pytest.mark.parametrize(
    "positions",
    [
        np.concatenate([np.zeros((5, 60, 3)), np.random.default_rng(3).normal(size=(1, 60, 3))]),
        np.repeat(np.random.default_rng(4).normal(size=(1, 60, 3)), 6, axis=0),
        np.random.default_rng(5).normal(size=(1, 60, 3)),
    ],
    ids=["mostly-padding", "identical-frames", "one-frame"],
)
def test_degenerate_chunks_with_a_shape_meet_the_target(positions):
    codec = TuckerNumcodec()
    data = codec.encode(positions)
    assert tuckercodec.info(data).frames == positions.shape[0]
    assert kg_error(positions, codec.decode(data)) <= TARGET


def test_ranks_are_capped_at_what_a_short_chunk_has(cloth):
    codec = TuckerNumcodec(ranks=[500, 50], dtype="<f4")
    data = codec.encode(cloth[:4, :300])
    assert tuckercodec.info(data).ranks == (12, 4)


def test_zarr3_keeps_a_nan_fill_value_where_nothing_was_written(cloth, tmp_path):
    array = zarr.create_array(
        str(tmp_path / "nan.zarr"),
        shape=(25, 200, 3),
        chunks=(10, 200, 3),
        dtype="f4",
        fill_value=float("nan"),
        serializer=TuckerZarrCodec(),
        compressors=None,
    )
    array[:17] = cloth[:17, :200]  # frames 17..19 of the second chunk are never written
    decoded = array[:]
    assert kg_error(cloth[:17, :200], decoded[:17]) <= TARGET
    assert np.isnan(decoded[17:]).all()


def test_zarr2_names_a_nan_fill_value_padding_an_edge_chunk(cloth, tmp_path):
    array = zarr.create_array(
        str(tmp_path / "nan.zarr"),
        shape=(15, 200, 3),
        chunks=(10, 200, 3),
        dtype="f4",
        fill_value=float("nan"),
        zarr_format=2,
        compressors=TuckerNumcodec(dtype="<f4"),
    )
    with pytest.raises(InputError, match="NaN fill_value cannot be encoded"):
        array[:] = cloth[:15, :200]


def test_a_point_chunk_that_is_damaged_is_refused():
    data = TuckerNumcodec().encode(_constant(4, 10))
    with pytest.raises(ValueError, match="point chunk"):
        TuckerNumcodec().decode(data[:-3])
    with pytest.raises(ValueError, match="declares"):
        TuckerNumcodec().decode(data[:8] + b"\xff" * 8 + data[16:])


def _refused(call) -> tuple[int, str]:
    """The most memory Python and numpy held during ``call()``, which must raise a ValueError
    saying what the chunk declares, and its message."""
    import tracemalloc

    tracemalloc.start()
    try:
        with pytest.raises(ValueError, match="declares") as caught:
            call()
        return tracemalloc.get_traced_memory()[1], str(caught.value)
    finally:
        tracemalloc.stop()


def test_a_chunk_declaring_more_than_the_arrays_chunks_is_refused_before_decompressing(cloth):
    """A crafted chunk: a 1x10x3 array's chunk of a few KB declaring millions of
    positions is refused from its head, not decompressed to what it declares."""
    import zstandard

    declared = (1, 2_000_000)  # 48 MB of float64 positions, from 1.6 KB of zstd
    hostile = chunk_module._POINT_HEAD.pack(chunk_module.POINT_MAGIC, *declared)
    hostile += zstandard.ZstdCompressor().compress(bytes(declared[0] * declared[1] * 24))
    assert len(hostile) < 20_000
    calls = {
        "format 3": lambda: chunk.decode_chunk(hostile, "<f4", shape=(1, 10, 3), fill_value=0),
        "format 2": lambda: TuckerNumcodec(dtype="<f4").decode(
            hostile, out=np.empty((1, 10, 3), "<f4")
        ),
    }
    for where, call in calls.items():
        peak, message = _refused(call)
        assert peak < 1 << 20, where
        assert "point chunk declares 1 frames of 2000000 vertices" in message, where
    tkc = TuckerNumcodec(dtype="<f4").encode(cloth[:5, :100])  # a .tkc chunk: its header
    peak, message = _refused(lambda: chunk.decode_chunk(tkc, "<f4", shape=(1, 10, 3)))
    assert peak < 1 << 20 and "the chunk declares more than the array's chunks hold" in message
    # a chunk that fits still decodes, through both
    small = TuckerNumcodec(dtype="<f4").encode(cloth[:1, :10])
    assert chunk.decode_chunk(small, "<f4", shape=(1, 10, 3)).shape == (1, 10, 3)
    out = np.empty((1, 10, 3), "<f4")
    TuckerNumcodec(dtype="<f4").decode(small, out=out)
    assert np.allclose(out, cloth[:1, :10], atol=1e-2)


def test_a_chunk_of_another_shape_than_the_arrays_is_refused(cloth):
    data = TuckerNumcodec(dtype="<f4").encode(cloth[:5, :100])
    with pytest.raises(ValueError, match=r"decodes to shape \(5, 100, 3\)"):
        chunk.decode_chunk(data, "<f4", shape=(10, 100, 3))
    assert numcodec_module.TuckerNumcodec is TuckerNumcodec


def test_the_zarr_benchmark_measures_what_it_stores(tmp_path):
    from tools.bench import zarr as bench_zarr
    from tuckercodec.io.samples import sheet_triangles, wave_sheet

    sheet = tuckercodec.MeshSequence(wave_sheet(frames=24, grid=9), sheet_triangles(9))
    result = bench_zarr.measure(sheet, 1.0, 8, 1, tmp_path)
    assert [c.frames for c in result.chunks] == [8, 8, 8]
    assert result.kg <= 1.0
    chunk_objects = bench_zarr._chunk_objects(tmp_path / "kg1.zarr")
    assert result.chunk_bytes == sum(p.stat().st_size for p in chunk_objects)
    assert result.store_bytes > result.chunk_bytes  # zarr.json too
    assert result.ratio == result.chunk_bytes / result.tkc_bytes
    assert result.kg <= result.worst_chunk_kg <= 1.0  # chunks meet it alone, the whole too
    fitted = bench_zarr.measure_fitted(sheet, 1.0, 8, 1, tmp_path)
    assert fitted.kg <= 1.0 and fitted.worst_chunk_kg <= 1.0
    objects = bench_zarr._chunk_objects(tmp_path / "fitted-kg1.zarr")
    assert fitted.chunk_bytes == sum(p.stat().st_size for p in objects)
    assert fitted.data_bytes == fitted.chunk_bytes + fitted.basis_bytes
    assert fitted.basis_text_bytes > 4 / 3 * fitted.basis_bytes  # base64 of it and its params
    assert fitted.store_bytes > fitted.chunk_bytes + fitted.basis_text_bytes  # zarr.json holds it
    assert fitted.whole_chunks == 0 and all(c.u1_bytes == 0 for c in fitted.chunks)
    table = bench_zarr.report("sheet", sheet, 8, [result], [fitted])
    assert f"| 1 | all | 24 | | {result.chunk_bytes} |" in table
    assert f"| 1 | {fitted.chunk_bytes} | {fitted.basis_columns} | {fitted.basis_bytes} |" in table


# ------------------------------------------------------------------------------------------
# the fitted mode: one basis in the configuration, each chunk its own part


@pytest.fixture(scope="module")
def fitted(cloth, tmp_path_factory):
    """The cloth written by codecs fitted to it, in each zarr format (float32, as shipped)."""
    root = tmp_path_factory.mktemp("fitted")
    v3 = TuckerZarrCodec.fit(cloth, target_kg=TARGET, chunk_frames=FRAMES_PER_CHUNK)
    v2 = TuckerNumcodec.fit(cloth, target_kg=TARGET, chunk_frames=FRAMES_PER_CHUNK)
    _write_v3(root / "v3.zarr", cloth, codec=v3)
    _write_v2(root / "v2.zarr", cloth, codec=v2)
    return {3: root / "v3.zarr", 2: root / "v2.zarr", "v3": v3, "v2": v2}


def _chunk_kgs(original, decoded, frames=FRAMES_PER_CHUNK):
    return [
        kg_error(original[a : a + frames], decoded[a : a + frames])
        for a in range(0, len(original), frames)
    ]


@pytest.mark.parametrize("zarr_format", [2, 3])
def test_a_fitted_codec_meets_the_target_in_every_chunk_with_chunks_a_fraction_of_the_size(
    cloth, stores, fitted, zarr_format
):
    decoded = zarr.open_array(str(fitted[zarr_format]))[:]
    assert decoded.dtype == cloth.dtype and decoded.shape == cloth.shape
    assert 0 < kg_error(cloth, decoded) <= TARGET
    assert max(_chunk_kgs(cloth, decoded)) <= TARGET  # each chunk on its own
    files = _chunk_files(fitted[zarr_format])
    assert len(files) == 3
    assert all(fitted_gap(f.read_bytes()) is not None for f in files)  # none fell back
    own = sum(f.stat().st_size for f in _chunk_files(stores[zarr_format, "float32"]))
    assert sum(f.stat().st_size for f in files) < own / 4  # about 1/6 here: no U1 in them
    # a chunk and the basis make the whole .tkc, which tuckercodec reads and checks
    basis = fitted["v3"].basis
    whole = basis.complete(files[0].read_bytes())
    assert tuckercodec.info(whole).frames == FRAMES_PER_CHUNK
    tuckercodec.Decoder(whole).check()


def test_dask_writes_and_reads_a_fitted_array(cloth, fitted, tmp_path):
    da = pytest.importorskip("dask.array", reason="the lazy read needs dask: pip install dask")
    store = zarr.create_array(
        str(tmp_path / "d.zarr"),
        shape=cloth.shape,
        chunks=(FRAMES_PER_CHUNK, cloth.shape[1], 3),
        dtype=cloth.dtype,
        serializer=fitted["v3"],
        compressors=None,
    )
    da.from_array(cloth, chunks=(FRAMES_PER_CHUNK, -1, -1)).to_zarr(store)
    assert all(fitted_gap(f.read_bytes()) for f in _chunk_files(tmp_path / "d.zarr"))
    lazy = da.from_zarr(str(tmp_path / "d.zarr"))
    assert lazy.chunks[0] == (20, 20, 20)
    decoded = lazy.compute()
    assert max(_chunk_kgs(cloth, decoded)) <= TARGET
    np.testing.assert_array_equal(lazy[25:35].compute(), decoded[25:35])


def test_both_codecs_fit_the_same_basis_and_keep_it_in_the_metadata(fitted):
    v3, v2 = fitted["v3"], fitted["v2"]
    assert v3.basis == v2.basis and v3.basis.vertices == 3101
    entry = json.loads((fitted[3] / "zarr.json").read_text())["codecs"][0]
    assert entry["configuration"] == {"target_kg": TARGET, **v3.basis.config()}
    compressor = json.loads((fitted[2] / ".zarray").read_text())["compressor"]
    assert compressor == {"id": "tuckercodec", "target_kg": TARGET, "dtype": "<f4"} | (
        v2.basis.config()
    )
    assert len(v3.basis.text) == 4 * math.ceil(len(base64.b64decode(v3.basis.text)) / 3)


def test_a_fitted_configuration_round_trips_through_json(fitted):
    v3, v2 = fitted["v3"], fitted["v2"]
    entry = json.loads(json.dumps(v3.to_dict()))
    assert TuckerZarrCodec.from_dict(entry) == v3
    assert TuckerZarrCodec.from_dict(entry) != TuckerZarrCodec(target_kg=TARGET)
    assert hash(TuckerZarrCodec.from_dict(entry)) == hash(v3)
    saved = json.loads(json.dumps(v2.get_config()))
    assert numcodecs.get_codec(saved) == v2
    assert numcodecs.get_codec(saved) != TuckerNumcodec(target_kg=TARGET, dtype="<f4")
    assert repr(v3).startswith("TuckerZarrCodec(target_kg=0.1, basis=<basis of 3101 x ")
    assert repr(v2).endswith(f"sha256 {v2.basis.sha256[:12]}...>, dtype='<f4')")


def test_a_fresh_process_reads_fitted_arrays_without_importing_tuckercodec(fitted, tmp_path):
    names = [str(fitted[3]), str(fitted[2])]
    done = subprocess.run(
        [sys.executable, "-c", READER, *names],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    assert done.returncode == 0, done.stderr
    for name in names:
        _assert_same_reading(np.load(name + ".npy"), zarr.open_array(name)[:])


def _other_basis(basis: FittedBasis) -> FittedBasis:
    """The basis with one payload byte changed, its SHA-256 made right again."""
    payload = bytearray(basis.payload)
    payload[len(payload) // 2] ^= 0x10
    return FittedBasis.of(SharedBasis(basis.shared.params, bytes(payload)))


def test_a_damaged_basis_in_the_configuration_is_refused_naming_it(fitted, tmp_path):
    v3, v2 = fitted["v3"], fitted["v2"]
    text = v3.basis.text
    damaged = text[:100] + ("A" if text[100] != "A" else "B") + text[101:]
    config = {"target_kg": TARGET, "basis": damaged, "basis_sha256": v3.basis.sha256}
    with pytest.raises(ValueError, match="does not match its basis_sha256"):
        TuckerZarrCodec.from_dict({"name": "tuckercodec", "configuration": config})
    with pytest.raises(ValueError, match="does not match its basis_sha256"):
        numcodecs.get_codec({"id": "tuckercodec", **config})
    with pytest.raises(ValueError, match="not base64"):
        TuckerNumcodec(basis="not base64!", basis_sha256="00")
    # a basis that is consistent but another: the chunks' U1 entries say it is not theirs
    other = _other_basis(v2.basis)
    chunk_bytes = _chunk_files(fitted[2])[0].read_bytes()
    other_config: dict[str, Any] = other.config()
    with pytest.raises(ValueError, match="another basis than the codec's"):
        TuckerNumcodec(target_kg=TARGET, dtype="<f4", **other_config).decode(chunk_bytes)
    with pytest.raises(ValueError, match="written by a fitted tuckercodec codec"):
        TuckerNumcodec(target_kg=TARGET, dtype="<f4").decode(chunk_bytes)
    # and through zarr, with the configuration of zarr.json edited
    store = tmp_path / "edited.zarr"
    _write_v3(store, np.load(sample_path())["V"][:20], codec=v3)
    metadata = json.loads((store / "zarr.json").read_text())
    metadata["codecs"][0]["configuration"].update(_other_basis(v3.basis).config())
    (store / "zarr.json").write_text(json.dumps(metadata))
    with pytest.raises(ValueError, match="another basis than the codec's"):
        zarr.open_array(str(store))[:]


@pytest.mark.parametrize(
    ("config", "message"),
    [
        ({"ranks": [3, 2]}, "serves a KG target"),
        ({"target_bpfv": 2.0}, "serves a KG target"),
        ({"basis_sha256": None}, "both 'basis'"),
    ],
)
def test_a_fitted_configuration_without_a_kg_target_or_its_hash_is_refused(fitted, config, message):
    settings = {**fitted["v2"].basis.config(), **config}
    with pytest.raises(ValueError, match=message):
        TuckerNumcodec(**settings)


@pytest.mark.parametrize("zarr_format", [2, 3])
def test_a_chunk_the_basis_does_not_serve_is_stored_whole_and_meets_the_target(
    cloth, tmp_path, zarr_format
):
    # fitted on the first 40 frames: the last 20 move in ways its columns do not span
    positions = cloth[:, :1000]
    if zarr_format == 3:
        codec = TuckerZarrCodec.fit(positions[:40], target_kg=TARGET, chunk_frames=20)
        _write_v3(tmp_path / "a.zarr", positions, codec=codec)
    else:
        codec = TuckerNumcodec.fit(positions[:40], target_kg=TARGET, chunk_frames=20)
        _write_v2(tmp_path / "a.zarr", positions, codec=codec)
    decoded = zarr.open_array(str(tmp_path / "a.zarr"))[:]
    assert max(_chunk_kgs(positions, decoded)) <= TARGET
    first, second, last = (f.read_bytes() for f in _chunk_files(tmp_path / "a.zarr"))
    assert fitted_gap(first) is not None and fitted_gap(second) is not None
    assert fitted_gap(last) is None
    assert tuckercodec.info(last).frames == 20  # a whole .tkc, with its own U1


def test_a_chunk_of_fewer_frames_than_the_basis_has_columns_uses_it(cloth):
    positions = cloth[:, :1000]
    codec = TuckerNumcodec.fit(positions, target_kg=TARGET, chunk_frames=20)
    assert codec.basis is not None
    assert codec.basis.columns > 3 * 2  # wider than two frames' U1 could be (spec §6.7)
    for start, frames in ((0, 1), (40, 2), (50, 7)):
        part = positions[start : start + frames]
        data = codec.encode(part)
        assert fitted_gap(data) is not None
        assert kg_error(part, codec.decode(data)) <= TARGET


@pytest.mark.parametrize("zarr_format", [2, 3])
def test_a_short_edge_chunk_uses_the_basis(cloth, tmp_path, zarr_format):
    # 60 frames in chunks of 22: the last holds 16 (format 2 pads it to 22 with zeros)
    positions = cloth[:, :1000]
    if zarr_format == 3:
        codec = TuckerZarrCodec.fit(positions, target_kg=TARGET, chunk_frames=22)
        _write_v3(tmp_path / "a.zarr", positions, chunks=22, codec=codec)
    else:
        codec = TuckerNumcodec.fit(positions, target_kg=TARGET, chunk_frames=22)
        _write_v2(tmp_path / "a.zarr", positions, chunks=22, codec=codec)
    decoded = zarr.open_array(str(tmp_path / "a.zarr"))[:]
    assert kg_error(positions, decoded) <= TARGET
    assert kg_error(positions[44:], decoded[44:]) <= TARGET
    edge = max(_chunk_files(tmp_path / "a.zarr"), key=str)
    assert codec.basis is not None
    whole = codec.basis.complete(edge.read_bytes())
    assert edge.stat().st_size < len(whole) / 4
    assert tuckercodec.info(whole).frames == (16 if zarr_format == 3 else 22)


def test_a_fitted_codec_refuses_chunks_that_split_the_vertices(cloth, tmp_path):
    positions = cloth[:20, :300]
    codec = TuckerZarrCodec.fit(positions, target_kg=TARGET, chunk_frames=20)
    with pytest.raises(ValueError, match="splits the 300 vertices"):
        zarr.create_array(
            str(tmp_path / "split.zarr"),
            shape=positions.shape,
            chunks=(20, 100, 3),
            dtype=positions.dtype,
            serializer=codec,
            compressors=None,
        )
    with pytest.raises(ValueError, match="fitted to 300 vertices, not the array's 400"):
        _write_v3(tmp_path / "other.zarr", cloth[:20, :400], codec=codec)
    numcodec = TuckerNumcodec.fit(positions, target_kg=TARGET, chunk_frames=20)
    with pytest.raises(InputError, match="fitted to 300 vertices"):
        numcodec.encode(cloth[:20, :100])


class _CountingArray:
    """An array with zarr's ``chunks`` that records the frames of every read."""

    def __init__(self, values, frames_per_chunk):
        self.values, self.shape, self.dtype = values, values.shape, values.dtype
        self.chunks = (frames_per_chunk, *values.shape[1:])
        self.reads: list[tuple[int, int]] = []

    def __getitem__(self, key):
        self.reads.append((key.start, key.stop))
        return self.values[key]


def test_the_fit_reads_a_zarr_or_dask_array_a_chunk_at_a_time(cloth):
    da = pytest.importorskip("dask.array", reason="reading a dask array needs dask")
    positions = cloth[:, :500]
    expected = TuckerZarrCodec.fit(positions, target_kg=TARGET, chunk_frames=20)
    counting = _CountingArray(positions, 25)  # chunks of 25: reads of 16-frame blocks cross them
    assert TuckerZarrCodec.fit(counting, target_kg=TARGET, chunk_frames=20) == expected
    assert set(counting.reads) == {(0, 25), (25, 50), (50, 60)}
    passes = len(counting.reads) // 3
    assert counting.reads == [(0, 25), (25, 50), (50, 60)] * passes  # each once a pass
    lazy = da.from_array(positions, chunks=(7, -1, -1))
    assert TuckerNumcodec.fit(lazy, target_kg=TARGET, chunk_frames=20).basis == expected.basis
    frames = ArrayFrames(lazy)
    np.testing.assert_array_equal(frames.read(5, 30), positions[5:30].astype(np.float64))


def test_the_fit_names_what_it_cannot_read(cloth):
    with pytest.raises(InputError, match=r"shape \(frames, vertices, 3\), not \(60, 3101\)"):
        TuckerZarrCodec.fit(cloth[:, :, 0], chunk_frames=20)
    with pytest.raises(InputError, match="floating-point positions, not int32"):
        TuckerNumcodec.fit(cloth.astype(np.int32), chunk_frames=20)
    bad = cloth[:, :200].copy()
    bad[33, 7, 1] = np.nan
    with pytest.raises(InputError, match="frame 33"):
        TuckerNumcodec.fit(bad, chunk_frames=20)
    with pytest.raises(ValueError, match="chunk_frames must be an integer >= 1"):
        TuckerNumcodec.fit(cloth[:, :200], chunk_frames=0)
    with pytest.raises(ValueError, match="positive finite"):
        TuckerNumcodec.fit(cloth[:, :200], target_kg=-1.0, chunk_frames=20)
