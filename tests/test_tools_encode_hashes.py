"""tools.encode_hashes: the digests of encodes through the command line, and their comparison."""

from __future__ import annotations

import json

from tools import encode_hashes


def test_the_same_encodes_give_the_same_digests_and_a_change_is_named(tmp_path, capsys):
    first = tmp_path / "first.json"
    modes = ["--modes", "kg1", "seg30kg1"]
    assert encode_hashes.main(["sample", *modes, "--out", str(first)]) == 0
    found = json.loads(first.read_text())
    assert sorted(found) == ["sample/kg1", "sample/seg30kg1"]
    assert all(len(digest) == 64 for digest in found.values()), found
    assert encode_hashes.main(["sample", *modes, "--compare", str(first)]) == 0
    assert "2 of 2 the same; differ: none" in capsys.readouterr().out
    found["sample/kg1"] = "0" * 64
    first.write_text(json.dumps(found))
    assert encode_hashes.main(["sample", *modes, "--compare", str(first)]) == 1
    assert "differ: ['sample/kg1']" in capsys.readouterr().out


def test_a_failing_encode_is_reported_not_hashed(tmp_path):
    missing = str(tmp_path / "nowhere.npz")
    digest = encode_hashes.encode_digest(missing, ["--kg", "1"])
    assert digest.startswith("exit ") and "nowhere.npz" in digest
