"""tools/bench/viewer.py on the built-in sample: it serves the file with ``tuckercodec view``,
measures the page in headless Chromium and prints one row per sequence (no timing is judged
here). Skips, naming what is missing, where chromium is not installed."""

from __future__ import annotations

import pytest

from tests.support.browser import find_chromium
from tools import bench

pytestmark = pytest.mark.skipif(
    find_chromium() is None,
    reason="chromium not found (at /usr/bin/chromium, or chromium, chromium-browser or "
    "google-chrome on PATH): the viewer benchmark runs it; Debian: apt-get install chromium",
)


def test_bench_viewer_on_the_sample(capsys):
    code = bench.main(["viewer", "sample", "--loads", "2", "--play-seconds", "3", "--reference"])
    out = capsys.readouterr().out
    assert code == 0
    lines = out.splitlines()
    assert lines[0].startswith("machine: ") and lines[1].startswith("browser: Chrome/")
    assert lines[2] == (
        "command: python -m tools.bench viewer sample --loads 2 --play-seconds 3 --reference"
    )
    header, rule, row = lines[-3:]
    assert header.startswith("| sequence (KG 0.1) |") and rule.startswith("|---|")
    cells = [cell.strip() for cell in row.strip("|").split("|")]
    assert cells[:3] == ["sample + reference", "3101", "60"]
    assert int(cells[3]) > 0  # the file's bytes
    assert cells[4].endswith("(2)")  # two page loads
    opening = float(cells[4].split()[0])
    assert opening > 0
    for column in (6, 8):  # while drawing, and the decoder alone
        times, over = cells[column].split(" (")
        frame = [float(x) for x in times.split(" / ")]
        assert len(frame) == 3 and frame[0] <= frame[1] <= frame[2]
        count, total = over.removesuffix(" > 2)").split(" of ")
        assert 0 <= int(count) <= int(total) and int(total) >= 60
    rate, seconds, counts = (part.strip() for part in cells[9].rsplit(",", 2))
    assert rate == "none (page: 24)" and seconds == "3"
    shown, dropped = (int(x) for x in counts.split(" / "))
    # 3 s, not 0.5: a busy machine's headless browser drew no frame in half a second
    assert shown + dropped > 0


def test_bench_viewer_without_a_sequence(capsys):
    assert bench.main(["viewer", "no-such-sequence.npz"]) == 2
    assert "skipped no-such-sequence.npz: not found" in capsys.readouterr().err
