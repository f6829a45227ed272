"""The decoder limits are written three times: the table of spec/FORMAT.md §7, the Python
decoder's ``Limits`` defaults and the JavaScript decoder's ``DEFAULT_LIMITS``
(tuckercodec/web/tkc/limits.js). Every limit must be in all three, with the same value: a limit
raised in one decoder alone would make the two accept different files."""

from __future__ import annotations

import dataclasses
import re
from pathlib import Path

import pytest

from tuckercodec import Limits

ROOT = Path(__file__).resolve().parents[1]
SPEC = ROOT / "spec" / "FORMAT.md"
LIMITS_JS = ROOT / "tuckercodec" / "web" / "tkc" / "limits.js"

#: a §7 table row: | `name` | 16 777 216 (16 MiB) | ... (digits grouped by spaces, then a note)
_SPEC_ROW = re.compile(r"^\| *`(max_\w+)` *\| *([\d ]+?) *(?:\(([^)]*)\))? *\|", re.M)
#: what the parenthesis after a spec value may say: 2^k, or N MiB
_POWER = re.compile(r"^2\^(\d+)$")
_MIB = re.compile(r"^(\d+) MiB$")
#: an entry of DEFAULT_LIMITS: `name: 64,` or `name: 2 ** 24,` (nothing else is parsed)
_JS_ENTRY = re.compile(r"^ *(max_\w+): *(\d+)(?: *\*\* *(\d+))? *,? *$")


def _noted(note: str, name: str) -> int:
    """The number a §7 note in parentheses says (2^k, or N MiB)."""
    if power := _POWER.match(note):
        return 2 ** int(power.group(1))
    if mib := _MIB.match(note):
        return int(mib.group(1)) << 20
    raise AssertionError(f"§7 {name}: cannot read the note ({note})")


def spec_limits() -> dict[str, int]:
    """name -> default, from the table of spec/FORMAT.md §7. The note in parentheses after a
    value (2^k, or N MiB) must say the same number."""
    text = SPEC.read_text()
    section = text[text.index("## 7. Decoder limits") : text.index("## 8.")]
    limits = {}
    for name, digits, note in _SPEC_ROW.findall(section):
        value = int(digits.replace(" ", ""))
        if note:
            assert _noted(note, name) == value, f"§7 {name}: {digits} is not {note}"
        assert name not in limits, f"§7 lists {name} twice"
        limits[name] = value
    return limits


def python_limits() -> dict[str, int]:
    """name -> default, from the Python decoder's Limits dataclass."""
    defaults = Limits()  # every field has its default: nothing is passed
    return {field.name: getattr(defaults, field.name) for field in dataclasses.fields(Limits)}


def js_limits() -> dict[str, int]:
    """name -> default, from the source of DEFAULT_LIMITS in limits.js. Every line of the
    object must be `name: INT` or `name: INT ** INT`: anything else fails, rather than being
    skipped, so no limit escapes the comparison."""
    text = LIMITS_JS.read_text()
    found = re.search(r"DEFAULT_LIMITS = Object\.freeze\(\{\n(.*?)\n\}\);", text, re.S)
    assert found, "limits.js: no `DEFAULT_LIMITS = Object.freeze({ ... });` found"
    limits = {}
    for line in found.group(1).splitlines():
        if not line.strip() or line.strip().startswith("//"):
            continue
        entry = _JS_ENTRY.match(line)
        assert entry, f"limits.js: cannot read the DEFAULT_LIMITS line {line.strip()!r}"
        name, base, exponent = entry.groups()
        assert name not in limits, f"limits.js lists {name} twice"
        limits[name] = int(base) ** int(exponent) if exponent else int(base)
    return limits


SOURCES = {"spec/FORMAT.md §7": spec_limits, "Python Limits": python_limits, "limits.js": js_limits}


def test_every_source_lists_limits():
    for source, read in SOURCES.items():
        assert len(read()) >= 10, f"{source}: only {sorted(read())} found: is the parsing right?"


def test_the_three_list_the_same_limits():
    names = {source: set(read()) for source, read in SOURCES.items()}
    every = set().union(*names.values())
    missing = {source: sorted(every - found) for source, found in names.items() if every - found}
    assert not missing, f"limits missing: {missing}"


@pytest.mark.parametrize("name", sorted(python_limits()))
def test_a_limit_has_one_value(name):
    values = {source: read().get(name) for source, read in SOURCES.items()}
    assert len(set(values.values())) == 1, f"{name} differs: {values}"
