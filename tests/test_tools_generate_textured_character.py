"""tools.generate.textured_character: the stage it authors with pxr is what the end-to-end demo
of attributes needs (uvs, normals, face colours, two material subsets, velocities), reads back
through our USD reader as such, passes USD's validators, and is never written over unasked."""

from __future__ import annotations

import numpy as np
import pytest

from tools.generate import textured_character
from tuckercodec.io import load_sequence

pytest.importorskip("pxr", reason="usd-core (the 'usd' extra) is not installed")
from tests.test_io_usd import usdchecker_errors


@pytest.fixture(scope="module")
def stage_path(tmp_path_factory):
    path = tmp_path_factory.mktemp("character") / "character.usdc"
    assert textured_character.main(["-o", str(path), "--frames", "5"]) == 0
    return path


def test_the_character_reads_back_with_everything_the_demo_needs(stage_path):
    seq = load_sequence(stage_path)
    assert (seq.frame_count, seq.vertex_count, seq.faces.shape) == (5, 3101, (5912, 3))
    st = seq.attribute_named("st")
    assert (st.domain, st.role, st.indices is not None) == ("corner", "uv", True)
    assert st.values.min() >= 0 and st.values.max() <= 1
    normals = seq.attribute_named("normals")
    assert (normals.domain, normals.role) == ("vertex", "normal")
    assert np.allclose(np.linalg.norm(normals.values, axis=1), 1, atol=1e-5)
    color = seq.attribute_named("displayColor")
    assert (color.domain, color.role, color.components) == ("face", "color", 3)
    sets = {face_set.name: face_set for face_set in seq.face_sets}
    assert sorted(sets) == ["blue", "red"]
    assert {face_set.family for face_set in seq.face_sets} == {"materialBind"}
    together = np.concatenate([sets["red"].faces, sets["blue"].faces])
    assert np.array_equal(np.sort(together), np.arange(5912))  # a partition of the faces
    velocities = seq.field_named("velocities")
    assert (velocities.role, velocities.values.shape) == ("velocity", (5, 3101, 3))
    assert np.abs(velocities.values).max() > 0


def test_usds_validators_find_nothing(stage_path):
    assert usdchecker_errors(stage_path) == []


def test_an_existing_output_is_kept_without_force(stage_path, capsys):
    before = stage_path.read_bytes()
    assert textured_character.main(["-o", str(stage_path), "--frames", "2"]) == 1
    assert "exists" in capsys.readouterr().err
    assert stage_path.read_bytes() == before
    assert not list(stage_path.parent.glob(".*.tmp*"))
