"""The tuckercodec codec for zarr (formats 2 and 3), numcodecs and dask.array.

The cloth sample as an array of 60 frames chunked by 20: every round trip's decoded KG over the
whole array is at most the target; dask reads one chunk for a slice inside it; a fresh process
opens the arrays without importing tuckercodec (entry points). Needs the ``[zarr]`` extra; dask
for its one test.
"""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap

import numpy as np
import pytest

zarr = pytest.importorskip("zarr", reason="the zarr codec needs zarr: pip install '.[zarr]'")
numcodecs = pytest.importorskip(
    "numcodecs", reason="the zarr codec needs numcodecs: pip install '.[zarr]'"
)

import tuckercodec  # noqa: E402
from tuckercodec import InputError  # noqa: E402
from tuckercodec.metrics import kg_error  # noqa: E402
from tuckercodec.samples import sample_path  # noqa: E402
from tuckercodec.zarr_codec import TuckerNumcodec, TuckerZarrCodec, chunk  # noqa: E402
from tuckercodec.zarr_codec import numcodec as numcodec_module  # noqa: E402
from tuckercodec.zarr_codec import zarr3 as zarr3_module  # noqa: E402

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


def _write_v2(path, positions, chunks=FRAMES_PER_CHUNK):
    array = zarr.create_array(
        str(path),
        shape=positions.shape,
        chunks=(chunks, positions.shape[1], 3),
        dtype=positions.dtype,
        zarr_format=2,
        compressors=TuckerNumcodec(target_kg=TARGET, dtype=positions.dtype.str),
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
    original = zarr3_module.decode_chunk

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
        np.testing.assert_array_equal(np.load(name + ".npy"), zarr.open_array(name)[:])


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


def test_a_chunk_of_another_shape_than_the_arrays_is_refused(cloth):
    data = TuckerNumcodec(dtype="<f4").encode(cloth[:5, :100])
    with pytest.raises(ValueError, match=r"decodes to shape \(5, 100, 3\)"):
        chunk.decode_chunk(data, "<f4", shape=(10, 100, 3))
    assert numcodec_module.TuckerNumcodec is TuckerNumcodec


def test_the_zarr_benchmark_measures_what_it_stores(tmp_path):
    from tools import bench_zarr
    from tuckercodec.samples import sheet_triangles, wave_sheet

    sheet = tuckercodec.MeshSequence(wave_sheet(frames=24, grid=9), sheet_triangles(9))
    result = bench_zarr.measure(sheet, 1.0, 8, 1, tmp_path)
    assert [c.frames for c in result.chunks] == [8, 8, 8]
    assert result.kg <= 1.0
    chunk_objects = bench_zarr._chunk_objects(tmp_path / "kg1.zarr")
    assert result.chunk_bytes == sum(p.stat().st_size for p in chunk_objects)
    assert result.store_bytes > result.chunk_bytes  # zarr.json too
    assert result.ratio == result.chunk_bytes / result.tkc_bytes
    table = bench_zarr.report("sheet", sheet, 8, [result])
    assert f"| 1 | all | 24 | | {result.chunk_bytes} |" in table
