// `npm test` (node --test): predictor 2's push (spec/FORMAT.md §6.2, format 1.6's `mean_push`) in
// topology.js's restoreMeshColumn, against a BigInt transcription of the spec's formula written
// here from the walk's depth, rank and parents (not from the decoder's plan): on a grid with
// values of magnitude 2^31 and more (within ±2^32), every push 0..9 restores the integers its residuals came
// from, push 2 is the same whether given or not, and a value pushed out of the range is R32.

import assert from 'node:assert/strict';
import { test } from 'node:test';
import { TkcError } from '../../tuckercodec/web/tkc/errors.js';
import { meshTopology, restoreMeshColumn } from '../../tuckercodec/web/tkc/topology.js';

const SIDE = 12;

/** A SIDE × SIDE grid of quads, one of them a triangle, as a face table (n = 4, −1 padded). */
function grid() {
  const faces = [];
  for (let i = 0; i + 1 < SIDE; i++) {
    for (let j = 0; j + 1 < SIDE; j++) {
      const a = i * SIDE + j;
      faces.push(a, a + 1, a + SIDE + 1, i === 3 && j === 5 ? -1 : a + SIDE);
    }
  }
  const M = faces.length / 4;
  return meshTopology(Int32Array.from(faces), M, 4, SIDE * SIDE);
}

/** floor(x / y) for BigInt, y > 0. */
function floorDiv(x, y) {
  const q = x / y;
  return x % y !== 0n && x < 0n ? q - 1n : q;
}

/**
 * §6.2's residuals of one column q (BigInt values) with push a: S(v) and anchors from the walk's
 * depth, rank (phase = rank mod 8) and parents; V = Σ ((6 + a)·q[w] − a·q[anchor(w)]),
 * pred = floor((2V + 6c) / (12c)). Every q is known, so the order does not matter here.
 */
function residualsOf(topo, q, a) {
  const { K, start, neighbours, parent, depth, rank } = topo;
  const out = new Int32Array(K);
  for (let v = 0; v < K; v++) {
    let V = 0n;
    let c = 0n;
    for (let e = start[v]; e < start[v + 1] && depth[v] > 0; e++) {
      const w = neighbours[e];
      const up = depth[w] === depth[v] - 1;
      if (!up && !(depth[w] === depth[v] && (rank[w] & 7) < (rank[v] & 7))) continue;
      const anchor = up && parent[w] >= 0 ? parent[w] : w;
      V += BigInt(6 + a) * q[w] - BigInt(a) * q[anchor];
      c++;
    }
    const r = depth[v] === 0 ? q[v] : q[v] - floorDiv(2n * V + 6n * c, 12n * c);
    assert.ok(r >= -(2n ** 31n) && r < 2n ** 31n, 'the test values keep residuals in int32');
    out[v] = Number(r);
  }
  return out;
}

/** Values from near 2^31 up to near 1.3·2^31 along a slope (large terms, int32 residuals), seeded. */
function column(K, seed) {
  let x = seed;
  const q = [];
  for (let v = 0; v < K; v++) {
    x = (x * 1103515245 + 12345) % 2147483648;
    q.push(BigInt(2 ** 31 - 2 ** 21 + v * 2 ** 22 - (x % 2 ** 20)) * (seed % 2 ? -1n : 1n));
  }
  return q;
}

test('every push restores the integers its residuals came from', () => {
  const topo = grid();
  for (let a = 0; a <= 9; a++) {
    for (const seed of [1, 2, 7]) {
      const q = column(topo.K, seed + a);
      const restored = restoreMeshColumn(residualsOf(topo, q, a), 0, 2, topo, `push ${a}`, a);
      assert.deepEqual(Array.from(restored), q.map(Number), `push ${a}, seed ${seed}`);
    }
  }
});

test('push 2 given is push 2 absent', () => {
  const topo = grid();
  const residuals = residualsOf(topo, column(topo.K, 4), 2);
  assert.deepEqual(restoreMeshColumn(residuals, 0, 2, topo, 'given', 2), restoreMeshColumn(residuals, 0, 2, topo, 'absent'));
});

test('a value pushed out of ±2^32 is R32-predictor', () => {
  const topo = grid();
  const residuals = residualsOf(topo, column(topo.K, 6), 9);
  residuals[topo.order[topo.K - 1]] = 2 ** 31 - 1; // the last vertex reached (depth ≥ 1): past 2^32
  assert.throws(
    () => restoreMeshColumn(residuals, 0, 2, topo, 'out', 9),
    (error) => error instanceof TkcError && error.rule === 'R32-predictor',
  );
});
