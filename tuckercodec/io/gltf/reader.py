"""A glTF 2.0 morph animation read as a mesh sequence: what a viewer shows, frame by frame.

Frame t of a mesh node is ``world(t) · (base + Σ_j w_j(t) · T_j)``: the primitive's POSITION
plus its morph targets' POSITION deltas weighted by the node's ``weights`` (animated, else the
node's or the mesh's default weights, else zeros), moved by the node's transform and its
parents' (each a ``matrix``, or translation/rotation/scale, static or animated).

Choices (documented for users in :func:`read_gltf`):

* Which meshes: the mesh nodes of the default scene (all nodes if the file has no scene), in
  scene order; with ``object_path``, the one node (or the nodes of the one mesh) of that name.
  Several are merged into one mesh, their vertices one after the other, as a viewer shows them.
  Skinned meshes are refused (the skinning is not evaluated).
* Primitives of a mesh are merged the same way (primitives that share all their vertex
  attributes and morph targets share their vertices), faces in primitive order then index
  order. TRIANGLES give triangles; TRIANGLE_STRIP and TRIANGLE_FAN are converted to
  triangles (a strip's degenerate joining triangles dropped); POINTS add vertices without faces;
  line modes are refused (:mod:`.primitives`).
* What the meshes carry beside positions: their vertex attributes (TEXCOORD_n, NORMAL at frame
  0, COLOR_n, _CUSTOM...) as static vertex-domain attributes, and one ``materialBind`` face set
  per material (:mod:`.scene_attributes`).
* Which times: the first animation (others are ignored), at the union of the keyframe times of
  the channels that move the chosen nodes (default) or at ``fps`` frames per second from its
  first to its last keyframe. No animation: one frame.
* Frame rate and time codes: as the tuckercodec writer recorded them (the asset's
  ``extras``), when the times are the ones it wrote; else keyframes spaced evenly by 1/r give
  rate r (rounded to a whole number when within 1e-4 of one) and time codes t·r, which are left
  out when they are 0, 1, 2...; uneven keyframes give the default rate (24) and time codes t·24;
  ``fps`` gives that rate (:mod:`.timing`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ...errors import InputError
from ...model.attributes import Attribute, FaceSet
from ...model.sequence import MeshSequence
from ..common.budget import Inflation
from .animation import PATH_WIDTHS, Sampler, node_matrix, numbers, read_sampler
from .container import Document, integer, read_document
from .primitives import MAX_NUMBERS, Mesh, read_mesh
from .scene_attributes import PlacedMesh, material_face_sets, scene_attributes
from .timing import timing

#: Extensions a file may require that this reader understands.
SUPPORTED_EXTENSIONS = frozenset({"KHR_mesh_quantization", "EXT_meshopt_compression"})
#: The key of the writer's own record in an animation's ``extras``.
EXTRAS_KEY = "tuckercodec"
#: glTF's units and up axis, fixed by its specification (§3.4: metres, +Y up).
METERS_PER_UNIT = 1.0
UP_AXIS = "Y"
#: The levels of nesting above the chosen mesh nodes, in all, allowed per node of the file:
#: each frame multiplies that many transforms (:func:`_check_nesting`).
NESTING_PER_NODE = 64
#: The most weights (frames x morph targets) evaluated at once: the frames of a range are
#: evaluated this many numbers' worth at a time.
WEIGHTS_AT_ONCE = 1 << 22
#: The most frames ``fps`` may ask for (a read also holds at most MAX_NUMBERS numbers, about
#: 2 GiB of float64): checked against the file's keyframe times before anything is sampled.
MAX_FRAMES = 1_000_000


@dataclass
class Sampled:
    """What :func:`sample_gltf` evaluates: positions (n, K, 3), triangles, the times (s)."""

    positions: np.ndarray
    faces: np.ndarray
    times: np.ndarray
    animated: bool
    extras: dict[str, Any] = field(default_factory=dict)
    attributes: list[Attribute] = field(default_factory=list)
    face_sets: list[FaceSet] = field(default_factory=list)


def read_gltf(
    path: Path,
    object_path: str | None = None,
    fps: float | None = None,
    inflation: Inflation | None = None,
) -> MeshSequence:
    """A mesh sequence from a ``.glb``/``.gltf`` file: the morph animation as a viewer plays it
    (see the module docstring for which meshes, primitives and times); its compressed views
    inflate within ``inflation`` (default: half the machine's memory).

    Raises:
        InputError: a damaged or unsupported file, naming the file, the mesh/node/accessor and
            the frame where one is at fault.
        DependencyError: the file uses EXT_meshopt_compression and meshoptimizer (extra
            ``gltf``) is missing.
    """
    sampled = sample_gltf(path, object_path=object_path, fps=fps, inflation=inflation)
    rate, codes, names = timing(sampled.times, sampled.animated, sampled.extras, fps)
    try:
        return MeshSequence(
            sampled.positions,
            sampled.faces,
            frame_names=names,
            frame_rate=rate,
            time_codes=codes,
            meters_per_unit=METERS_PER_UNIT,
            up_axis=UP_AXIS,
            attributes=sampled.attributes,
            face_sets=sampled.face_sets,
        )
    except InputError as error:
        raise InputError(error.reason, path=path, frame=error.frame) from None


def sample_gltf(
    path: Path,
    times: np.ndarray | None = None,
    *,
    object_path: str | None = None,
    fps: float | None = None,
    inflation: Inflation | None = None,
) -> Sampled:
    """Evaluate the file's mesh at ``times`` (seconds), or at its keyframes or ``fps``."""
    scene = Scene(path, times, object_path=object_path, fps=fps, inflation=inflation)
    positions = scene.evaluate(0, len(scene.times))
    return Sampled(
        positions,
        scene.faces,
        scene.times,
        scene.animated,
        scene.extras,
        scene.attributes,
        scene.face_sets,
    )


class Scene:
    """A file's chosen meshes and the animation that moves them, read and checked once, to be
    evaluated a range of frames at a time (:meth:`evaluate`).

    Attributes:
        times: the frames' times in seconds: ``times`` as given, else the keyframes' or
            ``fps``'s (:func:`sample_gltf`).
        faces: the merged meshes' triangles.
        animated: whether the file has an animation.
        extras: the tuckercodec writer's record in the asset's ``extras``, if any.
        attributes: the meshes' vertex attributes (:mod:`.scene_attributes`).
        face_sets: their materials' faces.

    ``inflation``: what the file's compressed views may inflate to (default: half the
    machine's memory).
    """

    def __init__(
        self,
        path: Path,
        times: np.ndarray | None = None,
        *,
        object_path: str | None = None,
        fps: float | None = None,
        inflation: Inflation | None = None,
    ):
        doc = read_document(path, inflation)
        required = doc.gltf.get("extensionsRequired", [])
        if not isinstance(required, list):
            raise doc.fail("extensionsRequired must be a list")
        unknown = [name for name in required if name not in SUPPORTED_EXTENSIONS]
        if unknown:
            raise doc.fail(
                f"requires {', '.join(map(str, unknown))}, which this reader does not support "
                f"(it reads {', '.join(sorted(SUPPORTED_EXTENSIONS))})"
            )
        self.doc = doc
        self.parents = _parents(doc)
        self.chosen = _mesh_nodes(doc, self.parents, object_path)
        _check_nesting(doc, self.chosen, self.parents)
        animation, self.channels = _channels(doc, self.chosen, self.parents)
        self.animated = animation is not None
        keys = [s.times for per_node in self.channels.values() for s in per_node.values()]
        self.extras: dict[str, Any] = {}
        record = doc.gltf["asset"].get("extras")
        if isinstance(record, dict) and isinstance(record.get(EXTRAS_KEY), dict):
            self.extras = record[EXTRAS_KEY]
        self.times = np.asarray(_frame_times(doc, keys, fps) if times is None else times)
        mesh_indices = {_mesh_of(doc, node) for node in self.chosen}
        self.meshes = {index: read_mesh(doc, index) for index in mesh_indices}
        vertex_total = sum(len(self.meshes[_mesh_of(doc, n)].base) for n in self.chosen)
        if len(self.times) * vertex_total * 3 > MAX_NUMBERS:
            raise doc.fail(
                f"{len(self.times)} frames of {vertex_total} vertices are too many to read"
            )
        faces, offset = [], 0
        for node in self.chosen:
            mesh = self.meshes[_mesh_of(doc, node)]
            faces.append(mesh.faces + offset)
            offset += len(mesh.base)
        self.faces = np.concatenate(faces)
        self.attributes = scene_attributes(doc, self._placed())
        materials = [self.meshes[_mesh_of(doc, node)].materials for node in self.chosen]
        self.face_sets = material_face_sets(doc, np.concatenate(materials))

    def _placed(self) -> list[PlacedMesh]:
        """The chosen mesh nodes at the first frame, for their attributes' frame-0 values."""
        doc, first = self.doc, self.times[:1]
        placed = []
        for node in self.chosen:
            mesh = self.meshes[_mesh_of(doc, node)]
            channels = self.channels.get(node, {})
            weights = morph_weights(doc, node, mesh, channels, first)[0]
            world = world_matrices(doc, node, self.parents, self.channels, first)[0]
            extras = doc.item("meshes", _mesh_of(doc, node), f"nodes[{node}]").get("extras")
            placed.append(PlacedMesh(mesh, extras, weights, world))
        return placed

    def evaluate(self, start: int, stop: int) -> np.ndarray:
        """The positions (n, K, 3) at ``times[start:stop]``, each frame's numbers the same
        whatever the range (see :func:`_morphed`); a non-finite one is an InputError naming its
        frame. The frames are evaluated a few at a time, so that their weights (frames x
        targets, which a file's JSON can make far larger than the positions) stay within
        :data:`WEIGHTS_AT_ONCE` numbers."""
        targets = max(len(mesh.weights) for mesh in self.meshes.values())
        step = max(1, WEIGHTS_AT_ONCE // max(1, targets))
        if stop - start <= step:
            return self._evaluate(start, stop)
        vertices = sum(len(self.meshes[_mesh_of(self.doc, n)].base) for n in self.chosen)
        result = np.empty((stop - start, vertices, 3))
        for first in range(start, stop, step):
            last = min(first + step, stop)
            result[first - start : last - start] = self._evaluate(first, last)
        return result

    def _evaluate(self, start: int, stop: int) -> np.ndarray:
        doc, times = self.doc, self.times[start:stop]
        positions = []
        for node in self.chosen:
            mesh = self.meshes[_mesh_of(doc, node)]
            local = _morphed(doc, node, mesh, self.channels.get(node, {}), times)
            world = world_matrices(doc, node, self.parents, self.channels, times)
            placed = np.einsum("nij,nkj->nki", world[:, :3, :3], local) + world[:, None, :3, 3]
            positions.append(placed)
        result = np.concatenate(positions, axis=1)
        bad = ~np.isfinite(result)
        if bad.any():
            frame, vertex, _ = (int(i) for i in np.argwhere(bad)[0])
            raise doc.fail(
                f"vertex {vertex} is not finite at {times[frame]:g} s", frame=start + frame
            )
        return result


def _parents(doc: Document) -> dict[int, int]:
    """Each child node's parent; a node with two parents or a cycle is an error."""
    parents: dict[int, int] = {}
    for index, node in enumerate(doc.array("nodes")):
        if not isinstance(node, dict):
            raise doc.fail(f"nodes[{index}] must be an object")
        children = node.get("children", [])
        if not isinstance(children, list):
            raise doc.fail(f"nodes[{index}].children must be a list")
        for child in children:
            doc.item("nodes", child, f"nodes[{index}].children")
            if child in parents or child == index:
                raise doc.fail(f"nodes[{child}] has two parents (or is its own): not a tree")
            parents[child] = index
    rooted: set[int] = set()  # nodes whose parents are known to end at a root
    for start in parents:
        walked, node = {start}, start
        while node in parents and node not in rooted:  # each node walked once: linear
            node = parents[node]
            if node in walked:
                raise doc.fail(f"nodes[{start}]'s parents form a cycle")
            walked.add(node)
        rooted |= walked
    return parents


def _mesh_nodes(doc: Document, parents: dict[int, int], object_path: str | None) -> list[int]:
    """The mesh nodes to read, in scene order."""
    nodes = doc.array("nodes")
    scenes = doc.array("scenes")
    if scenes:
        scene = integer(doc, doc.gltf, "scene", "the file", default=0)
        roots = doc.item("scenes", scene, "the default scene").get("nodes", [])
        if not isinstance(roots, list):
            raise doc.fail(f"scenes[{scene}].nodes must be a list")
    else:
        roots = [index for index in range(len(nodes)) if index not in parents]
    order: list[int] = []
    placed: set[int] = set()  # as order, for a membership test that does not grow with it
    pending = list(reversed(roots))
    while pending:
        index = pending.pop()
        node = doc.item("nodes", index, "a scene")
        if index in placed:
            raise doc.fail(f"nodes[{index}] appears twice in the scene")
        order.append(index)
        placed.add(index)
        pending.extend(reversed(node.get("children", [])))
    found = [index for index in order if "mesh" in nodes[index]]
    if object_path is not None:
        named = [
            index
            for index in found
            if object_path in (nodes[index].get("name"), _mesh_name(doc, index))
        ]
        if not named:
            names = sorted({str(nodes[i].get("name", f"nodes[{i}]")) for i in found})
            raise doc.fail(
                f"no mesh node or mesh named {object_path!r}; the mesh nodes are: "
                f"{', '.join(names) or 'none'}"
            )
        found = named
    if not found:
        raise doc.fail("the scene holds no mesh")
    for index in found:
        if "skin" in nodes[index]:
            raise doc.fail(
                f"nodes[{index}] ({nodes[index].get('name', 'unnamed')}) is skinned: skinning is "
                "not evaluated here (bake it to morph targets, or pick another mesh with --object)"
            )
    return found


def _check_nesting(doc: Document, chosen: list[int], parents: dict[int, int]) -> None:
    """Each frame multiplies the transforms from each chosen node up to its root: refuse a
    hierarchy where that is far more than the file's nodes (a chain of N mesh nodes, each
    inside the one before, costs N^2 / 2 products a frame from N nodes of JSON)."""
    limit = NESTING_PER_NODE * (len(doc.array("nodes")) + 1)
    total = 0
    for node in chosen:
        while node in parents:
            total += 1
            node = parents[node]
            if total > limit:
                raise doc.fail(
                    f"its {len(chosen)} mesh nodes lie more than {limit} levels deep in all "
                    f"(each frame multiplies the transforms of every level), beyond "
                    f"{NESTING_PER_NODE} per node of the file: refused"
                )


def _mesh_of(doc: Document, node: int) -> int:
    index = doc.array("nodes")[node].get("mesh")
    doc.item("meshes", index, f"nodes[{node}]")
    return int(index)


def _mesh_name(doc: Document, node: int) -> Any:
    return doc.item("meshes", _mesh_of(doc, node), f"nodes[{node}]").get("name")


def _channels(
    doc: Document, chosen: list[int], parents: dict[int, int]
) -> tuple[int | None, dict[int, dict[str, Sampler]]]:
    """The first animation's samplers that move the chosen nodes or their parents, by node and
    path; (None, {}) if the file has no animation."""
    animations = doc.array("animations")
    if not animations:
        return None, {}
    relevant = set(chosen)
    for start in chosen:  # up to a node already known (its own walk adds its parents)
        while start in parents and parents[start] not in relevant:
            start = parents[start]
            relevant.add(start)
    animation = doc.item("animations", 0, "the file")
    channels = animation.get("channels")
    if not isinstance(channels, list):
        raise doc.fail("animations[0].channels must be a list")
    found: dict[int, dict[str, Sampler]] = {}
    for number, channel in enumerate(channels):
        where = f"animations[0].channels[{number}]"
        target = channel.get("target") if isinstance(channel, dict) else None
        if not isinstance(target, dict):
            raise doc.fail(f"{where} lacks a target")
        node = target.get("node")
        path = target.get("path")
        if node is None:
            continue  # no node: an extension's target (KHR_animation_pointer), not a vertex's
        if not isinstance(node, int) or isinstance(node, bool):  # 1.0 == 1 passed the test
            raise doc.fail(f"{where}.target.node must be an integer, got {node!r}")  # below
        if node not in relevant or path not in (*PATH_WIDTHS, "weights"):
            continue  # another node, or a path (pointer...) that does not move vertices
        if path in found.get(node, {}):
            raise doc.fail(f"{where}: a second channel for nodes[{node}].{path}")
        if path == "weights":
            if node not in chosen:
                continue
            width = len(read_mesh(doc, _mesh_of(doc, node)).weights)
        else:
            width = PATH_WIDTHS[path]
        found.setdefault(node, {})[path] = read_sampler(
            doc, 0, channel.get("sampler"), width, f"{where} ({path})", rotation=path == "rotation"
        )
    return 0, found


def _frame_times(doc: Document, keys: list[np.ndarray], fps: float | None) -> np.ndarray:
    if not keys:
        return np.zeros(1)
    union = np.unique(np.concatenate(keys))
    if fps is None:
        return union
    count = int(np.floor((union[-1] - union[0]) * fps + 1e-6)) + 1
    if count > MAX_FRAMES:
        raise doc.fail(
            f"{union[-1] - union[0]:g} s at {fps:g} frames per second is {count} frames, more "
            f"than the {MAX_FRAMES} read at most"
        )
    return union[0] + np.arange(count) / fps


def _morphed(
    doc: Document, node: int, mesh: Mesh, channels: dict[str, Sampler], times: np.ndarray
) -> np.ndarray:
    """The node's mesh with its morph targets applied at each time, (n, K, 3).

    Each frame is its base plus its weighted targets added in order, skipping the targets its
    weight leaves out (0): elementwise, so a frame's numbers do not depend on which other
    frames are evaluated with it (a matrix product's rounding does, through the BLAS's
    blocking and threads), and a file that gives each frame a target of its own (as the
    writer does) costs one target per frame, not all of them.
    """
    count = len(mesh.weights)
    weights = morph_weights(doc, node, mesh, channels, times)
    moved = np.repeat(mesh.base[None], len(times), axis=0)
    with np.errstate(over="ignore", invalid="ignore"):  # found as non-finite by the caller
        for target in range(count):
            column = weights[:, target]
            used = column != 0
            if used.all():
                moved += column[:, None, None] * mesh.targets[target]
            elif used.any():
                moved[used] += column[used, None, None] * mesh.targets[target]
    return moved


def morph_weights(
    doc: Document, node: int, mesh: Mesh, channels: dict[str, Sampler], times: np.ndarray
) -> np.ndarray:
    """The node's morph weights at each time, (n, J): animated, else the node's or the mesh's
    default weights."""
    if "weights" in channels:
        return channels["weights"].at(times)
    default = mesh.weights
    if "weights" in doc.array("nodes")[node]:
        default = numbers(
            doc, doc.array("nodes")[node]["weights"], len(default), f"nodes[{node}].weights"
        )
    return np.repeat(default[None], len(times), axis=0)


def world_matrices(
    doc: Document,
    node: int,
    parents: dict[int, int],
    channels: dict[int, dict[str, Sampler]],
    times: np.ndarray,
) -> np.ndarray:
    """The node's world transform at each time, (n, 4, 4)."""
    chain = [node]
    while chain[-1] in parents:
        chain.append(parents[chain[-1]])
    world = np.repeat(np.eye(4)[None], len(times), axis=0)
    for index in chain:  # child first: world = parent · ... · node
        moves = {p: s for p, s in channels.get(index, {}).items() if p != "weights"}
        world = node_matrix(doc, index, times, moves) @ world
    return world
