"""tools.bench entropy on the built-in sample: it reads files of every format version, untimed."""

from __future__ import annotations

from tools import bench
from tools.bench import entropy as bench_entropy
from tuckercodec import encode_with_report, load_sequence
from tuckercodec.internal import parse_container, streams
from tuckercodec.io.samples import sample_path


def test_the_measured_integers_are_those_the_file_stores():
    data = encode_with_report(load_sequence(sample_path()), target_kg=1.0).data
    container = parse_container(data)
    for section_id, (stream, parents, stored) in bench_entropy.section_streams(data).items():
        entry = container.section(section_id)
        assert entry is not None
        if entry.params.get("coder", 0) == 0:  # else the tool packed the integers itself
            assert stored == entry.length
        rows, cols = entry.params["shape"]
        assert stream.shape == (rows, cols) and parents.shape == (rows,)
        # zstd of the same byte planes gives back the stored frame's content
        again, _ = streams.pack_integers(stream.T.copy())
        assert len(again) == stored


def test_the_tool_prints_both_tables(capsys):
    path = str(sample_path())
    assert bench.main(["entropy", path, "--targets", "1"]) == 0
    assert "A3 saves" in capsys.readouterr().out
    assert bench.main(["entropy", path, "--targets", "1", "--rdo"]) == 0
    assert "rdo" in capsys.readouterr().out
