"""The doors, one :class:`Target` each: how bytes become an input, the oracle, the seeds, the
mutator.

* ``decoder``: the bytes are a .tkc file; :func:`.container.check_input` is the oracle.
* ``segmented``: the same on segmented files (format 1.1), plus frames across the last segment
  boundary decoded alone and the last frame decoded from a path (sections read by range); each
  must equal the whole decode.
* ``face``: a msgpack array ``[codec, params, vertex_count, payload]``, given to the FACE
  section's decoder after the shape check the decoder makes first (§5 step 13); a decoded
  table must have the declared shape and indices within the vertices.
* ``zarr-chunk``: the first byte chooses a chunk shape, dtype and fill value, the rest is a
  chunk for the zarr codec's decoder, decoded as zarr format 3 does (shape known) and as
  numcodecs does (only the destination's size known). Its documented errors are
  ``FormatError`` and the codec's own ``ValueError`` (raised in tuckercodec).
* one per reader: the bytes are the file, or a bundle of files (:mod:`.mutators`: an XDMF with
  its ``.h5``, a ``.pvd`` with its ``.vtp`` files, a ``.gltf`` with its ``.bin``), written to a
  fresh folder and opened with :func:`tuckercodec.open_frames`; the whole sequence is loaded,
  and the last frame read again alone must equal it. The documented errors are ``InputError``
  and ``FormatError``; a sequence read must have finite positions. USD and Alembic are read
  through their isolated child, so each input costs a process (about 0.5 s).
"""

from __future__ import annotations

import atexit
import os
import random
import shutil
import tempfile
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from .container import (
    InvariantError,
    _containers_in,
    _hostile_value,
    _set_path,
    check_input,
    decoder_seeds,
    decompressed_start,
    mutate_container,
)
from .mutators import bundle, mutate_bundle, unbundle


@dataclass(frozen=True)
class Target:
    """One door into tuckercodec, as the fuzzer drives it."""

    name: str
    door: str  # one line: what it reads
    check: Callable[[bytes], str]  # the oracle: an outcome, or raises the crash
    seeds: Callable[[], dict[str, bytes]]  # small valid inputs, by file name
    mutate: Callable[[bytes, int, int], bytes]  # libFuzzer's custom mutator
    extra_seeds: tuple[str, ...] = ()  # globs in the repository (the conformance vectors)
    isolated: bool = False  # each input starts a process: run a few thousand, not millions
    needs: tuple[str, ...] = ()  # libraries it reads with: imported before the memory cap
    max_len: int = 8192
    #: the modules it exercises, each package with every module below it: imported under
    #: atheris' instrumentation before fuzzing (the package imports lazily)
    modules: tuple[str, ...] = ()


#: What every door goes through: the package's errors, the machine and the model, and the
#: tools' surface the checks and seeds import (which imports the codec).
COMMON_MODULES = (
    "tuckercodec.errors",
    "tuckercodec.system",
    "tuckercodec.model",
    "tuckercodec.internal",
)
#: The decoder and the parts of the format it reads.
DECODER_MODULES = (
    *COMMON_MODULES,
    "tuckercodec.decoder",
    "tuckercodec.format",
    "tuckercodec.files",
)
#: The readers, the isolated child's parent side and what the readers share.
READER_MODULES = (*COMMON_MODULES, "tuckercodec.io")


def _atheris_mutate(data: bytes, max_size: int) -> bytes:
    import atheris

    out: bytes = atheris.Mutate(data, max_size)
    return out


# ------------------------------------------------------------------------------------------
# the readers


_SCRATCH: list[Path] = []
#: Where a worker makes its scratch folder (set by the driver).
SCRATCH_VARIABLE = "TKC_FUZZ_SCRATCH"


def scratch_folder() -> Path:
    """A folder of this process's own (in memory, ``/dev/shm``, where there is one), emptied
    of the previous input's files."""
    if not _SCRATCH:
        memory = Path("/dev/shm")
        base = memory if memory.is_dir() and os.access(memory, os.W_OK) else None
        # the driver's, which it removes: libFuzzer ends its worker without running atexit
        given = os.environ.get(SCRATCH_VARIABLE)
        base = Path(given) if given else base
        _SCRATCH.append(Path(tempfile.mkdtemp(prefix="tkc-fuzz-read-", dir=base)))
        atexit.register(shutil.rmtree, _SCRATCH[0], True)
    folder = _SCRATCH[0]
    for path in folder.iterdir():
        if path.is_dir() and not path.is_symlink():
            shutil.rmtree(path, ignore_errors=True)
        else:
            path.unlink()
    return folder


def write_input(data: bytes, suffix_of: Callable[[bytes], str]) -> Path:
    """Write the input's files (a bundle's, or the bytes as one file) to the scratch folder;
    return the path of the first, named with a suffix its reader takes."""
    folder = scratch_folder()
    files = unbundle(data) or [("input" + suffix_of(data), data)]
    main_name, main_body = files[0]
    suffix = suffix_of(main_body)
    if not main_name.lower().endswith(suffix):
        main_name = Path(main_name).name.replace(".", "_") + suffix
    files[0] = (main_name, main_body)
    for name, body in files:
        path = folder / name
        if path.parent != folder:
            if path.parent.exists() and not path.parent.is_dir():
                continue
            path.parent.mkdir(exist_ok=True)
        if not path.is_dir():
            path.write_bytes(body)
    return folder / main_name


class _Opens:
    """Files opened by Python code (the ``open`` audit event) while a reader runs, outside
    the input's folder and the interpreter's and package's own files: a reader must never
    read a file its input names outside its folder (a .pvd's frames, an .xdmf's HDF5 file, a
    .gltf's buffers). Opens in C libraries (HDF5, pxr, Alembic) are not seen."""

    def __init__(self) -> None:
        self.folders: tuple[str, ...] = ()
        self.strays: list[str] = []
        self.allowed: tuple[str, ...] = ()

    def hook(self, event: str, args: tuple[Any, ...]) -> None:
        if event != "open" or not self.folders or not args:
            return
        name = args[0]
        if isinstance(name, (str, bytes, os.PathLike)):
            path = os.path.join(os.path.abspath(os.fsdecode(name)), "")  # a folder: its own
            if not path.startswith((*self.folders, *self.allowed)):  # name with a separator
                self.strays.append(path.rstrip(os.sep))

    def start(self, folder: Path, isolated: bool) -> None:
        if not self.allowed:
            import sys

            import tuckercodec

            sys.addaudithook(self.hook)
            package = str(Path(tuckercodec.__file__).resolve().parent)
            prefixes = {sys.prefix, sys.base_prefix, sys.exec_prefix, package}
            self.allowed = (*(p + os.sep for p in prefixes), "/dev/null/", "/proc/", "/sys/")
        self.folders = (str(folder) + os.sep,)
        if isolated:  # the child's stderr goes to a temporary file
            self.folders += (tempfile.gettempdir() + os.sep,)
        self.strays = []

    def stop(self) -> list[str]:
        self.folders = ()
        return self.strays


OPENS = _Opens()


def read_check(data: bytes, suffix_of: Callable[[bytes], str], isolated: bool = False) -> str:
    """The readers' oracle: ``open_frames`` loads the input, or raises InputError or
    FormatError; the last frame read alone equals the loaded one; positions are finite; no
    file outside the input's folder was opened (:class:`_Opens`)."""
    import numpy as np

    import tuckercodec as tc

    path = write_input(data, suffix_of)
    OPENS.start(path.parent, isolated)
    try:
        with tc.open_frames(path) as source:
            sequence = source.load()
            count = sequence.frame_count
            last = source.read(count - 1, count)
        outcome = "ok"
    except (tc.InputError, tc.FormatError) as error:
        outcome = type(error).__name__
    finally:
        strays = OPENS.stop()
    if strays:
        raise InvariantError(f"the reader opened {strays[0]!r}, outside the input's folder")
    if outcome != "ok":
        return outcome
    if not np.array_equal(last[0], sequence.vertices[-1]):
        raise InvariantError("the last frame read alone differs from the loaded one")
    if not np.isfinite(sequence.vertices).all():
        raise InvariantError("a sequence read with a non-finite position")
    return "ok"


def _suffix(suffix: str) -> Callable[[bytes], str]:
    return lambda data: suffix


def _usd_suffix(data: bytes) -> str:
    return ".usda" if data.lstrip()[:5] == b"#usda" else ".usdc"


def _small_sequences() -> dict[str, Any]:
    """The sequences the reader seeds are written from: triangles, polygons with names and a
    rate, points only, one frame, and a cut of the built-in sample."""
    import numpy as np

    import tuckercodec as tc
    from tuckercodec.internal import sample_path, sheet_triangles, wave_sheet

    frames = wave_sheet(3, 3)
    polygons = np.array([[0, 1, 4, 3], [1, 2, 5, -1], [3, 4, 7, 6], [4, 5, 8, 7]])
    sample = tc.load_sequence(sample_path(), progress=False)
    keep = np.unique(sample.faces[:6])
    remap = np.full(sample.vertex_count, -1)
    remap[keep] = np.arange(keep.size)
    return {
        "triangles": tc.MeshSequence(frames, sheet_triangles(3)),
        "polygons": tc.MeshSequence(frames, polygons, frame_names=["a", "b", "c"], frame_rate=24.0),
        "points": tc.MeshSequence(frames[:2, :4].astype(np.float32), np.zeros((0, 3), int)),
        "one-frame": tc.MeshSequence(frames[:1], sheet_triangles(3)),
        "sample": tc.MeshSequence(sample.vertices[:2, keep], remap[sample.faces[:6]]),
    }


def _written(suffix: str, only: tuple[str, ...] = ()) -> dict[str, bytes]:
    """Each small sequence written by the project's own writer for ``suffix`` (as a bundle
    when the writer makes companion files), by seed name; writers that refuse a sequence
    (a format without faces, say) give no seed for it. ``only``: these sequences alone."""
    import tuckercodec as tc

    seeds = {}
    for name, sequence in _small_sequences().items():
        if only and name not in only:
            continue
        folder = Path(tempfile.mkdtemp(prefix="tkc-fuzz-seed-"))
        try:
            try:
                tc.save_sequence(sequence, folder / f"a{suffix}")
            except (ValueError, tc.InputError):
                continue
            files = sorted(p for p in folder.rglob("*") if p.is_file())
            main = folder / f"a{suffix}"
            others = [p for p in files if p != main]
            if others:
                parts = [(main.name, main.read_bytes())]
                parts += [(p.relative_to(folder).as_posix(), p.read_bytes()) for p in others]
                seeds[f"seed-{name}"] = bundle(parts)
            else:
                seeds[f"seed-{name}{suffix}"] = main.read_bytes()
        finally:
            shutil.rmtree(folder, ignore_errors=True)
    return seeds


def _obj_seeds() -> dict[str, bytes]:
    import tuckercodec as tc

    seeds = {}
    for name, sequence in _small_sequences().items():
        folder = Path(tempfile.mkdtemp(prefix="tkc-fuzz-seed-"))
        try:
            tc.save_sequence(sequence, folder / "frames")
            first = sorted((folder / "frames").glob("*.obj"))[0]
            seeds[f"seed-{name}.obj"] = first.read_bytes()
        finally:
            shutil.rmtree(folder, ignore_errors=True)
    seeds["seed-hand.obj"] = (
        b"# by hand\nmtllib x.mtl\no thing\nv 0 0 0 1\nv 1 0 0\nv 1 1 0 0.5 0.5 0.5\n"
        b"v 0 1 \\\n 0\nvt 0 0\nvn 0 0 1\ng a\nusemtl m\ns off\nf 1/1/1 2/1/1 3/1/1\n"
        b"f -4//1 -2//1 -1//1\nf 1 2 3 4\nl 1 2\n"
    )
    return seeds


def _gltf_seeds() -> dict[str, bytes]:
    """The .gltf files as written (buffers as data URIs), and each also with its buffer as a
    separate .bin file."""
    import base64
    import json

    seeds = _written(".gltf")
    for name, data in list(seeds.items()):
        if unbundle(data) is not None:
            continue
        document = json.loads(data)
        parts = []
        for index, buffer in enumerate(document.get("buffers", [])):
            uri = buffer.get("uri", "")
            if uri.startswith("data:"):
                parts.append((f"b{index}.bin", base64.b64decode(uri.split(",", 1)[1])))
                buffer["uri"] = f"b{index}.bin"
        if parts:
            text = json.dumps(document).encode()
            seeds[name.replace(".gltf", "-bin")] = bundle([("a.gltf", text), *parts])
    return seeds


def _xdmf_seeds() -> dict[str, bytes]:
    """The writer's XDMF with its .h5, and a hand-made one with its data in the XML."""
    seeds = _written(".xdmf")
    seeds["seed-xml-data.xdmf"] = b"""<?xml version="1.0" ?>
<Xdmf Version="3.0"><Domain>
<Grid Name="series" GridType="Collection" CollectionType="Temporal">
<Grid Name="f0"><Time Value="0"/>
<Topology TopologyType="Triangle" NumberOfElements="2">
<DataItem Dimensions="2 3" NumberType="Int" Format="XML">0 1 2 1 3 2</DataItem></Topology>
<Geometry GeometryType="XYZ">
<DataItem Dimensions="4 3" NumberType="Float" Precision="8" Format="XML">
0 0 0 1 0 0 0 1 0 1 1 0</DataItem></Geometry></Grid>
<Grid Name="f1"><Time Value="0.5"/>
<Topology TopologyType="Triangle" NumberOfElements="2">
<DataItem Dimensions="2 3" NumberType="Int" Format="XML">0 1 2 1 3 2</DataItem></Topology>
<Geometry GeometryType="XYZ">
<DataItem Dimensions="4 3" NumberType="Float" Precision="4" Format="XML">
0 0 1 1 0 1 0 1 1 1 1 1</DataItem></Geometry></Grid>
</Grid></Domain></Xdmf>
"""
    return seeds


def _reader(
    name: str,
    suffix: str,
    door: str,
    seeds: Callable[[], dict[str, bytes]] | None = None,
    *,
    suffix_of: Callable[[bytes], str] | None = None,
    needs: tuple[str, ...] = (),
    isolated: bool = False,
    max_len: int = 8192,
) -> Target:
    pick = suffix_of or _suffix(suffix)
    return Target(
        name=name,
        door=door,
        check=lambda data: read_check(data, pick, isolated),
        seeds=seeds or (lambda: _written(suffix)),
        mutate=lambda data, max_size, seed: mutate_bundle(data, max_size, seed, _atheris_mutate),
        isolated=isolated,
        needs=needs,
        max_len=max_len,
        modules=READER_MODULES,
    )


# ------------------------------------------------------------------------------------------
# the segmented decoder


def segmented_check(data: bytes) -> str:
    """:func:`check_input`, then for a segmented file that decodes: the two frames around its
    last segment boundary decoded alone, and its last frame decoded from a path, each equal to
    the whole decode (§8's tolerance)."""
    import numpy as np

    import tuckercodec as tc

    outcome = check_input(data)
    if outcome != "ok":
        return outcome
    whole = tc.decode(data).vertices
    decoder = tc.Decoder(data)
    tolerance = 1e-9 * float(np.abs(whole).max()) + 1e-12  # spec/FORMAT.md §8
    if decoder.segmented and len(decoder.segments) > 1:
        start = decoder.segments[-1].start
        part = tc.decode(data, frames=range(start - 1, start + 1)).vertices
        if not np.allclose(part, whole[start - 1 : start + 1], rtol=0, atol=tolerance):
            raise InvariantError("frames across a segment boundary differ from the whole decode")
    path = scratch_folder() / "input.tkc"
    path.write_bytes(data)
    try:
        last = tc.Decoder(path).frame(whole.shape[0] - 1)
    except tc.FormatError as error:
        raise InvariantError(f"the bytes decode, the same file from a path: {error!r}") from None
    if not np.allclose(last, whole[-1], rtol=0, atol=tolerance):
        raise InvariantError("the last frame decoded from a path differs")
    return "ok"


def segmented_seeds() -> dict[str, bytes]:
    import numpy as np

    import tuckercodec as tc
    from tuckercodec.internal import sheet_triangles, wave_sheet

    frames = wave_sheet(12, 4)
    triangles = sheet_triangles(4)

    sequence = tc.MeshSequence(frames, triangles)
    seeds = {
        f"seed-{basis}.tkc": tc.encode(sequence, target_kg=1.0, segment_frames=4, basis=basis)
        for basis in ("shared", "own")
    }
    points = tc.MeshSequence(
        frames[:11], np.zeros((0, 3), int), frame_names=[str(n) for n in range(11)]
    )
    seeds["seed-ragged-points.tkc"] = tc.encode(points, target_kg=0.5, segment_frames=3)
    for data in seeds.values():
        assert tc.Decoder(data).segmented
    return seeds


# ------------------------------------------------------------------------------------------
# the FACE section


FACE_VERTEX_LIMIT = 1 << 26  # the decoder's max_vertices: a header with more is refused first


def face_check(data: bytes) -> str:
    """The FACE section's decoder on ``[codec, params, vertex_count, payload]`` after the
    decoder's shape check (default limits), as in a file with flag bit 3 (faces-traverse's
    ``coder`` may be 1); a table must have its shape and valid indices."""
    import msgpack
    import numpy as np

    from tuckercodec import FormatError, Limits
    from tuckercodec.internal import faces, sections

    try:
        item = msgpack.unpackb(data, raw=False, strict_map_key=False)
    except Exception:  # not an input of this door (msgpack is not the door)
        return "not-an-input"
    if not (isinstance(item, list) and len(item) == 4):
        return "not-an-input"
    codec, params, vertex_count, payload = item
    if (
        codec not in ("faces-delta", "faces-traverse")
        or not isinstance(params, dict)
        or type(vertex_count) is not int
        or not 0 <= vertex_count <= FACE_VERTEX_LIMIT
        or not isinstance(payload, bytes)
    ):
        return "not-an-input"
    try:
        sections.check_face_shape(params, Limits())
        table = faces.decode_face_section(
            codec,
            payload,
            params,
            vertex_count,
            "section FACE",
            adaptive_coding=True,
            uniform_ranks=True,
        )
    except FormatError as error:
        return type(error).__name__
    if list(table.shape) != list(params["shape"]):
        raise InvariantError(f"faces of shape {table.shape}, declared {params['shape']}")
    if table.size and (table.min() < -1 or table.max() >= vertex_count):
        raise InvariantError("a face index outside the vertices")
    if table.size and not (table[:, :3] >= 0).all():
        raise InvariantError("a face with fewer than three corners")
    del np
    return "ok"


def face_seeds() -> dict[str, bytes]:
    """Real FACE sections: of the conformance vectors, and both codecs (faces-traverse with
    either coder) on small meshes and a part of the built-in sample."""
    import msgpack

    from tuckercodec.internal import faces, parse_container, sections, traversal

    from .paths import VECTORS

    seeds = {}
    for path in sorted(VECTORS.glob("v1*.tkc")):
        data = path.read_bytes()
        container = parse_container(data)
        for entry in container.sections:
            if entry.id == "FACE":
                payload = data[container.data_start + entry.offset :][: entry.length]
                item = [entry.codec, dict(entry.params), container.header["vertices"], payload]
                seeds[f"seed-{path.stem}"] = msgpack.packb(item, use_bin_type=True)
    for name, sequence in _small_sequences().items():
        table, count = sequence.faces, sequence.vertex_count
        params, payload = faces.encode_faces(table)
        seeds[f"seed-delta-{name}"] = msgpack.packb(
            [sections.FACES_DELTA, params, count, payload], use_bin_type=True
        )
        if len(table):
            params, payload, _ = traversal.encode_traversal(table, count)
            seeds[f"seed-traverse-{name}"] = msgpack.packb(
                [sections.FACES_TRAVERSE, params, count, payload], use_bin_type=True
            )
            params, payload = _coder_1(table, count)
            seeds[f"seed-traverse-adaptive-{name}"] = msgpack.packb(
                [sections.FACES_TRAVERSE, params, count, payload], use_bin_type=True
            )
    return seeds


def _coder_1(table: Any, count: int) -> tuple[dict[str, Any], bytes]:
    """faces-traverse of ``table`` with ``coder`` 1 (format 1.6), whichever is smaller."""
    import numpy as np

    from tuckercodec.internal import traversal, unseen

    walked = traversal._walked(np.asarray(table, dtype=np.int64), len(table), count)
    placed = unseen.vertices_from_gaps(np.asarray(walked.new_residuals, dtype=np.int64))
    ranks = unseen.ranks_of(placed, count).tolist()
    values = [walked.ops[0], walked.degrees, ranks, walked.references]
    return traversal.pack_streams(values, len(table), table.shape[1], 0, 3, 1)


def _mutate_face_payload(rng: random.Random, item: list[Any]) -> None:
    """Decompress one stream of the payload (the one stream of faces-delta), change it, and
    compress it again, the table (or the shape) declaring the new length."""
    import zstandard

    codec, params, _, payload = item
    table = params.get("streams") if codec == "faces-traverse" else None
    if (
        isinstance(table, list)
        and table
        and all(isinstance(e, list) and len(e) == 3 for e in table)
    ):
        index = rng.randrange(len(table))
        start = sum(int(e[2]) for e in table[:index] if isinstance(e[2], int))
        length = table[index][2] if isinstance(table[index][2], int) else 0
    else:
        index, start, length = -1, 0, len(payload)
    part = payload[start : start + length]
    raw = decompressed_start(part)
    what = rng.randrange(4)
    if raw and what <= 1:
        for _ in range(rng.choice([1, 1, 2, 4])):
            raw[rng.randrange(len(raw))] = rng.choice(
                [0, 1, 2, 3, 0x7F, 0x80, 0xFF, rng.randrange(256)]
            )
    elif what == 2:
        raw = raw[: rng.randrange(len(raw) + 1)]
    else:
        raw += bytes(rng.choice([0, 1, 255]) for _ in range(rng.choice([1, 3, 4, 8])))
    new = zstandard.ZstdCompressor(level=1).compress(bytes(raw))
    item[3] = payload[:start] + new + payload[start + length :]
    if index >= 0 and table is not None:
        planes = table[index][1] if isinstance(table[index][1], int) and table[index][1] else 1
        count = len(raw) // planes if rng.random() < 0.7 else table[index][0]
        table[index] = [count, table[index][1], len(new)]


def mutate_face(data: bytes, max_size: int, seed: int) -> bytes:
    """The FACE door's mutator: one params value (anywhere, the stream table included), the
    vertex count, or one stream re-compressed; else libFuzzer's byte mutation."""
    import msgpack

    rng = random.Random(seed)
    try:
        item = msgpack.unpackb(data, raw=False, strict_map_key=False)
        if rng.random() < 0.75 and isinstance(item, list) and len(item) == 4:
            what = rng.random()
            if what < 0.4 and isinstance(item[1], dict):
                paths = [p for p, _ in _containers_in(item[1]) if p]
                if paths:
                    path = rng.choice(paths)
                    current: Any = item[1]
                    for key in path:
                        current = current[key]
                    _set_path(item[1], path, _hostile_value(rng, current))
            elif what < 0.5 and isinstance(item[2], int):
                item[2] = max(0, item[2] + rng.choice([-1, 1, -3, -item[2], item[2]]))
            elif what < 0.55:
                item[0] = rng.choice(["faces-delta", "faces-traverse"])
            elif isinstance(item[1], dict) and isinstance(item[3], bytes):
                _mutate_face_payload(rng, item)
            out: bytes = msgpack.packb(item, use_bin_type=True)
            if len(out) <= max_size:
                return out
    except Exception:  # the mutator must not stop the run
        pass
    return _atheris_mutate(data, max_size)


# ------------------------------------------------------------------------------------------
# zarr chunks


#: (shape, dtype, fill value) of a chunk, chosen by an input's first byte.
CHUNK_KINDS: list[tuple[tuple[int, int, int], str, float | None]] = [
    ((8, 9, 3), "<f8", None),
    ((8, 9, 3), "<f4", 0.0),
    ((4, 16, 3), "<f8", float("nan")),
    ((16, 1, 3), "<f8", None),
    ((3, 9, 3), "<f2", None),
    ((6, 5, 3), "<f4", -1.0),
]


def zarr_check(data: bytes) -> str:
    """The zarr codec's chunk decoder, as zarr format 3 calls it (the chunk's shape and fill
    value known) and as numcodecs does (at most the destination's positions)."""
    import numpy as np

    from tuckercodec import FormatError
    from tuckercodec.internal import decode_chunk

    if not data:
        return "empty"
    shape, dtype, fill = CHUNK_KINDS[data[0] % len(CHUNK_KINDS)]
    chunk = data[1:]
    outcomes = []
    for kwargs in (
        {"shape": shape, "fill_value": fill},
        {"positions": shape[0] * shape[1]},
    ):
        try:
            out = decode_chunk(chunk, dtype, **kwargs)
        except FormatError as error:
            outcomes.append(type(error).__name__)
            continue
        except ValueError as error:  # the codec's own, documented; numpy's would be a crash
            if not _raised_in_tuckercodec(error):
                raise
            outcomes.append("ValueError")
            continue
        if out.dtype != np.dtype(dtype) or not out.flags.c_contiguous:
            raise InvariantError(f"a chunk of {out.dtype}, asked for {dtype}")
        if "shape" in kwargs and out.shape != shape:
            raise InvariantError(f"a chunk of shape {out.shape}, asked for {shape}")
        outcomes.append("ok")
    return "/".join(outcomes)


def _raised_in_tuckercodec(error: BaseException) -> bool:
    import traceback

    frames = traceback.extract_tb(error.__traceback__)
    return bool(frames) and "tuckercodec" in Path(frames[-1].filename).parts


def zarr_seeds() -> dict[str, bytes]:
    import numpy as np

    from tuckercodec.internal import chunk_mode, encode_chunk, wave_sheet

    seeds = {}
    for index, (shape, dtype, fill) in enumerate(CHUNK_KINDS):
        frames, vertices, _ = shape
        positions = wave_sheet(frames, 4)[:, :vertices].astype(dtype)
        if vertices == 1:
            positions = positions * 0 + 1  # single points: stored exactly
        seeds[f"seed-kind{index}"] = bytes([index]) + encode_chunk(
            positions, chunk_mode(target_kg=0.5)
        )
        if fill is not None:  # an edge chunk: fewer frames than the shape, zarr pads it
            seeds[f"seed-kind{index}-edge"] = bytes([index]) + encode_chunk(
                positions[: frames - 1], chunk_mode(ranks=[3, 2])
            )
    del np
    return seeds


def mutate_zarr(data: bytes, max_size: int, seed: int) -> bytes:
    """The .tkc mutator on the chunk, its first byte (the kind) changed now and then."""
    if not data:
        return _atheris_mutate(data, max_size)
    rng = random.Random(seed)
    kind = bytes([rng.randrange(256)]) if rng.random() < 0.05 else data[:1]
    return kind + mutate_container(data[1:], max(1, max_size - 1), seed)


# ------------------------------------------------------------------------------------------
# the list


TARGETS: dict[str, Target] = {
    target.name: target
    for target in [
        Target(
            name="decoder",
            door="decode, info and Decoder.frame(0) on a .tkc file",
            check=check_input,
            seeds=decoder_seeds,
            mutate=mutate_container,
            extra_seeds=("spec/vectors/*.tkc",),
            modules=DECODER_MODULES,
        ),
        Target(
            name="segmented",
            door="the decoder on segmented files: ranges across segments, reads from a path",
            check=segmented_check,
            seeds=segmented_seeds,
            mutate=mutate_container,
            extra_seeds=(
                "spec/vectors/v1.1-*.tkc",
                "spec/vectors/v1.2-*segments.tkc",
                "spec/vectors/v1.3-segments-*.tkc",
                "spec/vectors/v1.4-scene-segments.tkc",
            ),
            modules=DECODER_MODULES,
        ),
        Target(
            name="face",
            door="the FACE section's decoder (faces-delta, faces-traverse) on params + payload",
            check=face_check,
            seeds=face_seeds,
            mutate=mutate_face,
            modules=DECODER_MODULES,
        ),
        Target(
            name="zarr-chunk",
            door="the zarr codec's chunk decoder, shape known (zarr 3) or size only (numcodecs)",
            check=zarr_check,
            seeds=zarr_seeds,
            mutate=mutate_zarr,
            modules=(*DECODER_MODULES, "tuckercodec.zarr_codec"),
        ),
        _reader("obj", ".obj", "one OBJ frame", _obj_seeds),
        _reader("npz", ".npz", "a NumPy .npz archive (zip of .npy members)"),
        _reader("npy", ".npy", "a NumPy .npy array of positions"),
        _reader("pc2", ".pc2", "a PC2 point cache"),
        _reader("mdd", ".mdd", "an MDD point cache (big-endian)"),
        _reader("gltf", ".gltf", "a .gltf (JSON) with data URIs or .bin files", _gltf_seeds),
        _reader("glb", ".glb", "a binary glTF (.glb)"),
        _reader("vtk", ".pvd", "a ParaView .pvd with its .vtp files", max_len=16384),
        _reader(
            "xdmf",
            ".xdmf",
            "an XDMF series with its HDF5 heavy data, or XML data",
            _xdmf_seeds,
            needs=("h5py",),
            max_len=16384,
        ),
        _reader(
            "usd",
            ".usdc",
            "a USD stage (.usda or .usdc) through the isolated child",
            # two seeds: each input costs a process, in the fuzz run and in the test suite
            lambda: {**_written(".usda", ("triangles",)), **_written(".usdc", ("polygons",))},
            suffix_of=_usd_suffix,
            needs=("pxr",),
            isolated=True,
        ),
        _reader(
            "alembic",
            ".abc",
            "an Alembic archive through the isolated child",
            lambda: _written(".abc", ("triangles", "points")),
            needs=("alembic3d",),
            isolated=True,
        ),
    ]
}


# ------------------------------------------------------------------------------------------
# every in-process door in one process (the bounded run of the test suite)


IN_PROCESS = [target for target in TARGETS.values() if not target.isolated]


def _part(data: bytes) -> tuple[Target, bytes]:
    return IN_PROCESS[data[0] % len(IN_PROCESS)], data[1:]


def all_check(data: bytes) -> str:
    """The first byte chooses an in-process door, the rest is its input."""
    if not data:
        return "empty"
    target, rest = _part(data)
    return f"{target.name}: {target.check(rest)}"


def all_mutate(data: bytes, max_size: int, seed: int) -> bytes:
    """The chosen door's mutator on the rest, the first byte kept."""
    if not data:
        return _atheris_mutate(data, max_size)
    target, rest = _part(data)
    return data[:1] + target.mutate(rest, max(1, max_size - 1), seed)


def all_seeds() -> dict[str, bytes]:
    """Every in-process door's committed seeds, each behind the byte that chooses it."""
    from .paths import CORPUS, ROOT, saved_inputs

    seeds = {}
    for index, target in enumerate(IN_PROCESS):
        paths = [p for pattern in target.extra_seeds for p in sorted(ROOT.glob(pattern))]
        for path in paths + saved_inputs(CORPUS / target.name):
            seeds[f"{target.name}-{path.name}"] = bytes([index]) + path.read_bytes()
    return seeds


ALL = Target(
    name="all",
    door="every in-process door in one process, the first byte choosing (CI's bounded run)",
    check=all_check,
    seeds=all_seeds,
    mutate=all_mutate,
    needs=tuple(sorted({module for t in IN_PROCESS for module in t.needs})),
    max_len=16384,
    modules=tuple(dict.fromkeys(module for t in IN_PROCESS for module in t.modules)),
)


def target_named(name: str) -> Target:
    if name == ALL.name:
        return ALL
    try:
        return TARGETS[name]
    except KeyError:
        raise ValueError(f"no fuzz target {name!r}: one of {', '.join(TARGETS)}") from None
