"""``tuckercodec view``: the viewer's folder, the server on 127.0.0.1, the exported folder, the
checks before serving and Ctrl-C. The page itself runs in headless Chromium in the browser
tests; here node runs only its arithmetic (measure.js)."""

from __future__ import annotations

import base64
import hashlib
import html
import http.client
import json
import os
import re
import shutil
import signal
import socket
import subprocess
import sys
import time
import tomllib
from fnmatch import fnmatch
from pathlib import Path

import numpy as np
import pytest

from tests.support.sequences import grid_faces, wave_sequence
from tuckercodec import MeshSequence, decode, encode
from tuckercodec.cli import main
from tuckercodec.measures.distortion import kg_error
from tuckercodec.system.atomic import OUTPUT_MARKER
from tuckercodec.web import server as server_module
from tuckercodec.web.server import ViewerServer
from tuckercodec.web.site import build_site, page_files, web_root

ROOT = Path(__file__).resolve().parents[1]
TYPES = {
    ".html": "text/html; charset=utf-8",
    ".js": "text/javascript; charset=utf-8",
    ".mjs": "text/javascript; charset=utf-8",
    ".css": "text/css; charset=utf-8",
    ".json": "application/json",
    ".bin": "application/octet-stream",
    ".tkc": "application/octet-stream",
    ".md": "text/markdown; charset=utf-8",
    "": "text/plain; charset=utf-8",
}


@pytest.fixture(scope="module")
def wave() -> MeshSequence:
    return MeshSequence(wave_sequence(12, 6), grid_faces(6))


@pytest.fixture(scope="module")
def files(tmp_path_factory, wave) -> dict[str, Path]:
    """A compressed file of a small wave, and its original as .npz (and one frame short)."""
    folder = tmp_path_factory.mktemp("view")
    tkc = folder / "wave one.tkc"  # a space: the folder's name for it must be URL-safe
    tkc.write_bytes(encode(wave, target_kg=0.5))
    original = folder / "wave.npz"
    np.savez(original, V=wave.vertices, F=wave.faces)
    short = folder / "short.npz"
    np.savez(short, V=wave.vertices[:-1], F=wave.faces)
    return {"tkc": tkc, "original": original, "short": short}


def _get(
    server: ViewerServer,
    path: str,
    method: str = "GET",
    host: str | None = None,
    cookie: str | None = "token",
) -> tuple[int, dict[str, str], bytes]:
    """A request as sent exactly; by default with the run's token in its cookie, as a page's
    requests carry it (``cookie``: the Cookie header, ``"token"`` for that one, None for none)."""
    connection = http.client.HTTPConnection("127.0.0.1", server.port, timeout=10)
    try:
        # the path is sent exactly as given: no client-side clean-up of "..", as a hostile
        # client would not do any
        connection.putrequest(method, path, skip_host=True, skip_accept_encoding=True)
        connection.putheader("Host", host or f"127.0.0.1:{server.port}")
        if cookie is not None:
            value = f"{server.cookie}={server.token}" if cookie == "token" else cookie
            connection.putheader("Cookie", value)
        connection.endheaders()
        response = connection.getresponse()
        return response.status, dict(response.getheaders()), response.read()
    finally:
        connection.close()


@pytest.fixture
def served(tmp_path, files, wave):
    """The viewer's folder for the wave with its reference, served on a free port."""
    with np.load(files["original"]) as loaded:
        positions = loaded["V"]

    class Frames:
        frame_count, vertex_count = positions.shape[:2]

        def read(self, start: int, stop: int) -> np.ndarray:
            return positions[start:stop]

    site = build_site(
        tmp_path, files["tkc"].read_bytes(), "wave_one.tkc", reference=Frames(), reference_name="w"
    )
    with ViewerServer(tmp_path, site.files, 0) as server:
        yield server, site, tmp_path


def test_the_server_listens_on_127_0_0_1_only_and_serves_each_file_with_its_type(served):
    server, site, folder = served
    assert server.server_address[0] == "127.0.0.1"
    assert server.socket.getsockname()[0] == "127.0.0.1"
    assert {Path(name).suffix for name in site.files} >= {".html", ".js", ".css", ".json", ".tkc"}
    for name in site.files:
        status, headers, body = _get(server, "/" + name)
        assert status == 200, name
        assert headers["Content-Type"] == TYPES[Path(name).suffix], name
        assert headers["Cache-Control"] == "no-store"
        assert headers["X-Content-Type-Options"] == "nosniff"
        assert body == (folder / name).read_bytes(), name
    status, headers, body = _get(server, "/")
    assert (status, body) == (200, (folder / "index.html").read_bytes())
    status, headers, body = _get(server, "/" + site.files[0], method="HEAD")
    assert (status, body) == (200, b"")
    assert int(headers["Content-Length"]) == (folder / site.files[0]).stat().st_size


@pytest.mark.parametrize(
    "path",
    [
        "/nothing.html",
        "/viewer",  # folders: no listing
        "/viewer/",
        "/data/",
        "/../wave.npz",  # out of the folder
        "/data/../../wave.npz",
        "/viewer/../data/wave_one.tkc",  # a file of the list, but not by its own name
        "/viewer/%2e%2e/data/wave_one.tkc",
        "/%2e%2e/%2e%2e/etc/passwd",
        "//etc/passwd",
        "/data/wave_one.tkc/",
        "/DATA/WAVE_ONE.TKC",
    ],
)
def test_anything_but_the_listed_files_is_404(served, path):
    server, _, _ = served
    status, headers, _ = _get(server, path)
    assert status == 404
    assert headers["Cache-Control"] == "no-store"


def test_a_request_for_another_host_name_is_refused(served):
    """A page elsewhere reaching the server through a name that resolves to 127.0.0.1."""
    server, _, _ = served
    assert _get(server, "/index.html", host=f"localhost:{server.port}")[0] == 200
    assert _get(server, "/index.html", host=f"evil.example:{server.port}")[0] == 403
    assert _get(server, "/index.html", host="127.0.0.1")[0] == 403


def test_every_request_needs_the_runs_token(served):
    """Without a token any local user could read the served files. The token comes in
    the printed URL's query; that response sets it as a cookie for the page's other requests."""
    server, site, folder = served
    assert len(server.token) >= 32
    other = ViewerServer(folder, site.files, 0)
    other.server_close()
    assert other.token != server.token  # one per run
    for path in ("/", "/index.html", "/data/wave_one.tkc", "/nope"):
        assert _get(server, path, cookie=None)[0] == 403, path
        assert _get(server, path, cookie=f"{server.cookie}=wrong")[0] == 403, path
        assert _get(server, path, cookie=f"tuckercodec-view-1={server.token}")[0] == 403, path
        assert _get(server, path + "?token=wrong", cookie=None)[0] == 403, path
    address = server.address(site.entry)
    assert address.startswith(server.url + site.entry + "&token=")
    status, headers, body = _get(server, address.removeprefix(server.url[:-1]), cookie=None)
    assert status == 200 and body == (folder / "viewer/index.html").read_bytes()
    cookie = headers["Set-Cookie"]
    assert cookie == f"{server.cookie}={server.token}; Path=/; HttpOnly; SameSite=Strict"
    status, headers, body = _get(server, "/data/wave_one.tkc", cookie=cookie.split(";")[0])
    assert status == 200 and body == (folder / "data/wave_one.tkc").read_bytes()
    assert "Set-Cookie" not in headers  # only where the query carried it


def test_every_response_carries_the_security_headers(served):
    """The page's policy as an HTTP header too, with what a meta tag cannot say: no framing."""
    server, _, _ = served
    page = (web_root() / "viewer/index.html").read_text(encoding="utf-8")
    meta = re.search(r'http-equiv="Content-Security-Policy" content="([^"]+)"', page)
    assert meta is not None
    for path in ("/", "/viewer/index.html", "/viewer/viewer.js", "/data/wave_one.tkc", "/nope"):
        status, headers, _ = _get(server, path)
        assert status == (404 if path == "/nope" else 200), path
        assert headers["Content-Security-Policy"] == f"{meta.group(1)}; frame-ancestors 'none'"
        assert headers["X-Frame-Options"] == "DENY"
        assert headers["Referrer-Policy"] == "no-referrer"
        assert headers["X-Content-Type-Options"] == "nosniff"


def _half_sent(port: int, count: int) -> list[socket.socket]:
    """``count`` connections that each send the start of a request and then nothing more."""
    held = []
    for _ in range(count):
        held.append(socket.create_connection(("127.0.0.1", port), timeout=10))
        held[-1].sendall(f"GET /index.html HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\n".encode())
    return held


def _closed_within(connection: socket.socket, seconds: float) -> bool:
    """Whether the server closes ``connection`` (with no response) within ``seconds``."""
    connection.settimeout(seconds)
    try:
        return connection.recv(1024) == b""
    except ConnectionResetError:
        return True
    except TimeoutError:
        return False


def test_half_sent_requests_are_closed_at_the_timeout_and_others_still_served(served):
    """Half-sent requests once held a thread each, forever."""
    _, site, folder = served
    assert 1 <= server_module.CONNECTION_TIMEOUT <= 10  # a few seconds by default
    with ViewerServer(folder, site.files, 0, connection_timeout=1.0) as server:
        held = _half_sent(server.port, 50)
        try:
            assert _get(server, "/index.html")[0] == 200  # while the 50 wait
            # generous: only that they are closed, not how fast a slow machine gets to it
            assert all(_closed_within(connection, 30) for connection in held)
        finally:
            for connection in held:
                connection.close()
        assert _get(server, "/index.html")[0] == 200


def test_a_request_that_trickles_in_is_closed_at_its_deadline(served):
    """A client that sends a byte of its request line every 4 s is never idle for the 5 s of
    the timeout, and held its connection for as long as it liked; the request line and headers
    must now arrive within REQUEST_DEADLINE, all of them."""
    _, site, folder = served
    assert 5 <= server_module.REQUEST_DEADLINE <= 30  # a slow link's request, not a trickle
    # the test's own scale: a byte every 0.1 s, never idle for the 2 s of the timeout
    with ViewerServer(
        folder, site.files, 0, connection_timeout=2.0, request_deadline=0.5
    ) as server:
        trickle = socket.create_connection(("127.0.0.1", server.port), timeout=10)
        with trickle:
            line = f"GET /index.html?token={server.token} HTTP/1.1\r\nX-Pad: " + "a" * 1000
            sent = 0
            try:
                for byte in line.encode():
                    trickle.sendall(bytes([byte]))
                    sent += 1
                    if _closed_within(trickle, 0.1):
                        break
            except (BrokenPipeError, ConnectionResetError):
                pass  # closed while sending
            # generous: 100 s of bytes for a deadline of 0.5 s, whatever the machine's speed
            assert sent < len(line), "the trickling request was never closed"
        assert _get(server, "/index.html")[0] == 200  # and others are served as before


def test_the_longest_waiting_connection_makes_room_for_a_new_one(served):
    """Connections that have sent no whole request are capped by closing the oldest, so a new
    one (a browser's, which sends its headers at once) is always heard."""
    _, site, folder = served
    with ViewerServer(folder, site.files, 0, connection_timeout=60, max_waiting=4) as server:
        held = _half_sent(server.port, 4)
        try:
            assert not any(_closed_within(connection, 0.2) for connection in held)
            extra = _half_sent(server.port, 1)[0]
            with extra:
                assert _closed_within(held[0], 30)  # the oldest, not at the 60 s timeout
                assert not any(_closed_within(connection, 0.2) for connection in held[1:])
                assert not _closed_within(extra, 0.2)
                assert _get(server, "/index.html")[0] == 200  # closes the next oldest
        finally:
            for connection in held:
                connection.close()


def test_trickling_connections_without_the_token_cannot_starve_the_page(served):
    """80 connections sending part of a request, without the token, once filled the server's
    64 places until their timeout: 27 of 34 of the page's requests were refused. Waiting
    connections now hold no place, and the oldest is closed for a new one."""
    _, site, folder = served
    with ViewerServer(folder, site.files, 0, connection_timeout=60) as server:
        held = _half_sent(server.port, 80)
        try:
            statuses: list[int | str] = []
            for _ in range(34):
                try:
                    statuses.append(_get(server, "/index.html")[0])
                except (ConnectionError, http.client.HTTPException) as error:
                    statuses.append(type(error).__name__)
            assert statuses == [200] * 34
        finally:
            for connection in held:
                connection.close()


def test_admitted_connections_over_the_cap_get_503_and_refused_ones_are_closed(served):
    """Connections whose request carried the token are capped (503 beyond); a connection whose
    request was refused (403) is closed after its answer, holding nothing."""
    _, site, folder = served
    with ViewerServer(folder, site.files, 0, connection_timeout=60, max_connections=2) as server:
        assert server.admit() and server.admit()  # two places taken, as by two answers
        assert _get(server, "/index.html")[0] == 503
        server.leave()
        assert _get(server, "/index.html")[0] == 200
        server.leave()
        refused = _half_sent(server.port, 1)[0]
        with refused:
            refused.sendall(b"\r\n")  # the request, whole, without the token: 403, then closed
            refused.settimeout(30)
            answer = b""
            while chunk := refused.recv(65536):
                answer += chunk
            assert answer.startswith((b"HTTP/1.0 403", b"HTTP/1.1 403"))


@pytest.mark.parametrize(
    "others",
    [
        'a="b; c=d',  # an unterminated quote: SimpleCookie gave up on the whole header
        "weird[name]=1",
        "noequals",
        'x="\\q"; y=1',
    ],
)
def test_a_cookie_of_another_app_does_not_hide_the_viewers(served, others):
    """Another localhost app's cookie that http.cookies cannot parse hid the viewer's, so every
    request of the page got 403."""
    server, _, _ = served
    for cookie in (
        f"{others}; {server.cookie}={server.token}",
        f"{server.cookie}={server.token}; {others}",
        f'{others};{server.cookie}="{server.token}"',
    ):
        assert _get(server, "/index.html", cookie=cookie)[0] == 200, cookie
    assert _get(server, "/index.html", cookie=f"{others}; {server.cookie}=wrong")[0] == 403
    assert _get(server, "/index.html", cookie=f"x{server.cookie}={server.token}")[0] == 403
    assert _get(server, "/index.html", cookie=f"{server.cookie}=é")[0] == 403  # not ASCII


def test_the_page_loads_only_shipped_files_and_its_policy_allows_its_import_map():
    """Every relative import of every shipped module names a shipped file (a module the
    decoder imports but the package lacks breaks the page), the import map points into the
    package, and the Content-Security-Policy's hash is that of the import map."""
    shipped = set(page_files())
    root = web_root()
    for name in shipped:
        if not name.endswith((".js", ".mjs")):
            continue
        text = (root / name).read_text(encoding="utf-8")
        specifiers = re.findall(
            r"""(?:^|\n)\s*(?:import|export)\b[^'";]*?from\s*['"]([^'"]+)['"]""", text
        )
        specifiers += re.findall(r"""\bimport\(\s*['"]([^'"]+)['"]\s*\)""", text)
        for specifier in specifiers:
            if specifier == "three":
                continue
            target = (Path("/") / name).parent / specifier
            resolved = str(Path(*target.parts).resolve().relative_to("/"))
            assert resolved in shipped, f"{name} imports {specifier}, which is not shipped"
    page = (root / "viewer/index.html").read_text(encoding="utf-8")
    imports = re.search(r'<script type="importmap">(.*?)</script>', page, re.S)
    assert imports is not None
    mapped = json.loads(imports.group(1))["imports"]["three"]
    assert "vendor/three/three.module.js" in shipped and mapped == "../vendor/three/three.module.js"
    digest = base64.b64encode(hashlib.sha256(imports.group(1).encode()).digest()).decode()
    policy = re.search(r'http-equiv="Content-Security-Policy" content="([^"]+)"', page)
    assert policy is not None and f"'sha256-{digest}'" in policy.group(1)
    assert "default-src 'self'" in policy.group(1)


def test_the_web_files_are_package_data():
    """pyproject's package data covers every file the folder takes from the package, so that a
    non-editable install ships the page."""
    config = tomllib.loads((ROOT / "pyproject.toml").read_text())
    patterns = config["tool"]["setuptools"]["package-data"]["tuckercodec"]
    for name in page_files():
        assert any(fnmatch(f"web/{name}", pattern) for pattern in patterns), name
    for licence in ("vendor/three/LICENSE", "vendor/fzstd/LICENSE"):
        assert licence in page_files()


def test_export_writes_the_folder_and_refuses_an_existing_one_without_force(
    files, tmp_path, capsys
):
    out = tmp_path / "site"
    assert main(["view", str(files["tkc"]), "--export-html", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "python -m http.server -d" in printed
    written = sorted(str(p.relative_to(out)) for p in out.rglob("*") if p.is_file())
    marker = OUTPUT_MARKER  # what --force later recognises as a folder the tool wrote
    assert written == sorted([*page_files(), marker, "data/wave_one.tkc", "index.html"])
    assert (out / "data/wave_one.tkc").read_bytes() == files["tkc"].read_bytes()
    index = (out / "index.html").read_text()
    assert "viewer/index.html?file=../data/wave_one.tkc" in index
    assert "reference=" not in index

    (out / "stray.txt").write_text("mine")
    assert main(["view", str(files["tkc"]), "--export-html", str(out)]) == 1
    assert "already exists" in capsys.readouterr().err
    assert (out / "stray.txt").exists()  # untouched

    # an export with a file it does not write beside its own is not replaced, even with --force
    assert main(["view", str(files["tkc"]), "--export-html", str(out), "--force"]) == 1
    err = capsys.readouterr().err.strip()
    assert "would delete 1 entry (stray.txt)" in err and "\n" not in err
    assert "holds files tuckercodec did not write" in err
    assert (out / "stray.txt").read_text() == "mine"

    (out / "stray.txt").unlink()
    (out / "data/wave_one.tkc").write_bytes(b"old")
    assert main(["view", str(files["tkc"]), "--export-html", str(out), "--force"]) == 0
    assert (out / "data/wave_one.tkc").read_bytes() == files["tkc"].read_bytes()
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]  # no staging left


def _exported(out: Path) -> list[str]:
    return sorted(str(p.relative_to(out)) for p in out.rglob("*") if p.is_file())


def test_export_force_replaces_a_previous_export_whole(files, tmp_path, capsys):
    out = tmp_path / "site"
    args = ["view", str(files["tkc"]), "--reference", str(files["original"])]
    assert main([*args, "--export-html", str(out)]) == 0
    assert json.loads((out / OUTPUT_MARKER).read_text())["format"].startswith("tuckercodec")
    assert "data/reference.bin" in _exported(out)
    (out / "data/reference.bin").write_bytes(b"x")  # a file the export wrote, changed: replaced
    assert main(["view", str(files["tkc"]), "--export-html", str(out), "--force"]) == 0
    written = _exported(out)
    assert written == sorted([*page_files(), OUTPUT_MARKER, "data/wave_one.tkc", "index.html"])
    assert not [p for p in tmp_path.iterdir() if p.name != "site"]  # no staging, nothing aside


def test_export_force_uses_an_empty_folder(files, tmp_path):
    out = tmp_path / "empty"
    out.mkdir()
    assert main(["view", str(files["tkc"]), "--export-html", str(out), "--force"]) == 0
    assert (out / "data/wave_one.tkc").read_bytes() == files["tkc"].read_bytes()
    assert (out / OUTPUT_MARKER).is_file()


def test_export_force_keeps_a_users_file_inside_the_exports_own_folders(files, tmp_path, capsys):
    """--force once looked only at the export's top-level names, so a file a user put in its
    data/ or viewer/ was deleted with it."""
    out = tmp_path / "site"
    assert main(["view", str(files["tkc"]), "--export-html", str(out)]) == 0
    for mine in ("data/notes.txt", "viewer/custom.css"):
        (out / mine).write_text("mine")
        capsys.readouterr()
        assert main(["view", str(files["tkc"]), "--export-html", str(out), "--force"]) == 1
        err = capsys.readouterr().err.strip()
        assert f"would delete 1 entry ({mine})" in err and "\n" not in err
        assert (out / mine).read_text() == "mine"
        assert sorted(p.name for p in tmp_path.iterdir()) == ["site"]  # nothing staged or aside
        (out / mine).unlink()
    assert main(["view", str(files["tkc"]), "--export-html", str(out), "--force"]) == 0


def test_export_force_refuses_a_folder_that_is_not_an_export_and_leaves_it(files, tmp_path, capsys):
    """--force once deleted a project's src/ and notes."""
    out = tmp_path / "project"
    (out / "src").mkdir(parents=True)
    (out / "src/main.py").write_text("print(1)")
    (out / "notes.txt").write_text("notes")
    before = {p: p.read_bytes() for p in out.rglob("*") if p.is_file()}
    assert main(["view", str(files["tkc"]), "--export-html", str(out), "--force"]) == 1
    err = capsys.readouterr().err.strip()
    assert err.startswith(f"tuckercodec: {out} was not written by tuckercodec") and "\n" not in err
    assert "would delete 2 entries (notes.txt, src/)" in err
    assert {p: p.read_bytes() for p in out.rglob("*") if p.is_file()} == before
    assert sorted(p.name for p in out.iterdir()) == ["notes.txt", "src"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["project"]  # nothing staged


def test_export_force_refuses_many_names_listing_the_first_few(files, tmp_path, capsys):
    out = tmp_path / "many"
    out.mkdir()
    for number in range(8):
        (out / f"f{number}.txt").write_text("x")
    assert main(["view", str(files["tkc"]), "--export-html", str(out), "--force"]) == 1
    err = capsys.readouterr().err
    assert "would delete 8 entries (f0.txt, f1.txt, f2.txt, f3.txt, f4.txt and 3 more)" in err
    assert len(list(out.iterdir())) == 8


def test_export_force_refuses_a_file_as_the_folder(files, tmp_path, capsys):
    out = tmp_path / "notes.txt"
    out.write_text("mine")
    assert main(["view", str(files["tkc"]), "--export-html", str(out), "--force"]) == 1
    err = capsys.readouterr().err.strip()
    assert err.startswith(f"tuckercodec: {out} is not a folder: --force") and "\n" not in err
    assert out.read_text() == "mine"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["notes.txt"]


def test_export_with_a_reference_writes_its_float32_positions_and_the_measures(
    files, wave, tmp_path, capsys
):
    out = tmp_path / "site"
    args = ["view", str(files["tkc"]), "--reference", str(files["original"])]
    assert main([*args, "--export-html", str(out)]) == 0
    assert "KG error" in capsys.readouterr().out
    meta = json.loads((out / "data/reference.json").read_text())
    assert (meta["vertices"], meta["frames"], meta["dtype"]) == (36, 12, "float32")
    assert meta["data"] == "reference.bin"
    rounded = np.fromfile(out / "data/reference.bin", dtype="<f4").reshape(12, 36, 3)
    np.testing.assert_array_equal(rounded, wave.vertices.astype(np.float32))
    decoded = decode(files["tkc"].read_bytes()).vertices
    original = rounded.astype(np.float64)
    largest = np.linalg.norm(original - decoded, axis=2).max()
    assert meta["maxDistance"] == pytest.approx(largest, rel=1e-12)
    assert meta["kg"] == pytest.approx(kg_error(original, decoded), rel=1e-9)
    index = (out / "index.html").read_text()
    assert "reference=../data/reference.json" in index


def test_a_bad_file_is_exit_3_with_one_line(files, tmp_path, capsys):
    damaged = tmp_path / "damaged.tkc"
    data = bytearray(files["tkc"].read_bytes())
    data[len(data) // 2] ^= 0xFF  # inside a section: its CRC no longer matches
    damaged.write_bytes(bytes(data))
    not_ours = tmp_path / "frames.obj"
    not_ours.write_text("v 0 0 0\n")
    for bad in (damaged, not_ours):
        assert main(["view", str(bad), "--export-html", str(tmp_path / "out")]) == 3
        err = capsys.readouterr().err.strip()
        assert err.startswith("tuckercodec: invalid or corrupt file: ") and "\n" not in err
        assert str(bad) in err and re.search(r"\[R\d\d-[a-z0-9-]+\]$", err)
    assert not (tmp_path / "out").exists()


def test_a_reference_of_another_shape_is_exit_4_naming_both(files, tmp_path, capsys):
    args = ["view", str(files["tkc"]), "--reference", str(files["short"])]
    assert main([*args, "--export-html", str(tmp_path / "out")]) == 4
    err = capsys.readouterr().err.strip()
    assert "11 frames of 36 vertices" in err and "12 of 36" in err and "\n" not in err
    assert not (tmp_path / "out").exists()


def test_options_that_do_not_apply_are_usage_errors(files, tmp_path, capsys):
    assert main(["view", str(files["tkc"]), "--force"]) == 2
    assert "--force applies to --export-html" in capsys.readouterr().err
    assert main(["view", str(files["tkc"]), "--open", "--export-html", str(tmp_path / "o")]) == 2
    capsys.readouterr()
    with pytest.raises(SystemExit):
        main(["view", str(files["tkc"]), "--port", "70000"])
    assert "a port is 0 to 65535" in capsys.readouterr().err


def test_a_port_in_use_is_exit_1_naming_it(files, capsys):
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        assert main(["view", str(files["tkc"]), "--port", str(port)]) == 1
    err = capsys.readouterr().err.strip()
    assert err.startswith(f"tuckercodec: 127.0.0.1:{port}: ") and "\n" not in err


def _start_view(arguments: list[str], env: dict[str, str] | None = None):
    """The real command in a child process, and the URL it prints once it serves. Python's own
    Ctrl-C handler, even where this test runs with SIGINT ignored (a shell's background job),
    which the child would inherit."""
    start = (
        "import runpy, signal, sys; signal.signal(signal.SIGINT, signal.default_int_handler); "
        f"sys.argv = ['tuckercodec', *{arguments!r}]; "
        "runpy.run_module('tuckercodec', run_name='__main__')"
    )
    child = subprocess.Popen(
        [sys.executable, "-c", start],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        cwd=ROOT,
        env=env,
    )
    assert child.stdout is not None
    url = ""
    while not url:
        line = child.stdout.readline()
        if not line:
            child.kill()
            raise AssertionError(f"the command ended early: {child.communicate(timeout=30)}")
        if line.startswith("http://127.0.0.1:"):
            url = line.strip()
    return child, url


def test_the_view_command_serves_until_ctrl_c_then_exits_0(files):
    """The real command in a child process: the URL it prints serves the file, byte for byte;
    SIGINT stops it cleanly (exit 0, no traceback) and the port is closed."""
    arguments = ["view", str(files["tkc"]), "--reference", str(files["original"])]
    child, url = _start_view(arguments)
    try:
        match = re.fullmatch(r"http://127\.0\.0\.1:(\d+)/viewer/index\.html\?file=(.+)", url)
        assert match is not None, url
        port = int(match.group(1))
        connection = http.client.HTTPConnection("127.0.0.1", port, timeout=10)
        connection.request("GET", "/data/wave_one.tkc")  # without the printed URL's token
        response = connection.getresponse()
        assert response.status == 403
        response.read()
        token = re.search(r"[?&]token=([^&]+)$", url)
        assert token is not None, url
        connection.request("GET", f"/data/wave_one.tkc?token={token.group(1)}")
        response = connection.getresponse()
        assert response.status == 200
        assert response.read() == files["tkc"].read_bytes()
        connection.close()
        child.send_signal(signal.SIGINT)
        out, err = child.communicate(timeout=30)
    finally:
        if child.poll() is None:
            child.kill()
            child.communicate()
    assert child.returncode == 0, err
    assert "stopped the server" in out
    assert err == ""
    with socket.socket() as probe, pytest.raises(ConnectionRefusedError):
        probe.connect(("127.0.0.1", port))


def test_measure_js_gives_the_frame_error_python_gives(files, wave, tmp_path):
    """The page's per-frame KG error and largest distance (measure.js, in node) against numpy,
    on one decoded frame of the wave and its float32 original."""
    node = shutil.which("node")
    if node is None:
        pytest.skip("node is not installed (needed to run the page's measure.js)")
    decoded = decode(files["tkc"].read_bytes()).vertices[5].astype(np.float32)
    original = wave.vertices[5].astype(np.float32)
    (tmp_path / "a.bin").write_bytes(original.tobytes())
    (tmp_path / "b.bin").write_bytes(decoded.tobytes())
    measure = Path(str(web_root() / "viewer/measure.js")).as_uri()
    triangles = json.dumps(wave.triangles().ravel().tolist())
    script = f"""
        import {{ readFileSync }} from 'node:fs';
        import {{ frameError, computeNormals }} from '{measure}';
        const load = (name) => {{
          const b = readFileSync(name);
          return new Float32Array(b.buffer, b.byteOffset, b.length / 4);
        }};
        const a = load('{tmp_path / "a.bin"}'), b = load('{tmp_path / "b.bin"}');
        const distances = new Float32Array(a.length / 3);
        const result = frameError(a, b, distances);
        const normals = new Float32Array(a.length);
        computeNormals(a, Uint32Array.from({triangles}), normals);
        const out = {{ ...result, distances: [...distances], normals: [...normals] }};
        console.log(JSON.stringify(out));
    """
    done = subprocess.run(
        [node, "--input-type=module", "-e", script], capture_output=True, text=True, timeout=60
    )
    assert done.returncode == 0, done.stderr
    result = json.loads(done.stdout)
    a, b = original.astype(np.float64), decoded.astype(np.float64)
    distances = np.linalg.norm(a - b, axis=1)
    assert result["kg"] == pytest.approx(kg_error(a[None], b[None]), rel=1e-12)
    assert result["maxError"] == pytest.approx(distances.max(), rel=1e-12)
    np.testing.assert_allclose(result["distances"], distances, rtol=1e-6)
    normals = np.array(result["normals"]).reshape(-1, 3)
    np.testing.assert_allclose(np.linalg.norm(normals, axis=1), 1.0, rtol=1e-6)
    # area-weighted vertex normals, as numpy forms them
    triangles = wave.triangles()
    e1, e2 = a[triangles[:, 1]] - a[triangles[:, 0]], a[triangles[:, 2]] - a[triangles[:, 0]]
    sums = np.zeros_like(a)
    for corner in range(3):
        np.add.at(sums, triangles[:, corner], np.cross(e1, e2))
    expected = sums / np.linalg.norm(sums, axis=1, keepdims=True)
    np.testing.assert_allclose(normals, expected, atol=1e-5)


def test_open_gives_the_browser_a_private_file_not_the_token(files, tmp_path):
    """--open once passed the URL with its token on the browser's command line, which every
    local user can read in /proc/PID/cmdline; the browser now gets the path of a redirect page
    that only this user can read (0600 in a 0700 folder)."""
    record = tmp_path / "record"
    launcher = tmp_path / "browser.sh"
    launcher.write_text(
        "#!/bin/sh\n"
        f'printf "%s\\n" "$0" "$@" > "{record}.argv"\n'
        'page="${1#file://}"\n'
        f'stat -c "%a" "$page" "$(dirname "$page")" > "{record}.mode"\n'
        f'cat "$page" > "{record}.page"\n'
        f'mv "{record}.argv" "{record}.done"\n'
    )
    launcher.chmod(0o700)
    arguments = ["view", str(files["tkc"]), "--open"]
    child, url = _start_view(arguments, {**os.environ, "BROWSER": f"{launcher} %s"})
    try:
        token = url.rsplit("token=", 1)[1]
        done = Path(f"{record}.done")
        for _ in range(600):  # generous: the launcher runs once the server is up
            if done.exists():
                break
            time.sleep(0.1)
        else:
            pytest.fail("the browser was never started")
        command_line = done.read_text().splitlines()
        assert command_line[0] == str(launcher) and len(command_line) == 2
        assert token not in done.read_text() and "token" not in done.read_text()
        page = Path(command_line[1].removeprefix("file://"))
        assert command_line[1].startswith("file://") and page.name == "open.html"
        assert Path(f"{record}.mode").read_text().split() == ["600", "700"]
        assert html.escape(url) in Path(f"{record}.page").read_text()  # it redirects there
        child.send_signal(signal.SIGINT)
        _, err = child.communicate(timeout=30)
    finally:
        if child.poll() is None:
            child.kill()
            child.communicate()
    assert child.returncode == 0, err
    assert not page.exists() and not page.parent.exists()  # removed with the server
