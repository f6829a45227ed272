"""The data of XDMF files: ``<DataItem>``s inline (``Format="XML"``) or in HDF5 files
(``Format="HDF"``, through h5py, the ``[xdmf]`` extra, imported only when needed), and the
``Reference``s that lead from one element to another.

Every count is checked before it is used: XML values against the item's ``Dimensions``; an HDF
dataset must hold exactly as many values, and store at least
1/:data:`~tuckercodec.io.vtk.arrays.MAX_INFLATION` of its size, so that no compression filter
inflates it beyond what zlib could before it is read; and the size of one that stores less than
it holds (compressed, or chunks never written) is taken from what a time step may inflate
(``--max-memory``, :mod:`~tuckercodec.io.common.budget`) before h5py reads it. Errors are
:class:`InputError`s without a path (the caller names the .xdmf and the frame).
"""

from __future__ import annotations

import os
import re
import stat
from collections.abc import Iterator
from pathlib import Path
from typing import Any
from xml.etree import ElementTree

import numpy as np

from ...errors import InputError
from ...system.optional import import_optional
from ...system.reading import inside_folder
from ..common.budget import Inflation
from ..vtk.arrays import MAX_INFLATION

#: The tags of XInclude elements, which are not followed.
XINCLUDE = ("{http://www.w3.org/2001/XInclude}include", "{http://www.w3.org/2003/XInclude}include")
#: XDMF number types and precisions, as numpy types.
_NUMBERS = {
    **{("float", size): f"f{size}" for size in (4, 8)},
    **{("int", size): f"i{size}" for size in (1, 2, 4, 8)},
    **{("uint", size): f"u{size}" for size in (1, 2, 4, 8)},
    ("char", 1): "i1",
    ("uchar", 1): "u1",
}
_REFERENCE_DEPTH = 8
_NAME = r"[A-Za-z_][A-Za-z0-9_.-]*"
#: The References followed: /Xdmf, then child steps, each an element name with at most one
#: predicate, [@Attribute='value'] or [n]. ElementTree's // and * search the whole tree again
#: for every match, without removing duplicates: /Xdmf/Domain//*//*//*//Nope over a few hundred
#: nested elements never ends, so a small crafted file could hang a read.
_PLAIN_PATH = re.compile(
    rf"/Xdmf(?:/{_NAME}(?:\[(?:@{_NAME}=(?:'[^']*'|\"[^\"]*\")|[1-9][0-9]*)\])?)+"
)


def lower(element: ElementTree.Element, *names: str, default: str = "") -> str:
    """The first of the attributes ``names`` (XDMF 2 and 3 spellings), lower case."""
    for name in names:
        value = element.get(name)
        if value is not None:
            return value.strip().lower()
    return default


#: One step of such a path: the name, then the predicate's attribute and value, or position.
_STEP = re.compile(rf"/({_NAME})(?:\[(?:@({_NAME})=(?:'([^']*)'|\"([^\"]*)\")|([1-9][0-9]*))\])?")
#: The elements a document's References may visit in all, per element of the document (and a
#: base): following them costs work in proportion to the document, whatever they name.
WORK_PER_ELEMENT = 32
_WORK_BASE = 100_000


class References:
    """Follows the References of one document (:data:`_PLAIN_PATH`s) as ElementTree's ``find``
    would (the first match in document order), but with each element's children indexed once
    by name, and by the value of an attribute that a predicate names, so that ``[n]`` and
    ``[@Name='...']`` cost nothing per lookup (ElementTree's ``[n]`` lists the siblings again
    for every candidate: one Reference to ``Grid[20000]`` of 20,000 grids took 4e8 steps); and
    with every element visited, and every child indexed, counted against a budget of
    :data:`WORK_PER_ELEMENT` per element of the document, which a file whose References
    search far for their targets exhausts (an InputError, not an endless read)."""

    def __init__(self, root: ElementTree.Element):
        self.root = root
        self.left = WORK_PER_ELEMENT * sum(1 for _ in root.iter()) + _WORK_BASE
        self._named: dict[tuple[int, str], list[ElementTree.Element]] = {}
        self._valued: dict[tuple[int, str, str], dict[str, list[ElementTree.Element]]] = {}
        self._found: dict[str, ElementTree.Element | None] = {}  # a path followed once

    def find(self, target: str) -> ElementTree.Element | None:
        """The element an ``/Xdmf/...`` path of child steps leads to, or None."""
        if target not in self._found:  # steps that share a topology, or a read's next pass
            self._found[target] = self._follow(target)
        return self._found[target]

    def _follow(self, target: str) -> ElementTree.Element | None:
        steps = [match.groups() for match in _STEP.finditer(target, len("/Xdmf"))]
        if not steps:
            return self.root
        pending = [self._children(self.root, steps[0])]
        while pending:  # depth first, children in order: ElementTree's order of matches
            child = next(pending[-1], None)
            if child is None:
                pending.pop()
                continue
            self._spend(1)
            if len(pending) == len(steps):
                return child
            pending.append(self._children(child, steps[len(pending)]))
        return None

    def _children(
        self, element: ElementTree.Element, step: tuple[str | None, ...]
    ) -> Iterator[ElementTree.Element]:
        name, attribute, single, double, position = step
        assert name is not None
        named = self._named.get((id(element), name))
        if named is None:
            self._spend(len(element))
            named = self._named[id(element), name] = [c for c in element if c.tag == name]
        if position is not None:
            return iter(named[int(position) - 1 : int(position)])
        if attribute is None:
            return iter(named)
        values = self._valued.get((id(element), name, attribute))
        if values is None:
            self._spend(len(named))
            values = self._valued[id(element), name, attribute] = {}
            for child in named:
                value = child.get(attribute)
                if value is not None:  # an absent attribute matches no value, not even ''
                    values.setdefault(value, []).append(child)
        return iter(values.get(single if single is not None else str(double), []))

    def _spend(self, work: int) -> None:
        self.left -= work
        if self.left < 0:
            raise InputError(
                "its References search further than the document's size allows "
                f"({WORK_PER_ELEMENT} elements visited per element of the document, in all): "
                "refused"
            )


def resolve(element: ElementTree.Element, references: References) -> ElementTree.Element:
    """The element a ``Reference`` leads to (an ``/Xdmf/...`` path of child steps,
    :data:`_PLAIN_PATH`, or for ``Reference="XML"`` the path in the element's text)."""
    for _ in range(_REFERENCE_DEPTH):
        reference = element.get("Reference")
        if reference is None:
            return element
        target = (element.text or "") if reference.strip().upper() == "XML" else reference
        target = target.strip()
        if not _PLAIN_PATH.fullmatch(target):
            raise InputError(
                f"its Reference {target[:80]!r} is not a plain path of child elements "
                "(/Xdmf/Domain/Grid[@Name='...']/...; no //, *, .. or functions): refused"
            )
        found = references.find(target)
        if found is None:
            raise InputError(f"its Reference {target[:80]!r} leads to no element found here")
        element = found
    raise InputError("its References nest too deep (a cycle?)")


class HeavyData:
    """The HDF5 files a series names, opened once each, and what the datasets read for one time
    step may still inflate to (:attr:`inflation`, which the reader renews for each step)."""

    def __init__(self, folder: Path, inflation: Inflation) -> None:
        self.folder = folder
        self.files: dict[Path, Any] = {}
        self.inflation = inflation

    def close(self) -> None:
        """Close every file opened."""
        for handle in self.files.values():
            handle.close()
        self.files.clear()

    def read(self, text: str, count: int, what: str) -> tuple[np.ndarray, object]:
        """The values of ``file.h5:/dataset``, and that name as the source's identity."""
        h5py = import_optional("h5py", "xdmf", "reading XDMF's HDF5 heavy data")
        name, _, dataset = text.strip().partition(":")
        if not name or not dataset:
            raise InputError(f"{what}: HDF data {text.strip()[:80]!r} is not FILE:/DATASET")
        try:
            file = inside_folder(self.folder, name)
        except InputError as error:
            raise InputError(f"{what}: HDF data {error.reason}") from None
        if file not in self.files:
            try:
                if not stat.S_ISREG(os.stat(file).st_mode):
                    raise InputError(f"{what}: {file} is not a regular file")
                self.files[file] = h5py.File(file, "r")
            except OSError as error:  # h5py raises OSError for files that are not HDF5 too
                raise InputError(f"{what}: cannot read {file} as HDF5 ({error})") from None
        try:
            found = _dataset(h5py, self.files[file], dataset, file, what)
            if not isinstance(found, h5py.Dataset) or found.dtype.kind not in "fiu":
                raise InputError(f"{what}: {file} has no dataset of numbers named {dataset!r}")
            outside = _stored_outside(found, file)
            if outside:
                raise InputError(
                    f"{what}: {file}:{dataset} {outside}, outside {file.name}: refused (only "
                    "data inside the HDF5 file is read)"
                )
            if found.size != count:
                raise InputError(
                    f"{what}: {file}:{dataset} holds {found.size} values, not the {count} its "
                    "Dimensions declare"
                )
            stored = found.id.get_storage_size()
            if found.nbytes > MAX_INFLATION * stored:  # before reading: no filter goes further
                raise InputError(
                    f"{what}: {file}:{dataset} declares {found.nbytes} bytes but stores "
                    f"{stored}: refused"
                )
            if found.nbytes > stored:  # compressed, or chunks never written (fill values)
                self.inflation.take(found.nbytes, f"{what}: {file}:{dataset}")
            values = np.asarray(found[()]).reshape(-1)
        except InputError:
            raise
        except Exception as error:  # h5py and HDF5 raise many kinds on a damaged file
            raise InputError(f"{what}: cannot read {file}:{dataset} ({error})") from None
        return values, (file, dataset)


#: The soft links followed on the way to one dataset, in all (HDF5's own default).
_SOFT_LINKS = 16


def _dataset(h5py: Any, handle: Any, dataset: str, file: Path, what: str) -> Any:
    """The object at ``dataset`` in the open ``file``, or None, reached by following its path
    here one link at a time, each link's kind read before anything behind it is opened: a hard
    link is stepped through, a soft link's target is followed here (at most
    :data:`_SOFT_LINKS` of them), an external link (to another file) or a user-defined one is
    refused. HDF5 itself would follow a soft link whose target crosses an external link, and
    open the other file (a named pipe there blocks for ever) before any check of the path."""
    h5l = h5py.h5l
    parts = [part for part in reversed(dataset.split("/")) if part not in ("", ".")]
    at: list[str] = []  # the path reached, through hard links only: safe to open
    followed = 0
    while parts:
        part = parts.pop()
        group = handle["/" + "/".join(at)]
        if not isinstance(group, h5py.Group) or not group.id.links.exists(part.encode()):
            return None
        kind = group.id.links.get_info(part.encode()).type
        if kind == h5l.TYPE_HARD:
            at.append(part)
            continue
        link = "/" + "/".join([*at, part])
        if kind == h5l.TYPE_SOFT:
            followed += 1
            if followed > _SOFT_LINKS:
                raise InputError(
                    f"{what}: {file}:{dataset}: its soft links nest too deep (more than "
                    f"{_SOFT_LINKS} followed; a cycle?): refused"
                )
            target = group.id.links.get_val(part.encode()).decode("utf-8", "replace")
            if target.startswith("/"):
                at = []
            parts.extend(p for p in reversed(target.split("/")) if p not in ("", "."))
            continue
        if kind == h5l.TYPE_EXTERNAL:
            name, path = (
                v.decode("utf-8", "replace") for v in group.id.links.get_val(part.encode())
            )
            raise InputError(
                f"{what}: {file}:{dataset} leads through an external link ({link}) to "
                f"{name}:{path}, outside {file.name}: refused (only data inside the HDF5 file "
                "is read)"
            )
        raise InputError(
            f"{what}: {file}:{dataset} leads through a user-defined link ({link}): refused "
            "(only hard and soft links inside the HDF5 file are followed)"
        )
    return handle["/" + "/".join(at)]


def _stored_outside(found: Any, file: Path) -> str:
    """How a dataset keeps its values outside its HDF5 file (external storage, a virtual
    dataset's sources, a link to another file), or "" when it does not."""
    if found.is_virtual:
        return "is a virtual dataset, mapped from other datasets"
    if found.external or found.id.get_create_plist().get_external_count():
        return "has external storage (its values are kept in other files)"
    if Path(found.file.filename).resolve() != file:
        return f"is in {found.file.filename}, reached by a link"
    return ""


def read_item(
    element: ElementTree.Element, references: References, heavy: HeavyData, what: str
) -> tuple[np.ndarray, tuple[int, ...], object]:
    """A <DataItem>'s values (flat, of its number type), dimensions and source identity."""
    item = resolve(element, references)
    if lower(item, "ItemType", default="uniform") != "uniform":
        raise InputError(f"{what}: a {item.get('ItemType')} DataItem is not read (Uniform is)")
    try:
        dims = tuple(int(n) for n in (item.get("Dimensions") or "").split())
    except ValueError:
        dims = ()
    if not dims or min(dims) < 0:
        raise InputError(f"{what}: Dimensions {item.get('Dimensions')!r} are not sizes")
    number = lower(item, "NumberType", "DataType", default="float")
    precision = lower(item, "Precision", default="4")
    code = _NUMBERS.get((number, int(precision) if precision.isdigit() else 0))
    if code is None:
        raise InputError(f"{what}: NumberType {number!r} of Precision {precision!r} is unknown")
    count = int(np.prod(dims, dtype=object))
    layout = lower(item, "Format", default="xml")
    if layout == "hdf":
        values, source = heavy.read(item.text or "", count, what)
    elif layout == "xml":
        tokens = (item.text or "").split()
        if len(tokens) != count:
            raise InputError(f"{what}: holds {len(tokens)} values, not the {count} declared")
        try:
            values = np.array(tokens, dtype=np.float64 if code[0] == "f" else np.int64)
        except (ValueError, OverflowError) as error:
            raise InputError(f"{what}: a value is not a number ({error})") from None
        values, source = _narrowed(values, code, what), id(item)
    else:
        raise InputError(f"{what}: Format {item.get('Format')!r} is not read (XML and HDF are)")
    return values, dims, source


def _narrowed(values: np.ndarray, code: str, what: str) -> np.ndarray:
    """XML values (parsed as float64 or int64) in the item's NumberType and Precision. An
    integer the type cannot hold is refused (numpy's cast would wrap it silently: 300 as a
    uchar became 44, a valid index out of an invalid one); a float beyond float32 becomes
    infinity, which the finiteness checks name."""
    if code[0] in "iu" and values.size:
        info = np.iinfo(code)
        if values.min() < info.min or values.max() > info.max:
            raise InputError(f"{what}: a value is beyond the {info.min}..{info.max} of {code}")
    with np.errstate(over="ignore"):
        return values.astype(code)
