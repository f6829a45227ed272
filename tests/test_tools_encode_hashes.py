"""tools.encode_hashes: the digests of encodes through the command line, and their comparison."""

from __future__ import annotations

import json

from tools import encode_hashes


def test_the_same_encodes_give_the_same_digests_and_a_change_is_named(tmp_path, capsys):
    first, second = tmp_path / "first.json", tmp_path / "second.json"
    modes = ["--modes", "kg1", "seg30kg1"]
    assert encode_hashes.main(["sample", *modes, "--out", str(first)]) == 0
    found = json.loads(first.read_text())
    assert sorted(found) == ["sample/kg1", "sample/seg30kg1"]
    assert all(len(digest) == 64 for digest in found.values()), found
    # one more run both compares and writes: against a copy with kg1's digest changed, it names
    # that one alone, and what it wrote is the first run's digests again
    changed = tmp_path / "changed.json"
    changed.write_text(json.dumps({**found, "sample/kg1": "0" * 64}))
    capsys.readouterr()
    arguments = ["sample", *modes, "--compare", str(changed), "--out", str(second)]
    assert encode_hashes.main(arguments) == 1
    assert "1 of 2 the same; differ: ['sample/kg1']" in capsys.readouterr().out
    assert json.loads(second.read_text()) == found


def test_the_same_digests_compare_equal(tmp_path, capsys):
    """The comparison's other outcome, on an input that fails at once (its digest is the error)."""
    missing, saved = str(tmp_path / "nowhere.npz"), tmp_path / "saved.json"
    assert encode_hashes.main([missing, "--modes", "kg1", "--out", str(saved)]) == 0
    capsys.readouterr()
    assert encode_hashes.main([missing, "--modes", "kg1", "--compare", str(saved)]) == 0
    assert "1 of 1 the same; differ: none" in capsys.readouterr().out


def test_a_failing_encode_is_reported_not_hashed(tmp_path):
    missing = str(tmp_path / "nowhere.npz")
    digest = encode_hashes.encode_digest(missing, ["--kg", "1"])
    assert digest.startswith("exit ") and "nowhere.npz" in digest
