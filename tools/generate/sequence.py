"""Large, realistic animated meshes at any size, so that scale is tested without shipping data.

Two kinds, each deterministic from ``--seed``:

* ``cloth``: a flag pinned along a vertical pole, a grid of triangles. Each row of the grid is
  laid out segment by segment along the wind, so the sheet keeps its length as it flaps: its
  angle to the wind is a sum of travelling waves whose amplitudes follow gusts (smooth random
  splines) and whose speed follows the wind; oblique folds under moving Gaussian envelopes
  cross it, and it droops when the wind drops. The waves enter through sines and cosines of the
  integrated angle, so the motion has the harmonics and the spread spectrum of a simulation,
  not one frequency.
* ``body``: a four-legged creature with a tail, 24 bones (pelvis, spine, chest, neck, head,
  five tail bones, three per leg) under closed tubes whose radius follows the anatomy, skinned
  by linear blend skinning with smooth weights (Gaussian in the distance along the tube to each
  bone, at most four bones a vertex). The joints follow a walk whose speed, gait frequency and
  heading drift smoothly (legs in walk phase, knees flexing in the swing only, the tail as a
  travelling wave) plus a few random-phase sinusoids per joint and slow random looks of the
  head; the root walks, turns and bobs. Corrective shapes ride on the bones: breathing, the
  bulge of each thigh and upper arm as its knee or elbow flexes, and a belly that jiggles as a
  damped spring driven by the root's vertical acceleration.

Both add noise of about 1e-4 of the model size (the rest pose's bounding-box diagonal) per
vertex, smooth in time (a cubic B-spline through random keys every few frames), as simulation
and capture jitter. Time runs at 30 frames per second, so a longer sequence holds more motion.

The frames are made and written in blocks, so memory stays bounded (a few hundred MB at
200,000 vertices) whatever the frame count: ``OUT.npy`` (float32, shape (frames, vertices,
3)) and ``OUT.faces.obj`` (frame 0 with the faces, for ``encode --faces``), or with ``--npz``
(or ``-o OUT.npz``) an uncompressed ``.npz`` with the keys ``V`` and ``F`` that
``load_sequence`` reads, its members streamed. Files are written atomically and never replace
an existing one without ``--force``.

    python -m tools.generate.sequence --kind body --vertices 200000 --frames 2000 -o /tmp/body.npy
    python -m tools.generate.sequence --kind cloth --vertices 5000 --frames 300 -o c.npz --seed 3
"""

from __future__ import annotations

import argparse
import sys
import time
import zipfile
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import BinaryIO, Protocol

import numpy as np

from tools import common
from tuckercodec.internal import refuse_existing, write_atomic

KINDS = ("cloth", "body")
FPS = 30.0
#: Positions per block of frames (frames x vertices x 3): about 64 MB of float64 a block.
BLOCK_VALUES = 1 << 23
#: The noise: its size per vertex relative to the model, and its keys' spacing in frames.
NOISE_SIZE = 1e-4
NOISE_KEY_FRAMES = 8
MIN_VERTICES = {"cloth": 4, "body": 200}


class Sequence(Protocol):
    """A generated sequence: its size, faces, and any range of its frames on demand."""

    vertex_count: int
    frame_count: int
    faces: np.ndarray  # (T, 3) int64, 0-based

    def frames(self, start: int, stop: int) -> np.ndarray:
        """Frames ``start`` to ``stop`` (exclusive), float64 (stop - start, K, 3)."""
        ...


# ------------------------------------------------------------------------------------------
# smooth random functions of time


def _bspline(keys: np.ndarray, spacing: float, frames: np.ndarray) -> np.ndarray:
    """The uniform cubic B-spline of ``keys`` (knots every ``spacing`` frames) at ``frames``:
    C2-smooth in time, and local (four keys per value)."""
    position = np.asarray(frames, dtype=np.float64) / spacing
    j = np.floor(position).astype(np.int64)
    u = position - j
    u2, u3 = u * u, u * u * u
    basis = [
        (1 - u) ** 3 / 6,
        (3 * u3 - 6 * u2 + 4) / 6,
        (-3 * u3 + 3 * u2 + 3 * u + 1) / 6,
        u3 / 6,
    ]
    shape = (-1,) + (1,) * (keys.ndim - 1)
    return sum(b.reshape(shape) * keys[j + i] for i, b in enumerate(basis))


def _smooth_random(
    rng: np.random.Generator, frames: int, seconds: float, count: int = 1
) -> np.ndarray:
    """``count`` smooth random functions of time, (frames, count), about unit size, whose
    features last about ``seconds``."""
    spacing = max(1.0, seconds * FPS)
    keys = rng.standard_normal((int((frames - 1) / spacing) + 4, count)) * 1.6
    return _bspline(keys, spacing, np.arange(frames))


def _sinusoids(
    rng: np.random.Generator, frames: int, count: int, hertz: tuple[float, float]
) -> np.ndarray:
    """A sum of ``count`` sinusoids of random frequency in ``hertz``, phase and weight,
    (frames,), of unit RMS."""
    t = np.arange(frames) / FPS
    freq = rng.uniform(*hertz, count)
    phase = rng.uniform(0, 2 * np.pi, count)
    weight = rng.uniform(0.3, 1.0, count)
    weight /= np.sqrt(0.5 * np.sum(weight**2))
    return np.sin(2 * np.pi * freq * t[:, None] + phase) @ weight


class SmoothNoise:
    """Per-vertex noise smooth in time: a cubic B-spline through random keys (K, 3) every
    :data:`NOISE_KEY_FRAMES` frames, each key drawn from its own seeded generator, so that any
    frame range is made alone and equals the same frames made with the others."""

    # the mean of the sum of the squared cubic B-spline weights over a knot interval
    _VARIANCE = 0.4793650793650794

    def __init__(self, seed: int, vertices: int, size: float) -> None:
        self.seed, self.vertices = seed, vertices
        self.scale = size / np.sqrt(3 * self._VARIANCE)
        self._keys: dict[int, np.ndarray] = {}

    def _key(self, index: int) -> np.ndarray:
        if index not in self._keys:
            if len(self._keys) >= 8:
                self._keys.pop(min(self._keys))
            rng = np.random.default_rng([self.seed, 0x6E6F6973, index])
            self._keys[index] = rng.standard_normal((self.vertices, 3), dtype=np.float32)
        return self._keys[index]

    def add_to(self, out: np.ndarray, start: int) -> None:
        """Add the noise of frames ``start``... to ``out`` (n, K, 3) in place."""
        for row in range(out.shape[0]):
            position = (start + row) / NOISE_KEY_FRAMES
            j = int(np.floor(position))
            u = position - j
            weights = (
                (1 - u) ** 3 / 6,
                (3 * u**3 - 6 * u**2 + 4) / 6,
                (-3 * u**3 + 3 * u**2 + 3 * u + 1) / 6,
                u**3 / 6,
            )
            for i, weight in enumerate(weights):
                out[row] += (weight * self.scale) * self._key(j + i)


# ------------------------------------------------------------------------------------------
# cloth


class Cloth:
    """A flag pinned along a pole (see the module docstring): a grid of ``columns`` vertices
    along the wind and as many rows as ``vertices`` needs, the last row possibly partial."""

    LENGTH, HEIGHT = 2.0, 1.3
    WAVES, FOLDS = 7, 3

    def __init__(self, vertices: int, frames: int, seed: int, noise: float = NOISE_SIZE) -> None:
        self.vertex_count, self.frame_count = vertices, frames
        self.columns = max(2, round(np.sqrt(vertices * self.LENGTH / self.HEIGHT)))
        self.rows = -(-vertices // self.columns)
        if self.rows < 2:
            self.columns, self.rows = -(-vertices // 2), 2
        self.faces = _grid_triangles(self.rows, self.columns, vertices)
        rng = np.random.default_rng([seed, 1])
        x = np.linspace(0.0, self.LENGTH, self.columns)
        self.dx = x[1] - x[0]
        self.x_mid = x[:-1] + self.dx / 2  # the segments between columns
        self.y = np.linspace(self.HEIGHT, 0.0, self.rows)
        reach = self.x_mid / self.LENGTH
        self.envelope = reach**0.8  # waves grow from the pinned edge
        self.reach = reach
        # wind strength in [0, 1] and the distance it has carried the waves
        self.wind = 1 / (1 + np.exp(-(0.9 + _smooth_random(rng, frames, 4.0)[:, 0])))
        travel = np.cumsum(0.4 + 1.0 * self.wind) / FPS
        self.heading = 0.25 * _smooth_random(rng, frames, 6.0)[:, 0]  # the wind's direction
        # travelling waves: wavenumbers along and across the wind, dispersion, gusts
        n = self.WAVES + self.FOLDS
        self.kx = 2 * np.pi * rng.uniform(0.4, 2.5, n) / self.LENGTH
        self.ky = np.concatenate(
            [
                rng.normal(0, 0.6, self.WAVES),
                rng.uniform(2.0, 5.0, self.FOLDS) * rng.choice([-1, 1]),
            ]
        ) * (2 * np.pi / self.LENGTH)
        speed = rng.uniform(0.7, 1.3, n)
        self.phase = self.kx * speed * travel[:, None] + rng.uniform(0, 2 * np.pi, n)
        base = 0.45 * rng.uniform(0.3, 1.0, n) / np.sqrt(1 + self.kx / self.kx.min())
        base[self.WAVES :] *= 0.5
        gusts = 1 + 0.5 * np.tanh(_smooth_random(rng, frames, 1.5, n))
        self.amplitude = base * gusts * (0.3 + 0.7 * self.wind[:, None])
        # folds: where each one's envelope is, over time
        self.fold_x = self.LENGTH * (
            0.5 + 0.3 * np.tanh(_smooth_random(rng, frames, 3.0, self.FOLDS))
        )
        self.fold_y = self.HEIGHT * (
            0.5 + 0.35 * np.tanh(_smooth_random(rng, frames, 3.0, self.FOLDS))
        )
        self.fold_width = rng.uniform(0.2, 0.45, self.FOLDS)
        # droop, with its own slower waves
        self.droop = 0.05 + 1.1 * (1 - self.wind) ** 1.5
        self.sag_phase = 2 * np.pi * rng.uniform(0.3, 1.2, 2) * travel[:, None] / 2
        self.sag_k = 2 * np.pi * rng.uniform(0.3, 1.0, 2) / self.LENGTH
        self.sag_amplitude = 0.08 * (0.5 + 0.5 * np.tanh(_smooth_random(rng, frames, 2.0, 2)))
        size = float(np.hypot(self.LENGTH, self.HEIGHT))
        self.noise = SmoothNoise(seed, vertices, noise * size)

    def frames(self, start: int, stop: int) -> np.ndarray:
        """Frames ``start`` to ``stop``, float64 (n, K, 3)."""
        f = slice(start, stop)
        n = stop - start
        x, y = self.x_mid, self.y
        theta = np.zeros((n, self.rows, self.columns - 1))
        for m in range(self.WAVES + self.FOLDS):
            along = self.kx[m] * x[None, :] - self.phase[f, m, None]  # (n, segments)
            across = self.ky[m] * y  # (rows,)
            xs, xc = np.sin(along), np.cos(along)
            ys, yc = np.broadcast_to(np.sin(across), (n, self.rows)), np.cos(across)[None, :]
            if m >= self.WAVES:  # a fold: the wave under a moving Gaussian envelope
                fold = m - self.WAVES
                width = self.fold_width[fold]
                ex = np.exp(-(((x[None, :] - self.fold_x[f, fold, None]) / width) ** 2))
                ey = np.exp(-(((y[None, :] - self.fold_y[f, fold, None]) / width) ** 2))
                xs, xc, ys, yc = xs * ex, xc * ex, ys * ey, yc * ey
            a = self.amplitude[f, m, None, None]
            # sin(kx x + ky y - p) = sin(kx x - p) cos(ky y) + cos(kx x - p) sin(ky y)
            theta += a * (xs[:, None, :] * yc[:, :, None] + xc[:, None, :] * ys[:, :, None])
        theta *= self.envelope
        theta += self.heading[f, None, None]
        psi = self.droop[f, None, None] * self.reach**1.3 + np.zeros_like(theta)
        for m in range(2):
            wave = np.sin(self.sag_k[m] * x[None, :] - self.sag_phase[f, m, None])
            psi += (self.sag_amplitude[f, m, None] * wave * self.reach)[:, None, :]
        cos_psi = np.cos(psi)
        steps = np.stack([cos_psi * np.cos(theta), -np.sin(psi), cos_psi * np.sin(theta)], axis=-1)
        out = np.empty((n, self.rows, self.columns, 3))
        out[:, :, 0] = 0.0
        out[:, :, 0, 1] = y  # the pinned edge, on the pole
        np.cumsum(steps * self.dx, axis=2, out=out[:, :, 1:])
        out[:, :, 1:, 1] += y[None, :, None]
        out = out.reshape(n, -1, 3)[:, : self.vertex_count]
        out = np.ascontiguousarray(out)
        self.noise.add_to(out, start)
        return out


def _grid_triangles(rows: int, columns: int, vertices: int) -> np.ndarray:
    """The triangles of a row-major grid of ``rows`` x ``columns`` vertices of which only the
    first ``vertices`` exist (the last row may be partial), (T, 3)."""
    index = np.arange(rows * columns).reshape(rows, columns)
    a, b = index[:-1, :-1].ravel(), index[1:, :-1].ravel()
    c, d = index[1:, 1:].ravel(), index[:-1, 1:].ravel()
    triangles = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])
    triangles = triangles[(triangles < vertices).all(axis=1)]
    last = rows * columns - columns  # the last row's first vertex
    if vertices - last == 1:  # a lone vertex in the last row: tie it to the row above
        triangles = np.concatenate([triangles, [[last - columns, last, last - columns + 1]]])
    return triangles.astype(np.int64)


# ------------------------------------------------------------------------------------------
# body: the skeleton, the tubes around it, the motion


@dataclass(frozen=True)
class _Bone:
    name: str
    parent: int  # index of the parent bone, -1 for the root
    pivot: tuple[float, float, float]  # the joint it turns about, rest pose


@dataclass(frozen=True)
class _Tube:
    points: np.ndarray  # (P, 3) the centre line's knots, rest pose
    radii: np.ndarray  # (P,)
    bones: tuple[int, ...]  # the bone of each of the P - 1 segments


# x forward, y up, z to the left. The main line runs from the tail's tip to the nose:
# (x, y, radius) of each knot, and the bone of each segment between two knots.
_MAIN = (
    (-1.60, 0.50, 0.015),
    (-1.35, 0.58, 0.030),
    (-1.10, 0.64, 0.045),
    (-0.85, 0.69, 0.060),
    (-0.60, 0.73, 0.085),
    (-0.35, 0.76, 0.150),
    (-0.10, 0.78, 0.170),
    (0.15, 0.79, 0.180),
    (0.40, 0.79, 0.170),
    (0.55, 0.86, 0.110),
    (0.68, 1.00, 0.075),
    (0.82, 1.10, 0.095),
    (1.12, 1.04, 0.040),
)
_MAIN_BONES = [
    "tail5",
    "tail4",
    "tail3",
    "tail2",
    "tail1",
    "pelvis",
    "spine1",
    "spine2",
    "chest",
    "neck1",
    "neck2",
    "head",
]
# (x, y, z, radius) of a left leg's knots, from inside the body to the toe; z flips for the right
_HIND = (
    (-0.35, 0.80, 0.09, 0.07),
    (-0.35, 0.64, 0.17, 0.08),
    (-0.27, 0.38, 0.19, 0.05),
    (-0.40, 0.12, 0.19, 0.032),
    (-0.28, 0.015, 0.20, 0.025),
)
_FRONT = (
    (0.40, 0.80, 0.09, 0.065),
    (0.40, 0.64, 0.16, 0.07),
    (0.44, 0.38, 0.18, 0.045),
    (0.38, 0.11, 0.18, 0.03),
    (0.50, 0.015, 0.19, 0.022),
)
SIDES = (("L", 1.0), ("R", -1.0))


def _skeleton() -> tuple[list[_Bone], list[_Tube]]:
    """The 24 bones in an order where parents come first, and the five tubes around them."""
    main = {i: (x, y, 0.0) for i, (x, y, _) in enumerate(_MAIN)}
    bones: list[_Bone] = []
    index: dict[str, int] = {}

    def bone(name: str, parent: str | None, pivot: tuple[float, float, float]) -> None:
        index[name] = len(bones)
        bones.append(_Bone(name, -1 if parent is None else index[parent], pivot))

    bone("pelvis", None, main[5])
    for name, parent, knot in (
        ("spine1", "pelvis", 6),
        ("spine2", "spine1", 7),
        ("chest", "spine2", 8),
        ("neck1", "chest", 9),
        ("neck2", "neck1", 10),
        ("head", "neck2", 11),
        ("tail1", "pelvis", 5),
        ("tail2", "tail1", 4),
        ("tail3", "tail2", 3),
        ("tail4", "tail3", 2),
        ("tail5", "tail4", 1),
    ):
        bone(name, parent, main[knot])
    tubes = [
        _Tube(
            np.array([main[i] for i in range(len(_MAIN))]),
            np.array([r for *_, r in _MAIN]),
            tuple(index[name] for name in _MAIN_BONES),
        )
    ]
    for knots, root, names in (
        (_HIND, "pelvis", ("thigh", "shin", "hindfoot")),
        (_FRONT, "chest", ("upperarm", "forearm", "forefoot")),
    ):
        for side, sign in SIDES:
            points = np.array([(x, y, z * sign) for x, y, z, _ in knots])
            parent = root
            for j, name in enumerate(names):
                x, y, z = (float(c) for c in points[j + 1])
                bone(f"{name}_{side}", parent, (x, y, z))
                parent = f"{name}_{side}"
            segment_bones = (index[root], *(index[f"{name}_{side}"] for name in names))
            tubes.append(_Tube(points, np.array([r for *_, r in knots]), segment_bones))
    return bones, tubes


def _rotations(vectors: np.ndarray) -> np.ndarray:
    """Rotation matrices (..., 3, 3) of rotation vectors (..., 3) (Rodrigues)."""
    angle = np.linalg.norm(vectors, axis=-1)[..., None, None]
    safe = np.where(angle > 1e-12, angle, 1.0)
    k = vectors / safe[..., 0]
    cross = np.zeros((*vectors.shape[:-1], 3, 3))
    cross[..., 0, 1], cross[..., 0, 2] = -k[..., 2], k[..., 1]
    cross[..., 1, 0], cross[..., 1, 2] = k[..., 2], -k[..., 0]
    cross[..., 2, 0], cross[..., 2, 1] = -k[..., 1], k[..., 0]
    eye = np.broadcast_to(np.eye(3), cross.shape)
    return eye + np.sin(angle) * cross + (1 - np.cos(angle)) * (cross @ cross)


def _sigmoid(x: np.ndarray) -> np.ndarray:
    return 1 / (1 + np.exp(-x))


class _Motion:
    """Every bone's rotation (frames, B, 3) as a rotation vector in the parent's rest axes, the
    root's path, and the signals the corrective shapes follow."""

    def __init__(self, bones: list[_Bone], frames: int, rng: np.random.Generator) -> None:
        n = len(bones)
        by_name = {b.name: i for i, b in enumerate(bones)}
        rot = np.zeros((frames, n, 3))

        def smooth(seconds: float, count: int = 1) -> np.ndarray:
            return _smooth_random(rng, frames, seconds, count)

        # walking speed (units/s), gait frequency and phase
        speed = 0.2 + 1.0 * _sigmoid(smooth(5.0)[:, 0])
        gait = 2 * np.pi * np.cumsum(0.5 + 0.6 * speed) / FPS
        stride = 0.15 + 0.3 * speed / 1.2
        offsets = {"thigh_L": 0.0, "upperarm_L": 0.25, "thigh_R": 0.5, "upperarm_R": 0.75}
        offsets = {k: 2 * np.pi * (v + rng.normal(0, 0.02)) for k, v in offsets.items()}
        self.flex: dict[str, np.ndarray] = {}
        for side, _ in SIDES:
            for upper, lower, foot, sign in (
                ("thigh", "shin", "hindfoot", -1.0),
                ("upperarm", "forearm", "forefoot", -1.0),
            ):
                phase = gait + offsets[f"{upper}_{side}"]
                rot[:, by_name[f"{upper}_{side}"], 2] = stride * np.sin(phase)
                swing = ((1 + np.sin(phase + 0.6)) / 2) ** 3  # the foot lifts in swing
                flex = sign * (0.25 + 0.6 * speed / 1.2) * swing
                rot[:, by_name[f"{lower}_{side}"], 2] = flex
                self.flex[f"{upper}_{side}"] = np.abs(flex)
                rot[:, by_name[f"{foot}_{side}"], 2] = 0.5 * ((1 + np.sin(phase - 0.4)) / 2) ** 2
                rot[:, by_name[f"{upper}_{side}"], 0] = 0.04 * np.sin(phase + 1.0)
        # the spine sways with the gait and bends into turns
        turn = 0.45 * np.tanh(smooth(4.0)[:, 0])  # rad/s
        for k, name in enumerate(("spine1", "spine2", "chest")):
            rot[:, by_name[name], 1] = 0.05 * np.sin(gait + 0.6 * k) + 0.25 * turn
            rot[:, by_name[name], 2] = 0.025 * np.sin(2 * gait + 0.4 * k)
        # the head looks around
        look = smooth(1.5, 4)
        rot[:, by_name["neck1"], 2] = 0.15 * look[:, 0] + 0.03 * np.sin(2 * gait + 1.0)
        rot[:, by_name["neck1"], 1] = 0.2 * look[:, 1]
        rot[:, by_name["neck2"], 1] = 0.15 * look[:, 1] + 0.1 * look[:, 2]
        rot[:, by_name["head"], 2] = 0.2 * look[:, 2]
        rot[:, by_name["head"], 0] = 0.12 * look[:, 3]
        # the tail: a travelling wave, raised and lowered with the mood
        tail_phase = 2 * np.pi * np.cumsum(0.5 + 0.5 * _sigmoid(smooth(3.0)[:, 0])) / FPS
        mood = smooth(4.0)[:, 0]
        for k in range(1, 6):
            rot[:, by_name[f"tail{k}"], 1] = (0.1 + 0.06 * k) * np.sin(tail_phase - 0.9 * k)
            rot[:, by_name[f"tail{k}"], 2] = -0.08 * mood + 0.03 * np.sin(gait + 0.5 * k)
        # and every joint a little of its own
        for b in range(n):
            for axis in range(3):
                rot[:, b, axis] += 0.03 * _sinusoids(rng, frames, 3, (0.1, 1.0))
        # the root walks, turns and bobs
        heading = np.cumsum(turn) / FPS + rng.uniform(0, 2 * np.pi)
        rot[:, 0, 0] += 0.04 * np.sin(gait)
        rot[:, 0, 2] += 0.03 * np.sin(2 * gait + 0.5)
        self.bob = 0.02 * np.sin(2 * gait + 0.3) * speed
        velocity = speed[:, None] * np.stack([np.cos(heading), 0 * heading, -np.sin(heading)], 1)
        self.root = np.cumsum(velocity, axis=0) / FPS
        self.root[:, 1] += self.bob
        self.heading = heading
        self.local = _rotations(rot)
        self.breath = (0.6 + 0.6 * speed) * np.sin(
            2 * np.pi * np.cumsum(0.3 + 0.2 * _sigmoid(smooth(6.0)[:, 0])) / FPS
        )
        height = self.root[:, 1]
        lift = np.zeros(frames)  # the root's vertical acceleration, per frame squared
        if frames >= 3:
            lift[1:-1] = height[2:] - 2 * height[1:-1] + height[:-2]
            lift[0], lift[-1] = lift[1], lift[-2]
        self.jiggle = _spring(lift * FPS**2)


def _spring(drive: np.ndarray, hertz: float = 2.5, damping: float = 0.15) -> np.ndarray:
    """A damped spring driven by ``drive`` (per frame), its displacement scaled to unit RMS."""
    omega, dt = 2 * np.pi * hertz, 1 / FPS
    x = v = 0.0
    out = np.empty_like(drive)
    for f, a in enumerate(drive):  # semi-implicit Euler: stable for omega*dt < 2
        v += dt * (-(omega**2) * x - 2 * damping * omega * v - a)
        x += dt * v
        out[f] = x
    rms = float(np.sqrt(np.mean(out**2)))
    return out / rms if rms > 0 else out


@dataclass(frozen=True)
class _Line:
    """A tube's centre line, sampled densely, with a frame transported along it."""

    points: np.ndarray  # (D, 3)
    arc: np.ndarray  # (D,) arc length
    tangents: np.ndarray  # (D, 3)
    normals: np.ndarray  # (D, 3), perpendicular to the tangent, without twist
    knot_arc: np.ndarray  # (P,) the arc length of each knot
    radii: np.ndarray  # (P,)

    def radius(self, s: np.ndarray) -> np.ndarray:
        """The tube's radius at arc lengths ``s``, eased between the knots."""
        k = self.knot_arc
        i = np.clip(np.searchsorted(k, s, side="right") - 1, 0, len(k) - 2)
        w = np.clip((s - k[i]) / (k[i + 1] - k[i]), 0.0, 1.0)
        w = (1 - np.cos(np.pi * w)) / 2
        return self.radii[i] + (self.radii[i + 1] - self.radii[i]) * w


def _centre_line(tube: _Tube, samples: int = 48) -> _Line:
    """A Catmull-Rom curve through the tube's knots, with parallel-transported frames."""
    p = tube.points
    ext = np.concatenate([2 * p[:1] - p[1:2], p, 2 * p[-1:] - p[-2:-1]])
    u = (np.arange(samples) / samples)[:, None]
    pieces = []
    for i in range(len(p) - 1):
        p0, p1, p2, p3 = ext[i : i + 4]
        pieces.append(
            p1
            + 0.5 * (p2 - p0) * u
            + 0.5 * (2 * p0 - 5 * p1 + 4 * p2 - p3) * u**2
            + 0.5 * (-p0 + 3 * p1 - 3 * p2 + p3) * u**3
        )
    points = np.concatenate([*pieces, p[-1:]])
    arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(points, axis=0), axis=1))])
    tangents = np.gradient(points, axis=0)
    tangents /= np.linalg.norm(tangents, axis=1, keepdims=True)
    normals = np.empty_like(points)
    seed = np.eye(3)[int(np.argmin(np.abs(tangents[0])))]
    normal = np.cross(tangents[0], seed)
    for d, t in enumerate(tangents):  # parallel transport: no twist along the tube
        normal = normal - np.dot(normal, t) * t
        normal /= np.linalg.norm(normal)
        normals[d] = normal
    return _Line(points, arc, tangents, normals, arc[::samples], np.asarray(tube.radii, float))


def _ring_layout(line: _Line, spacing: float) -> tuple[np.ndarray, np.ndarray]:
    """Arc lengths and vertex counts of a tube's rings for an edge length of about
    ``spacing``: at least 3 rings of at least 6 vertices."""
    length = line.arc[-1]
    count = max(3, round(length / spacing))
    s = length * (np.arange(count) + 0.5) / count
    sizes = np.maximum(6, np.rint(2 * np.pi * line.radius(s) / spacing)).astype(np.int64)
    return s, sizes


def _strip(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Triangles joining the closed rings of vertex indices ``a`` and ``b`` (any sizes), both
    running the same way round, by merging them in angle; they face outward for rings made
    as in :func:`_surface`."""
    n1, n2 = len(a), len(b)
    keys = np.concatenate([(np.arange(n1) + 1) * n2, (np.arange(n2) + 1) * n1])  # exact angles
    on_b = np.concatenate([np.zeros(n1, bool), np.ones(n2, bool)])
    on_b = on_b[np.argsort(keys, kind="stable")]
    i = np.cumsum(~on_b) - ~on_b  # steps along a before each triangle
    j = np.cumsum(on_b) - on_b
    along_a = np.stack([a[i % n1], a[(i + 1) % n1], b[j % n2]], axis=1)
    along_b = np.stack([a[i % n1], b[(j + 1) % n2], b[j % n2]], axis=1)
    return np.where(on_b[:, None], along_b, along_a)


@dataclass(frozen=True)
class _Surface:
    rest: np.ndarray  # (K, 3)
    normals: np.ndarray  # (K, 3)
    faces: np.ndarray  # (T, 3)
    tube: np.ndarray  # (K,) which tube each vertex is on
    arc: np.ndarray  # (K,) its arc length along that tube's centre line
    weights: np.ndarray  # (K, B) skinning weights, at most 4 nonzero a row, rows sum to 1
    lines: list[_Line]


def _surface(tubes: list[_Tube], bone_count: int, vertices: int) -> _Surface:
    """The tubes' closed surfaces with exactly ``vertices`` vertices in all: rings about
    evenly spaced, each tube capped at both ends by a pole."""
    lines = [_centre_line(tube) for tube in tubes]

    def total(spacing: float) -> int:
        return sum(int(_ring_layout(line, spacing)[1].sum()) + 2 for line in lines)

    low, high = 1e-5, 10.0
    if total(high) > vertices:
        raise ValueError(f"a body needs at least {total(high)} vertices, not {vertices}")
    for _ in range(80):  # the widest spacing whose count is at most the target
        middle = np.sqrt(low * high)
        low, high = (middle, high) if total(middle) > vertices else (low, middle)
    layouts = [_ring_layout(line, high) for line in lines]
    # the few vertices short of the target go one each to the biggest rings
    sizes = np.concatenate([size for _, size in layouts])
    short = vertices - total(high)
    order = np.argsort(-sizes, kind="stable")
    np.add.at(sizes, order[np.arange(short) % len(sizes)], 1)
    parts: dict[str, list[np.ndarray]] = {k: [] for k in ("rest", "normals", "tube", "arc", "w")}
    faces, first, ring_start = [], 0, 0
    for t, (line, (s, _)) in enumerate(zip(lines, layouts, strict=True)):
        ring_sizes = sizes[ring_start : ring_start + len(s)]
        ring_start += len(s)
        at = np.clip(np.searchsorted(line.arc, s), 0, len(line.arc) - 1)
        tangent, normal = line.tangents[at], line.normals[at]
        binormal = np.cross(tangent, normal)
        centre = np.stack([np.interp(s, line.arc, line.points[:, c]) for c in range(3)], axis=1)
        ring_of = np.repeat(np.arange(len(s)), ring_sizes)
        step = np.arange(len(ring_of)) - np.repeat(np.cumsum(ring_sizes) - ring_sizes, ring_sizes)
        angle = 2 * np.pi * step / ring_sizes[ring_of]
        radial = (
            np.cos(angle)[:, None] * normal[ring_of] + np.sin(angle)[:, None] * binormal[ring_of]
        )
        ring_points = centre[ring_of] + line.radius(s)[ring_of, None] * radial
        poles = line.points[[0, -1]]
        parts["rest"] += [ring_points, poles]
        parts["normals"] += [radial, np.stack([-line.tangents[0], line.tangents[-1]])]
        arc = np.concatenate([s[ring_of], [0.0, line.arc[-1]]])
        parts["arc"].append(arc)
        parts["tube"].append(np.full(len(arc), t))
        parts["w"].append(_weights(arc, line.knot_arc, tubes[t].bones, bone_count))
        # faces: a strip between each pair of rings, a fan at each end
        starts = first + np.cumsum(ring_sizes) - ring_sizes
        rings = [np.arange(a, a + n) for a, n in zip(starts, ring_sizes, strict=True)]
        faces += [_strip(rings[r], rings[r + 1]) for r in range(len(rings) - 1)]
        pole = first + len(ring_of)
        for ring, p, flip in ((rings[0], pole, True), (rings[-1], pole + 1, False)):
            nxt = np.roll(ring, -1)
            fan = np.stack([np.full(len(ring), p), ring, nxt], axis=1)
            faces.append(fan[:, [0, 2, 1]] if flip else fan)
        first = pole + 2
    return _Surface(
        rest=np.concatenate(parts["rest"]),
        normals=np.concatenate(parts["normals"]),
        faces=np.concatenate(faces).astype(np.int64),
        tube=np.concatenate(parts["tube"]),
        arc=np.concatenate(parts["arc"]),
        weights=np.concatenate(parts["w"]),
        lines=lines,
    )


def _weights(
    s: np.ndarray, knot_arc: np.ndarray, bones: tuple[int, ...], bone_count: int
) -> np.ndarray:
    """Linear-blend-skinning weights of points at arc lengths ``s`` along a tube: Gaussian in
    the distance to each segment's span (zero inside it), summed per bone, the four largest
    kept, normalized. (len(s), bone_count)."""
    lengths = np.diff(knot_arc)
    before, after = knot_arc[:-1][None, :] - s[:, None], s[:, None] - knot_arc[1:][None, :]
    distance = np.maximum(0.0, np.maximum(before, after))
    per_segment = np.exp(-((distance / (0.3 * lengths)) ** 2))
    weights = np.zeros((len(s), bone_count))
    for segment, bone in enumerate(bones):
        weights[:, bone] += per_segment[:, segment]
    if bone_count > 4:
        fourth = np.partition(weights, -4, axis=1)[:, -4:-3]
        weights[weights < fourth] = 0.0
    return weights / weights.sum(axis=1, keepdims=True)


@dataclass(frozen=True)
class _Corrective:
    """A shape that rides on one bone: ``vertices`` move by ``offsets`` (rest axes) times
    ``amount`` of the frame, turned with the bone."""

    vertices: slice  # a tube's rings are consecutive: a slice, not a gather
    offsets: np.ndarray
    bone: int
    amount: np.ndarray  # (frames,)


class Body:
    """A skinned, articulated creature (see the module docstring)."""

    def __init__(self, vertices: int, frames: int, seed: int, noise: float = NOISE_SIZE) -> None:
        self.vertex_count, self.frame_count = vertices, frames
        bones, tubes = _skeleton()
        surface = _surface(tubes, len(bones), vertices)
        self.faces = surface.faces
        rng = np.random.default_rng([seed, 2])
        motion = _Motion(bones, frames, rng)
        # forward kinematics: each bone's world rotation and joint position, every frame
        pivots = np.array([bone.pivot for bone in bones])
        world = np.empty((frames, len(bones), 3, 3))
        joints = np.empty((frames, len(bones), 3))
        yaw = _rotations(np.stack([0 * motion.heading, motion.heading, 0 * motion.heading], 1))
        for b, bone in enumerate(bones):
            if bone.parent < 0:
                world[:, b] = yaw @ motion.local[:, b]
                joints[:, b] = pivots[b] + motion.root
            else:
                p = bone.parent
                world[:, b] = world[:, p] @ motion.local[:, b]
                joints[:, b] = joints[:, p] + world[:, p] @ (pivots[b] - pivots[p])
        # x' = W (x - pivot) + J = [W | J - W pivot] (x, 1)
        shift = joints - np.einsum("fbij,bj->fbi", world, pivots)
        self._matrices = np.concatenate([world, shift[..., None]], axis=3)  # (F, B, 3, 4)
        self._world = world
        # Skinning is one matrix product per tube and block of frames, over only the bones
        # that move the tube (12 for the main one, 4 for a leg): a tube's vertices are
        # consecutive. blend[v, 4b + j] = weight[v, b] * (x, y, z, 1)[j].
        homogeneous = np.concatenate([surface.rest, np.ones((vertices, 1))], axis=1)
        self._parts = []
        for tube in range(len(tubes)):
            on = np.flatnonzero(surface.tube == tube)
            rows = slice(int(on[0]), int(on[-1]) + 1)
            used = np.flatnonzero(surface.weights[rows].any(axis=0))
            blend = surface.weights[rows, used][:, :, None] * homogeneous[rows, None, :]
            self._parts.append((rows, used, blend.reshape(len(on), -1)))
        self._correctives = _correctives(surface, bones, motion)
        size = float(np.linalg.norm(np.ptp(surface.rest, axis=0)))
        self.noise = SmoothNoise(seed, vertices, noise * size)

    def frames(self, start: int, stop: int) -> np.ndarray:
        """Frames ``start`` to ``stop``, float64 (n, K, 3)."""
        n = stop - start
        out = np.empty((n, self.vertex_count, 3))
        for rows, used, blend in self._parts:
            # (4b, 3n): row 4b + j, column 3f + c holds bone b's matrix [c, j] at frame f
            stacked = self._matrices[start:stop, used].transpose(1, 3, 0, 2).reshape(-1, 3 * n)
            out[:, rows] = (blend @ stacked).reshape(-1, n, 3).transpose(1, 0, 2)
        for shape in self._correctives:
            turning = self._world[start:stop, shape.bone].transpose(0, 2, 1)
            turning = turning * shape.amount[start:stop, None, None]
            out[:, shape.vertices] += shape.offsets @ turning
        self.noise.add_to(out, start)
        return out


def _correctives(surface: _Surface, bones: list[_Bone], motion: _Motion) -> list[_Corrective]:
    """Breathing, the belly's jiggle, and a bulge on each thigh and upper arm."""
    index = {bone.name: b for b, bone in enumerate(bones)}
    main = surface.lines[0].knot_arc
    shapes = []

    def shape(tube: int, centre: float, width: float, size: float, extra: np.ndarray | None,
              bone: str, amount: np.ndarray) -> None:  # fmt: skip
        weight = size * np.exp(-(((surface.arc - centre) / width) ** 2)) * (surface.tube == tube)
        if extra is not None:
            weight *= extra
        weight[weight < 0.01 * size] = 0.0
        chosen = np.flatnonzero(weight)
        span = slice(int(chosen[0]), int(chosen[-1]) + 1)
        offsets = surface.normals[span] * weight[span, None]
        shapes.append(_Corrective(span, offsets, index[bone], amount))

    shape(0, (main[7] + main[8]) / 2, 0.22, 0.012, None, "spine2", motion.breath)
    belly = np.maximum(0.0, -surface.normals[:, 1]) ** 1.5
    shape(0, (main[6] + main[7]) / 2, 0.3, 0.01, belly, "spine1", motion.jiggle)
    names = [f"{upper}_{side}" for upper in ("thigh", "upperarm") for side, _ in SIDES]
    for tube, name in enumerate(names, start=1):
        knots = surface.lines[tube].knot_arc
        swell = _sigmoid(10 * (motion.flex[name] - 0.25))
        shape(tube, (knots[1] + knots[2]) / 2, 0.35 * (knots[2] - knots[1]), 0.008, None, name,
              swell)  # fmt: skip
    return shapes


# ------------------------------------------------------------------------------------------
# making and writing


def make(
    kind: str, vertices: int, frames: int, seed: int = 1, noise: float = NOISE_SIZE
) -> Sequence:
    """The generator of a sequence of ``kind`` (``cloth`` or ``body``): its faces at once, its
    frames on demand by range."""
    if kind not in KINDS:
        raise ValueError(f"kind must be one of {', '.join(KINDS)}, not {kind!r}")
    if vertices < MIN_VERTICES[kind]:
        raise ValueError(f"a {kind} needs at least {MIN_VERTICES[kind]} vertices, not {vertices}")
    if frames < 1:
        raise ValueError(f"frames must be at least 1, not {frames}")
    if kind == "cloth":
        return Cloth(vertices, frames, seed, noise)
    return Body(vertices, frames, seed, noise)


def block_frames(vertices: int) -> int:
    """Frames made at once: a fixed function of the vertex count, so that the bytes do not
    depend on anything but the arguments."""
    return max(1, BLOCK_VALUES // (3 * vertices))


def blocks(sequence: Sequence) -> Iterator[tuple[int, np.ndarray]]:
    """(first frame, float32 frames) block by block."""
    step = block_frames(sequence.vertex_count)
    for start in range(0, sequence.frame_count, step):
        stop = min(start + step, sequence.frame_count)
        yield start, sequence.frames(start, stop).astype("<f4")


def generate(kind: str, vertices: int, frames: int, seed: int = 1) -> tuple[np.ndarray, np.ndarray]:
    """The whole sequence in memory, for small sizes: float32 positions (F, K, 3), faces."""
    sequence = make(kind, vertices, frames, seed)
    out = np.empty((frames, vertices, 3), dtype=np.float32)
    for start, block in blocks(sequence):
        out[start : start + len(block)] = block
    return out, sequence.faces


def faces_path(output: Path) -> Path:
    """Where the faces go beside ``OUT.npy``: ``OUT.faces.obj``."""
    return output.with_suffix(".faces.obj")


def _npy_header(sequence: Sequence) -> dict[str, object]:
    shape = (sequence.frame_count, sequence.vertex_count, 3)
    return {"descr": "<f4", "fortran_order": False, "shape": shape}


def _write_positions(handle: BinaryIO, sequence: Sequence, report: Callable[[int], None]) -> None:
    """The positions as an .npy: its header, then the frames block by block."""
    np.lib.format.write_array_header_1_0(handle, _npy_header(sequence))
    for start, block in blocks(sequence):
        handle.write(block.data)  # C-contiguous: astype made it
        report(start + len(block))


def _write_npz(handle: BinaryIO, sequence: Sequence, report: Callable[[int], None]) -> None:
    """An uncompressed .npz with ``V`` (the positions, streamed) and ``F`` (the faces)."""
    with zipfile.ZipFile(handle, "w", zipfile.ZIP_STORED, allowZip64=True) as archive:
        with archive.open("V.npy", "w", force_zip64=True) as member:
            _write_positions(member, sequence, report)  # type: ignore[arg-type]
        with archive.open("F.npy", "w") as member:
            np.lib.format.write_array(member, sequence.faces.astype(np.int32))


def _write_obj(handle: BinaryIO, positions: np.ndarray, faces: np.ndarray, title: str) -> None:
    """Frame 0 and the faces as Wavefront OBJ (1-based indices)."""
    handle.write(f"# {title}\n".encode())
    np.savetxt(handle, positions, fmt="v %.8g %.8g %.8g")
    np.savetxt(handle, faces + 1, fmt="f %d %d %d")


def write(
    output: Path,
    sequence: Sequence,
    *,
    npz: bool = False,
    force: bool = False,
    progress: Callable[[int], None] | None = None,
    title: str = "tools.generate.sequence",
) -> list[Path]:
    """Write ``sequence`` to ``output`` (.npy and ``OUT.faces.obj``, or with ``npz`` one
    .npz), atomically, never replacing a file unless ``force``; returns the paths written.

    Every output is checked before any work, so an existing file stops it at once.
    """
    report = progress or (lambda _: None)
    paths = [output] if npz else [output, faces_path(output)]
    refuse_existing(paths, force)
    writer = _write_npz if npz else _write_positions
    write_atomic(output, lambda handle: writer(handle, sequence, report), overwrite=force)
    if not npz:
        first = sequence.frames(0, 1)[0].astype(np.float32)
        write_atomic(
            paths[1],
            lambda handle: _write_obj(handle, first, sequence.faces, title),
            overwrite=force,
        )
    return paths


def main(argv: list[str] | None = None) -> int:
    """Make and write one sequence; returns the exit status."""
    parser = argparse.ArgumentParser(
        prog="python -m tools.generate.sequence", description=__doc__.splitlines()[0]
    )
    parser.add_argument("--kind", choices=KINDS, default="body", help="what moves (default body)")
    parser.add_argument("--vertices", type=int, default=200_000, help="K (default 200000)")
    parser.add_argument("--frames", type=int, default=2_000, help="F (default 2000)")
    parser.add_argument("-o", "--output", type=Path, required=True, help="OUT.npy or OUT.npz")
    parser.add_argument("--seed", type=int, default=1, help="the same seed, the same bytes")
    parser.add_argument(
        "--noise",
        type=float,
        default=NOISE_SIZE,
        help=f"each vertex's own jitter, relative to the model's size (default {NOISE_SIZE:g})",
    )
    parser.add_argument("--npz", action="store_true", help="write an .npz (V and F) instead")
    parser.add_argument("--force", action="store_true", help="replace existing outputs")
    parser.add_argument("--quiet", action="store_true", help="no progress on stderr")
    args = parser.parse_args(argv)
    npz = args.npz or args.output.suffix == ".npz"
    output = args.output.with_suffix(".npz") if npz else args.output
    if not npz and output.suffix != ".npy":
        parser.error("the output must end in .npy (or .npz, or give --npz)")
    start = time.perf_counter()
    try:
        sequence = make(args.kind, args.vertices, args.frames, args.seed, args.noise)
    except ValueError as error:
        parser.error(str(error))
    total_bytes = args.frames * args.vertices * 12
    shown = [-1]

    def progress(done: int) -> None:
        tenth = 10 * done // args.frames
        if not args.quiet and tenth != shown[0]:
            shown[0] = tenth
            elapsed = time.perf_counter() - start
            print(f"  {done}/{args.frames} frames, {elapsed:.0f} s", file=sys.stderr, flush=True)

    command = common.command("tools.generate.sequence", argv)
    try:
        paths = write(output, sequence, npz=npz, force=args.force, progress=progress, title=command)
    except (FileExistsError, FileNotFoundError, NotADirectoryError) as error:
        print(f"error: {error}", file=sys.stderr)
        return 1
    seconds = time.perf_counter() - start
    print(f"machine: {common.machine()}")
    print(f"command: {command}")
    print(
        f"wrote {', '.join(map(str, paths))}: {args.kind}, {args.frames} frames x "
        f"{args.vertices} vertices, {len(sequence.faces)} triangles, "
        f"{total_bytes / 1e9:.2f} GB as float32"
    )
    print(
        f"time {seconds:.1f} s ({total_bytes / 1e6 / seconds:.0f} MB/s), peak resident memory "
        f"{common.lifetime_peak_rss_mib():.0f} MiB"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
