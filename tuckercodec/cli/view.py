"""The ``view`` verb: play a compressed file in a web browser.

``tuckercodec view FILE.tkc`` checks the file with the Python decoder (every section, so that a
damaged file is reported here, exit 3, not half-played in the browser), builds the viewer's
folder (:mod:`tuckercodec.web.site`) in a temporary folder and serves it on 127.0.0.1
(:mod:`tuckercodec.web.server`) until Ctrl-C, printing the URL with the run's token, which
the server requires; the browser decodes the file itself, with the JavaScript decoder.
``--reference ORIGINAL`` adds the original's positions (its frame and vertex
counts must be the file's, else exit 4). ``--export-html DIR`` writes the same folder instead,
for any static web server, with the manifest every folder output has
(:func:`tuckercodec.system.atomic.refuse_unless_ours`): ``--force`` replaces only a folder
tuckercodec wrote (nothing in it beyond what its manifest lists) or an empty folder, and
refuses anything else (a file, a folder with other files, at any depth) before writing, naming
what it would delete (exit 1, as for an existing output).

``--open`` starts a web browser without putting the token on its command line, which other
users of the machine can read (``/proc/PID/cmdline``): as Jupyter does, the URL with the token
goes into a redirect page readable by this user only (0600, in a private temporary folder,
removed when the server stops), and the browser is given that file's path.

Ctrl-C is how a server is stopped, not a failure: it shuts the server down, removes the
temporary folder and exits 0 (other verbs exit 130, since Ctrl-C cut their work short).
SIGTERM still ends it as every verb: the same clean-up, then exit 143.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import threading
import webbrowser
from collections.abc import Iterator
from contextlib import ExitStack, contextmanager
from pathlib import Path

import numpy as np

from ..decoder import Decoder
from ..errors import EXIT_OK, FormatError, InputError
from ..format.disk import read_file
from ..io import open_frames
from ..system.atomic import atomic_store, refuse_existing, refuse_unless_ours
from ..web.server import ViewerServer
from ..web.site import (
    ReferenceFrames,
    Site,
    build_site,
    data_name,
    redirect_page,
)
from .inputs import is_compressed, read_options, sequence_source


def run_view(args: argparse.Namespace) -> int:
    _check_options(args)
    if args.export_html is not None:
        # before the work, not after it; with --force, only a folder tuckercodec wrote
        refuse_existing([args.export_html], args.force)
        if args.force:
            refuse_unless_ours(args.export_html)  # a file there, too, is refused
    data, decoder = _validated(args.input)
    name = data_name(args.input)
    if args.export_html is not None:
        with _reference(args, decoder) as reference:
            return _export(args, data, name, decoder, reference)
    with tempfile.TemporaryDirectory(prefix="tuckercodec-view-") as folder:
        with _reference(args, decoder) as reference:  # closed before the server starts
            site = build_site(
                Path(folder),
                data,
                name,
                decoder=decoder,
                reference=reference,
                reference_name=_shown(args),
            )
        return _serve(args, Path(folder), site)


def _check_options(args: argparse.Namespace) -> None:
    if args.export_html is not None and (args.port is not None or args.open):
        raise ValueError("--port and --open are for serving; --export-html writes a folder only")
    if args.export_html is None and args.force:
        raise ValueError("--force applies to --export-html (replace the folder if it exists)")


def _validated(path: str) -> tuple[bytes, Decoder]:
    """The file's bytes, decoded whole by the Python decoder: the bytes served are the bytes
    checked. A FormatError names the file."""
    try:
        data = read_file(path)
        decoder = Decoder(data)
        decoder.check()
    except FormatError as error:
        error.path = os.fspath(path)
        raise
    return data, decoder


class _DecodedFrames:
    """A compressed file as a reference, read a few frames at a time."""

    def __init__(self, source: str) -> None:
        self._decoder = Decoder(source)
        self.frame_count = self._decoder.frame_count
        self.vertex_count = self._decoder.info.vertices

    def read(self, start: int, stop: int) -> np.ndarray:
        return self._decoder.positions(range(start, stop))


@contextmanager
def _reference(args: argparse.Namespace, decoder: Decoder) -> Iterator[ReferenceFrames | None]:
    """The reference, opened and its shape checked against the file's; None without one."""
    if args.reference is None:
        yield None
        return
    if is_compressed(args.reference):
        source: ReferenceFrames = _DecodedFrames(args.reference)
        _check_shape(args, source, decoder)
        yield source
        return
    with open_frames(sequence_source(args.reference), **read_options(args)) as frames:
        _check_shape(args, frames, decoder)
        yield frames


def _check_shape(args: argparse.Namespace, reference: ReferenceFrames, decoder: Decoder) -> None:
    header = decoder.info
    if (reference.frame_count, reference.vertex_count) != (header.frames, header.vertices):
        raise InputError(  # frames must correspond one to one, as for decode --reference
            f"the reference has {reference.frame_count} frames of {reference.vertex_count} "
            f"vertices, {args.input} {header.frames} of {header.vertices}",
            path=args.reference,
        )


def _shown(args: argparse.Namespace) -> str | None:
    if args.reference is None:
        return None
    return "the built-in sample" if args.reference == "sample" else Path(args.reference).name


def _summary(site: Site) -> None:
    if site.reference is not None:
        kg = "undefined" if site.reference.kg is None else f"{site.reference.kg:.5f}"
        print(
            f"against the reference (rounded to float32): KG error {kg}, largest vertex "
            f"distance {site.reference.max_distance:.6g} scene units"
        )


def _export(
    args: argparse.Namespace,
    data: bytes,
    name: str,
    decoder: Decoder,
    reference: ReferenceFrames | None,
) -> int:
    destination = Path(args.export_html)
    # checked again as it is replaced: the folder may have changed while the site was built
    with atomic_store(destination, overwrite=args.force) as staging:
        site = build_site(
            staging,
            data,
            name,
            decoder=decoder,
            reference=reference,
            reference_name=_shown(args),
        )
    size = sum((destination / file).stat().st_size for file in site.files)
    print(f"wrote {destination}: the viewer and {name} ({len(site.files)} files, {size} bytes)")
    _summary(site)
    print(
        "serve it with any static web server, then open its index.html, e.g.:\n"
        f"  python -m http.server -d {destination} --bind 127.0.0.1 8000\n"
        "  http://127.0.0.1:8000/\n"
        "(opened from the disk as a file:// URL the page cannot load its modules or the file)"
    )
    return EXIT_OK


def _serve(args: argparse.Namespace, folder: Path, site: Site) -> int:
    try:
        server = ViewerServer(folder, site.files, 0 if args.port is None else args.port)
    except OSError as error:
        raise OSError(error.errno, error.strerror, f"127.0.0.1:{args.port}") from None
    with server:
        # Ctrl-C is awaited from the first line printed: a caller that reads the URL and stops
        # the server at once must not catch it before the wait (that exited 130)
        try:
            url = server.address(site.entry)  # with the run's token, which every request needs
            _summary(site)
            print(f"serving {args.input} on {server.url} (this machine only); open:", flush=True)
            print(url, flush=True)
            with ExitStack() as opened:  # the redirect page lives as long as the server
                if args.open:
                    private = opened.enter_context(
                        tempfile.TemporaryDirectory(prefix="tuckercodec-open-")
                    )
                    if not open_browser(url, Path(private)):
                        print(
                            "note: no web browser could be started; open the URL above",
                            file=sys.stderr,
                        )
                print("press Ctrl-C to stop", flush=True)
                threading.Event().wait()  # the server answers in its own thread until Ctrl-C
        except KeyboardInterrupt as interrupt:
            if type(interrupt) is not KeyboardInterrupt:  # SIGTERM: exit as every verb does
                raise
    print("stopped the server", flush=True)
    return EXIT_OK


def open_browser(url: str, private: Path) -> bool:
    """Start a web browser on ``url`` without putting it (and its token) on the browser's
    command line: write a redirect page to it, readable by this user only, into ``private``
    (a folder only this user can enter) and open that file. Whether a browser started."""
    page = private / "open.html"
    descriptor = os.open(page, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
    with os.fdopen(descriptor, "w", encoding="utf-8") as handle:
        handle.write(redirect_page(url))
    return webbrowser.open(page.as_uri())
