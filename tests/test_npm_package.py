"""The npm package ``tuckercodec`` (its root: tuckercodec/web/package.json) as a web developer gets
it: ``npm pack`` makes the tarball, which installs offline into an empty project, where node, by
the package's own names (``import ... from "tuckercodec"`` and ``"tuckercodec/three"``):

- decodes every conformance vector of spec/vectors as test_js_conformance.py requires of the
  decoder in the source tree (the same observation script, importing the installed package),
  in a project without three (three is an optional peer: the decoder needs none);
- with three installed too (packed from the copy the viewer vendors, tuckercodec/web/vendor/three,
  so nothing comes from the network), plays files with ``TKCLoader``: ``setFrame(t)`` puts the
  Python decoder's frame t, rounded to float32, into the mesh's position attribute (the same bits
  for a file with corrections), its index is the file's faces fanned into triangles, its normals
  and bounds follow the frame, ``update(seconds)`` follows the clock, and ``load`` over HTTP
  honours the loader's path, request header and LoadingManager, and hands a damaged file's rule
  to onError;
- and tsc types a user's TypeScript (tests/js/package_usage.ts) and the READMEs' examples of
  TKCLoader with the declarations the package's ``exports`` name, which are those tsc emits from
  the JSDoc now.

The tests that run node or npm skip, naming what is missing, where node (18 or newer) or npm is
absent; the ones that run tsc skip where tools/js has not been installed (``npm ci`` there).
"""

from __future__ import annotations

import base64
import json
import os
import re
import shutil
import subprocess
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import tuckercodec
from tests.support.js_decoder import (
    EXPECTED,
    INVALID,
    VALID,
    VECTORS,
    check_every_vector_observed,
    check_invalid_observation,
    check_valid_observation,
    node,
)
from tuckercodec import Decoder

ROOT = Path(__file__).resolve().parents[1]
WEB = ROOT / "tuckercodec" / "web"
MANIFEST = json.loads((WEB / "package.json").read_text())
JS_TESTS = ROOT / "tests" / "js"
TOOLS_JS = ROOT / "tools" / "js"
TSC = TOOLS_JS / "node_modules" / ".bin" / "tsc"
VENDORED_THREE = WEB / "vendor" / "three"
#: the loader's files: a file with corrections (the JavaScript frame is the Python one, bit for
#: bit) and no frame rate, and a segmented one of polygons at 30 fps (within §8's tolerance)
LOADER_FILES = ("v1.3-bound-grid", "v1.2-traverse-polygons-segments", "v1.4-scene-times")
#: The files of LOADER_FILES whose frames are evenly spaced (no time codes of format 1.4).
EVEN_FILES = LOADER_FILES[:2]
TIMEOUT = 60.0


def three_version() -> str:
    """The version of three.js the viewer vendors (and is tested with)."""
    match = re.search(
        r"npm package three (\d+\.\d+\.\d+)", (VENDORED_THREE / "VENDORED.md").read_text()
    )
    assert match is not None, "VENDORED.md no longer names three's version"
    return match.group(1)


# ------------------------------------------------------------------------------------------
# the manifest, read


def test_the_npm_version_is_the_python_version():
    assert MANIFEST["version"] == tuckercodec.__version__, (
        "tuckercodec/web/package.json's version must be tuckercodec/_version.py's: change both"
    )


def test_the_manifest_names_files_the_package_has():
    assert MANIFEST["name"] == "tuckercodec"
    assert MANIFEST["type"] == "module" and MANIFEST["sideEffects"] is False
    assert MANIFEST["license"] == "MIT" and (WEB / "LICENSE").is_file()
    assert set(MANIFEST["exports"]) == {".", "./three", "./package.json"}
    for entry in (MANIFEST["exports"]["."], MANIFEST["exports"]["./three"]):
        assert list(entry) == ["types", "default"]  # "types" first, as TypeScript reads them
        assert all((WEB / path).is_file() for path in entry.values()), entry
    assert (WEB / MANIFEST["main"]).is_file() and (WEB / MANIFEST["types"]).is_file()


def test_three_is_an_optional_peer_of_the_version_the_viewer_is_tested_with():
    version = three_version()
    major, minor, _ = version.split(".")
    assert MANIFEST["peerDependencies"]["three"] == f"^{major}.{minor}.0"
    assert MANIFEST["peerDependencies"]["@types/three"] == f"^{major}.{minor}.0"
    assert all(meta["optional"] for meta in MANIFEST["peerDependenciesMeta"].values())
    tests_three = json.loads((JS_TESTS / "package.json").read_text())["dependencies"]["three"]
    assert tests_three == version  # the glTF tests' three, the same release


# ------------------------------------------------------------------------------------------
# the declarations


def tsc() -> Path:
    if not TSC.exists():
        pytest.skip(f"tsc not installed in tools/js (run `npm ci` there): {TSC} is missing")
    node()  # tsc is a node program
    return TSC


def run(command: list[str | Path], cwd: Path, what: str) -> str:
    done = subprocess.run(
        [str(part) for part in command],
        cwd=cwd,
        capture_output=True,
        text=True,
        timeout=TIMEOUT,
        check=False,
        env={**os.environ, "npm_config_update_notifier": "false"},
    )
    assert done.returncode == 0, f"{what} failed:\n{done.stdout[-3000:]}\n{done.stderr[-3000:]}"
    return done.stdout


def test_the_declarations_are_those_tsc_emits_from_the_jsdoc(tmp_path):
    """tuckercodec/web/types/ is committed: emitted again, it must not differ (after a change to
    the JSDoc, `npm run declarations` in tools/js writes it)."""
    out = tmp_path / "types"
    config = TOOLS_JS / "tsconfig.declarations.json"
    run([tsc(), "-p", config, "--outDir", out], TOOLS_JS, "tsc --declaration")
    emitted = {p.relative_to(out): p.read_text() for p in out.rglob("*.d.ts")}
    committed = {
        p.relative_to(WEB / "types"): p.read_text()
        for p in (WEB / "types").rglob("*")
        if p.is_file()
    }
    assert sorted(emitted) == sorted(committed)
    stale = [str(name) for name in emitted if emitted[name] != committed[name]]
    assert not stale, f"declarations out of date (run `npm run declarations` in tools/js): {stale}"


# ------------------------------------------------------------------------------------------
# packed and installed


def npm() -> str:
    node()
    path = shutil.which("npm")
    if path is None:
        pytest.skip("npm not found on PATH: the npm package's tests pack and install it")
    return path


def pack(folder: Path, into: Path) -> tuple[Path, list[str]]:
    """``npm pack`` of ``folder`` into ``into``: the tarball and the paths it holds."""
    listing = json.loads(
        run([npm(), "pack", "--json", "--pack-destination", into], folder, "npm pack")
    )
    return into / listing[0]["filename"], sorted(f["path"] for f in listing[0]["files"])


def install(project: Path, *packages: Path) -> Path:
    """An empty project with the packages (tarballs, folders) installed, offline, with an npm
    cache of its own."""
    project.mkdir()
    (project / "package.json").write_text('{"name": "app", "private": true, "type": "module"}')
    command = [npm(), "install", "--offline", "--no-audit", "--no-fund", "--loglevel=error"]
    run(
        [*command, "--cache", project.parent / f"{project.name}-cache", *packages],
        project,
        "npm install",
    )
    return project


@pytest.fixture(scope="module")
def packed(tmp_path_factory) -> dict[str, Any]:
    """The package's tarball and its listing, and the vendored three as a package folder."""
    folder = tmp_path_factory.mktemp("packed")
    tarball, listing = pack(WEB, folder)
    three = folder / "three"
    three.mkdir()
    for name in ("three.module.js", "three.core.js", "LICENSE"):
        shutil.copy(VENDORED_THREE / name, three)
    manifest = {
        "name": "three",
        "version": three_version(),
        "type": "module",
        "license": "MIT",
        "exports": {".": "./three.module.js"},
    }
    (three / "package.json").write_text(json.dumps(manifest))
    return {"tarball": tarball, "files": listing, "three": three, "folder": folder}


def test_the_tarball_holds_the_decoder_loader_types_and_licences_only(packed):
    files = packed["files"]
    for name in ("package.json", "README.md", "LICENSE", "vendor/fzstd/LICENSE"):
        assert name in files
    for name in ("tkc/decoder.js", "three/TKCLoader.js", "vendor/fzstd/fzstd.mjs"):
        assert name in files
    assert "types/tkc/decoder.d.ts" in files and "types/three/TKCLoader.d.ts" in files
    tkc = {p.name for p in (WEB / "tkc").glob("*.js")}
    assert tkc == {Path(f).name for f in files if f.startswith("tkc/") and f.endswith(".js")}
    strays = [f for f in files if f.endswith(".py") or f.startswith(("viewer/", "vendor/three/"))]
    assert not strays, f"the Python side or the viewer's files are packed: {strays}"


@pytest.fixture(scope="module")
def decoder_project(packed) -> Path:
    """A project with the package alone (no three)."""
    return install(packed["folder"] / "decoder-app", packed["tarball"])


@pytest.fixture(scope="module")
def three_project(packed) -> Path:
    """A project with the package and three."""
    return install(packed["folder"] / "three-app", packed["tarball"], packed["three"])


def copy_importing_the_package(script: str, project: Path) -> None:
    """tests/js/``script`` into ``project``, its import of the decoder in the source tree made an
    import of the installed package."""
    text = (JS_TESTS / script).read_text()
    source = "'../../tuckercodec/web/tkc/decoder.js'"
    if source in text:
        assert text.count(source) == 1
        text = text.replace(source, "'tuckercodec'")
    (project / script).write_text(text)


def test_the_installed_package_decodes_every_vector_without_three(decoder_project):
    assert not (decoder_project / "node_modules" / "three").exists()
    for script in ("conformance.mjs", "conformance_observe.mjs"):
        copy_importing_the_package(script, decoder_project)
    observed = json.loads(run([node(), "conformance.mjs", VECTORS], decoder_project, "node"))
    check_every_vector_observed(observed)
    for name in VALID:
        check_valid_observation(observed, name)
    for name in INVALID:
        check_invalid_observation(observed, name)


# ------------------------------------------------------------------------------------------
# TKCLoader, in node with three


@pytest.fixture(scope="module")
def loader_runs(three_project) -> dict[str, dict[str, Any]]:
    """What tests/js/package_loader.mjs reports for each of LOADER_FILES, from the project."""
    copy_importing_the_package("package_loader.mjs", three_project)
    runs = {}
    for name in LOADER_FILES:
        path = VECTORS / f"{name}.tkc"
        damaged = three_project / f"{name}-damaged.tkc"
        damaged.write_bytes(path.read_bytes()[: path.stat().st_size // 2])
        frames = Decoder(path).info.frames
        request = {
            "file": str(path),
            "damaged": str(damaged),
            "frames": [0, frames - 1, frames // 2, 3],
        }
        (three_project / "request.json").write_text(json.dumps(request))
        out = run([node(), "package_loader.mjs", "request.json"], three_project, "node")
        runs[name] = {**json.loads(out), "request": request}
    return runs


def array(text: str, dtype: type) -> np.ndarray:
    return np.frombuffer(base64.b64decode(text), dtype=np.dtype(dtype).newbyteorder("<"))


def fan(faces: np.ndarray) -> np.ndarray:
    """The faces (-1 padded rows) as triangles (c0, ci, ci+1), as the viewer drew them."""
    triangles = []
    for row in faces:
        corners = row[row >= 0]
        triangles += [(corners[0], corners[i], corners[i + 1]) for i in range(1, len(corners) - 1)]
    return np.array(triangles, dtype=np.uint32).ravel()


def area_normals(positions: np.ndarray, index: np.ndarray) -> np.ndarray:
    triangles = positions.astype(np.float64)[index.reshape(-1, 3)]
    cross = np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0])
    normals = np.zeros_like(positions, dtype=np.float64)
    for corner in range(3):
        np.add.at(normals, index.reshape(-1, 3)[:, corner], cross)
    return normals / np.linalg.norm(normals, axis=1, keepdims=True)


@pytest.mark.parametrize("name", LOADER_FILES)
def test_set_frame_puts_the_python_decoders_frame_in_the_position_attribute(loader_runs, name):
    parsed = loader_runs[name]["parse"]
    decoder = Decoder(VECTORS / f"{name}.tkc")
    assert parsed["isMesh"] and parsed["isBufferGeometry"]
    assert parsed["frameCount"] == decoder.info.frames
    assert parsed["vertices"] == decoder.info.vertices
    assert parsed["frameRate"] == (decoder.info.frame_rate or 24)
    index = array(parsed["index"], np.uint32)
    assert parsed["indexType"] == "Uint32Array" and np.array_equal(index, fan(decoder.faces))
    exact = decoder.corrections is not None
    relative = EXPECTED[f"{name}.json"]["tolerance"]["relative_to_max_abs"]
    assert exact == (relative == 0)
    for t in loader_runs[name]["request"]["frames"]:
        shown = parsed["frames"][str(t)]
        assert shown["frame"] == t
        drawn = array(shown["positions"], np.float32).reshape(-1, 3)
        python = decoder.frame(t).astype(np.float32)
        if exact:
            assert drawn.tobytes() == python.tobytes(), f"frame {t}"
        else:  # §8's tolerance, then float32's rounding of either side
            tolerance = relative * np.abs(decoder.frame(t)).max() + np.spacing(np.abs(python))
            assert (np.abs(drawn - python) <= tolerance).all(), f"frame {t}"
        normals = array(shown["normals"], np.float32).reshape(-1, 3)
        assert np.allclose(normals, area_normals(drawn, index), atol=1e-5), f"frame {t}"
        box = np.array(shown["box"])
        assert np.array_equal(box, np.concatenate([drawn.min(axis=0), drawn.max(axis=0)]))
        centre, radius = np.array(shown["sphere"][:3]), shown["sphere"][3]
        assert np.allclose(centre, (box[:3] + box[3:]) / 2)
        assert np.isclose(radius, np.linalg.norm(drawn - centre, axis=1).max(), rtol=1e-12)
    # one decode per setFrame, none before (frame 0 was decoded when parsed)
    assert parsed["decodedBySetFrame"] == len(loader_runs[name]["request"]["frames"])
    last = parsed["frameCount"] - 1
    assert parsed["setFrameErrors"] == [
        f"RangeError: frame -1 does not exist: the file has frames 0..{last}",
        f"RangeError: frame {last + 1} does not exist: the file has frames 0..{last}",
        f"RangeError: frame 0.5 does not exist: the file has frames 0..{last}",
    ]


@pytest.mark.parametrize("name", EVEN_FILES)
def test_update_follows_the_clock_at_the_frame_rate_and_loops(loader_runs, name):
    played = loader_runs[name]["update"]
    frames = loader_runs[name]["parse"]["frameCount"]
    rate = loader_runs[name]["parse"]["frameRate"]
    assert played["duration"] == pytest.approx(frames / rate)
    # a quarter of a frame per call: frame n from the 4n-th call on, each decoded once
    assert played["shown"][:10] == [0, 0, 0, 1, 1, 1, 1, 2, 2, 2]
    assert played["decodedByQuarters"] == 2
    # a whole pass comes back to the same frame; three frames back from 2.5 wraps to the last
    assert played["shown"][10:] == [2, frames - 1]
    assert played["afterSetFrame"] == 1  # half a frame on from the start of frame 1
    assert played["clamped"] == frames - 1  # loop = false stops at the last frame
    # a step back from 0 lands in the last frame, even one smaller than the pass's rounding
    assert played["tinyBack"] == [frames - 1, True]


@pytest.mark.parametrize("name", LOADER_FILES)
def test_update_keeps_the_time_finite_at_the_smallest_frame_rate(loader_runs, name):
    """At 5e-324 fps (a valid rate) a step back once made the time Infinity, then NaN: the
    frame times and a pass are infinite, so playback clamps instead of looping."""
    played = loader_runs[name]["update"]
    # frame 1 starts at 1 / 5e-324 s, beyond every double: frame 0 shows whatever the steps
    assert played["tinyRate"] == [[0, True]] * 7


def test_update_plays_a_file_with_time_codes_at_their_times(loader_runs):
    # v1.4-scene-times: frames at 1001..1010, then 1012..1025 (one sample missing), 24 fps
    played = loader_runs["v1.4-scene-times"]["update"]
    codes = np.array(EXPECTED["v1.4-scene-times.json"]["header"]["time_codes"])
    assert played["frameTimes"] == pytest.approx(((codes - codes[0]) / 24.0).tolist())
    assert played["duration"] == pytest.approx((codes[-1] - codes[0] + 1) / 24.0)
    # just before each frame's start the one before it shows, at its start the frame itself:
    # frame 10 starts two frame periods after frame 9
    assert played["aroundStarts"] == [[f - 1, f] for f in range(1, len(codes))]


def test_load_fetches_through_the_loaders_path_header_and_manager_and_aborts(loader_runs):
    name = LOADER_FILES[0]
    loaded = loader_runs[name]["load"]
    parsed = loader_runs[name]["parse"]
    assert loaded["frame"] == 0 and loaded["sameAsLoad"]
    assert loaded["frame0"] == parsed["frames"]["0"]["positions"]
    # the manager counts the file until the animation is handed over, its FileLoader's fetch too
    assert loaded["eventsOfLoad"] == [
        "onStart anim.tkc",
        "animation",
        "onProgress anim.tkc",
        "onProgress /models/anim.tkc",
        "onLoad",
    ]
    assert loaded["requests"] == [
        {"url": f"/models/{name}", "header": "sent"}
        for name in ("anim.tkc", "anim.tkc", "missing.tkc", "damaged.tkc", "slow.tkc")
    ]
    missing = loaded["missing"]
    assert not missing["tkcError"] and "404" in missing["message"]
    assert (
        "error" in loaded["eventsOfMissing"] and "onError missing.tkc" in loaded["eventsOfMissing"]
    )
    assert loaded["eventsOfMissing"][-1] == "onLoad"
    damaged = loaded["damaged"]
    assert damaged["tkcError"] and damaged["rule"] == "R10-file-truncated"
    assert damaged["message"].endswith("[R10-file-truncated]")
    assert "onError damaged.tkc" in loaded["eventsOfDamaged"]
    # abort() stops a fetch under way: onError, and the manager is idle again
    aborted = loaded["aborted"]
    assert aborted["name"] == "AbortError" and not aborted["tkcError"]
    assert "onError slow.tkc" in loaded["eventsOfAborted"]
    assert loaded["eventsOfAborted"][-1] == "onLoad"


#: what the READMEs' three.js examples may use without defining it, and its type
EXAMPLE_CONTEXT = {
    "scene": "Scene",
    "camera": "Camera",
    "renderer": "WebGLRenderer",
    "clock": "Clock",
}


def readme_examples() -> dict[str, str]:
    """The ```js examples of TKCLoader in README.md (For web developers) and the package's README,
    as TypeScript modules: their imports, then a declaration of each name of EXAMPLE_CONTEXT
    they do not define, then the rest."""
    texts = {
        "readme_example.ts": (ROOT / "README.md").read_text().split("### For web developers")[1],
        "package_readme_example.ts": (WEB / "README.md").read_text(),
    }
    examples = {}
    for name, text in texts.items():
        code = re.search(r"```js\n(.*?)```", text, re.S)
        assert code is not None and "TKCLoader" in code.group(1), f"no TKCLoader example for {name}"
        lines = code.group(1).splitlines()
        imports = [line for line in lines if line.startswith("import ")]
        rest = [line for line in lines if not line.startswith("import ")]
        context = [
            f"declare const {variable}: import('three').{kind};"
            for variable, kind in EXAMPLE_CONTEXT.items()
            if not re.search(rf"\b(const|let|var)\s+{variable}\b", code.group(1))
        ]
        examples[name] = "\n".join([*imports, *context, *rest, ""])
    return examples


def test_the_declarations_type_a_users_typescript(three_project):
    """tsc, strict, over tests/js/package_usage.ts and the READMEs' examples in the project: the
    package's types come from its exports' "types" conditions, three's from @types/three
    (tools/js's copy)."""
    compiler = tsc()
    types = three_project / "node_modules" / "@types"
    types.mkdir(exist_ok=True)
    if not (types / "three").exists():
        (types / "three").symlink_to(TOOLS_JS / "node_modules" / "@types" / "three")
    shutil.copy(JS_TESTS / "package_usage.ts", three_project)
    examples = readme_examples()
    for name, code in examples.items():
        (three_project / name).write_text(code)
    config = {
        "compilerOptions": {
            "strict": True,
            "noEmit": True,
            "target": "es2022",
            "module": "nodenext",
            "moduleResolution": "nodenext",
            "lib": ["es2023", "dom"],
            "types": [],
            # the declarations themselves are checked where they are made (tools/js); checking
            # all of @types/three again here would take ten seconds
            "skipLibCheck": True,
        },
        "files": ["package_usage.ts", *examples],
    }
    (three_project / "tsconfig.json").write_text(json.dumps(config))
    run([compiler, "-p", "tsconfig.json"], three_project, "tsc over package_usage.ts")
