// U1's mesh prediction (spec/FORMAT.md §6.2): the mesh parents (predictor 1) and the mesh mean
// (predictor 2, version 1.2), both from the breadth-first forest of the face edges.
//
//   const topo = meshTopology(faces, M, n, K);           // once per file (FACE is shared)
//   const q = restoreMeshColumn(stream, c * K, predictor, topo, "section 'U1' column c", push);
//   const order = meshCodingOrder(topo);                 // U1's adaptive coding order (§6.14)
//
// No DOM: runs in node and in browsers. Every restored value is the exact integer the spec
// defines (float64 where the bounds below prove it exact, BigInt otherwise).

import { formatError } from './errors.js';

const EXACT = 2 ** 53; // float64 holds every integer of magnitude below this
const MEAN_RANGE = 2 ** 32; // §6.2: a predictor-2 value lies in −2^32..2^32 (R32-predictor)
const MAX_DEPTHS = 2048; // §6.2: predictor 2 only on a forest of at most 2048 depths
// The fewest sources c for which one vertex's mean is no longer computed in float64 (BigInt
// instead): push 2's terms are within 10·2^32, any other push's within 24·2^32; see restoreMean.
const FLOAT_SOURCES = 2 ** 17;
const PUSHED_FLOAT_SOURCES = 2 ** 16;
/** Predictor 2's push where a section gives none (§6.2): a third (2/6) of a step. */
export const MEAN_PUSH = 2;

/**
 * The mesh mean's plan (meanPlan); `sources` is the most sources of any vertex.
 * @typedef {{restore: Int32Array, first: Int32Array, source: Int32Array, anchor: Int32Array,
 *   sources: number}} MeanPlan
 */

/**
 * The face edges' structure (meshTopology).
 * @typedef {{K: number, start: Int32Array, neighbours: Int32Array, parent: Int32Array,
 *   order: Int32Array, depth: Int32Array, rank: Int32Array, maxDepth: number,
 *   plan: MeanPlan | null}} Topology
 */

/**
 * The structure of the face edges that U1's prediction needs (§6.2).
 * @param {Int32Array} faces M*n vertex indices, row-major, −1 padded (already valid: R33, R34)
 * @param {number} M faces
 * @param {number} n face width
 * @param {number} K vertices
 * @returns {Topology}
 *   `neighbours[start[v] .. start[v+1]−1]` is N(v), ascending and without repeats; `order` lists
 *   every vertex in the order the walk reaches it (a parent before its children); the predictor-2
 *   plan is built on first use.
 */
export function meshTopology(faces, M, n, K) {
  const { start, neighbours } = neighbourLists(faces, M, n, K);
  const parent = new Int32Array(K).fill(-1);
  const depth = new Int32Array(K);
  const rank = new Int32Array(K);
  const order = new Int32Array(K); // the reach order, which is also the queue of every tree
  const reached = new Uint8Array(K);
  const atDepth = new Int32Array(K + 1); // vertices reached so far at each depth (for rank)
  let tail = 0;
  let maxDepth = 0;
  for (let s = 0; s < K; s++) {
    if (reached[s]) continue;
    reached[s] = 1; // a root: depth 0
    rank[s] = atDepth[0]++;
    let head = tail;
    order[tail++] = s;
    while (head < tail) {
      const u = order[head++];
      const d = depth[u] + 1;
      for (let e = start[u], end = start[u + 1]; e < end; e++) {
        const w = neighbours[e];
        if (reached[w]) continue;
        reached[w] = 1;
        parent[w] = u;
        depth[w] = d;
        rank[w] = atDepth[d]++;
        order[tail++] = w;
        if (d > maxDepth) maxDepth = d;
      }
    }
  }
  return { K, start, neighbours, parent, order, depth, rank, maxDepth, plan: null };
}

/**
 * N(v) for every vertex as compressed lists: the edges of §6.2 (each corner to the next real
 * corner, the last real corner back to corner 0), both directions, bucketed by vertex, each
 * bucket sorted (insertion sort for the short lists of a surface, the native sort for long ones,
 * so no degree makes it quadratic) and its repeats dropped.
 * @param {Int32Array} faces
 * @param {number} M
 * @param {number} n
 * @param {number} K
 */
function neighbourLists(faces, M, n, K) {
  const start = new Int32Array(K + 1);
  for (let r = 0; r < M; r++) {
    const row = r * n;
    for (let j = 0; j < n; j++) {
      const a = faces[row + j];
      if (a < 0) continue;
      const b = j + 1 < n && faces[row + j + 1] >= 0 ? faces[row + j + 1] : faces[row];
      if (b < 0 || a === b) continue; // a = b: a degenerate corner, ignored
      start[a + 1]++;
      start[b + 1]++;
    }
  }
  for (let v = 0; v < K; v++) start[v + 1] += start[v];
  const sorted = new Int32Array(start[K]);
  const fill = start.slice(0, K);
  for (let r = 0; r < M; r++) {
    const row = r * n;
    for (let j = 0; j < n; j++) {
      const a = faces[row + j];
      if (a < 0) continue;
      const b = j + 1 < n && faces[row + j + 1] >= 0 ? faces[row + j + 1] : faces[row];
      if (b < 0 || a === b) continue;
      sorted[fill[a]++] = b;
      sorted[fill[b]++] = a;
    }
  }
  let out = 0;
  let from = 0;
  for (let v = 0; v < K; v++) {
    const end = start[v + 1];
    if (end - from > 16) {
      sorted.subarray(from, end).sort();
    } else {
      for (let t = from + 1; t < end; t++) {
        const w = sorted[t];
        let u = t - 1;
        while (u >= from && sorted[u] > w) {
          sorted[u + 1] = sorted[u];
          u--;
        }
        sorted[u + 1] = w;
      }
    }
    start[v] = out;
    let previous = -1;
    for (let t = from; t < end; t++) {
      const w = sorted[t];
      if (w !== previous) sorted[out++] = w;
      previous = w;
    }
    from = end;
  }
  start[K] = out;
  return { start, neighbours: sorted.subarray(0, out) };
}

/**
 * The mesh mean's plan (§6.2 predictor 2), built once per topology: the vertices of depth ≥ 1
 * in restoring order (by depth, then phase = rank mod 8), and for each its sources S(v) and their
 * anchors as compressed lists in that same order, so each column is one pass over flat arrays.
 * @param {Topology} topo
 * @returns {MeanPlan}
 */
function meanPlan(topo) {
  if (topo.plan !== null) return topo.plan;
  const { K, start, neighbours, parent, order, depth, rank, maxDepth } = topo;
  const buckets = maxDepth * 8; // key (depth − 1)·8 + phase for depth ≥ 1
  const slot = new Int32Array(buckets + 1);
  let rows = 0;
  for (let v = 0; v < K; v++) {
    if (depth[v] > 0) {
      slot[(depth[v] - 1) * 8 + (rank[v] & 7) + 1]++;
      rows++;
    }
  }
  for (let b = 0; b < buckets; b++) slot[b + 1] += slot[b];
  const restore = new Int32Array(rows);
  for (let t = 0; t < K; t++) {
    const v = order[t]; // any order within a bucket is allowed; the reach order is as good as any
    if (depth[v] > 0) restore[slot[(depth[v] - 1) * 8 + (rank[v] & 7)]++] = v;
  }
  let total = 0;
  const first = new Int32Array(rows + 1);
  for (let i = 0; i < rows; i++) {
    const v = restore[i];
    const d = depth[v];
    const phase = rank[v] & 7;
    let c = 0;
    for (let e = start[v], end = start[v + 1]; e < end; e++) {
      const w = neighbours[e];
      if (depth[w] === d - 1 || (depth[w] === d && (rank[w] & 7) < phase)) c++;
    }
    total += c;
    first[i + 1] = total;
  }
  const source = new Int32Array(total);
  const anchor = new Int32Array(total);
  let most = 0;
  for (let i = 0, t = 0; i < rows; i++) {
    const v = restore[i];
    const d = depth[v];
    const phase = rank[v] & 7;
    for (let e = start[v], end = start[v + 1]; e < end; e++) {
      const w = neighbours[e];
      if (depth[w] === d - 1) {
        source[t] = w;
        anchor[t++] = parent[w] >= 0 ? parent[w] : w;
      } else if (depth[w] === d && (rank[w] & 7) < phase) {
        source[t] = w;
        anchor[t++] = w;
      }
    }
    most = Math.max(most, first[i + 1] - first[i]);
  }
  topo.plan = { restore, first, source, anchor, sources: most };
  return topo.plan;
}

/**
 * U1's adaptive coding order (§6.14): the depth-0 vertices (roots and vertices on no face) in
 * ascending index, without earlier neighbours, then predictor 2's restoring order (by depth, then
 * phase, then the walk's reach order), each vertex with its sources S(v). It holds whatever the
 * mesh's depth (predictor 2's depth limit is not this order's), and shares predictor 2's plan,
 * built once per topology.
 * @param {Topology} topo
 * @returns {import('./adaptive.js').CodingOrder}
 */
export function meshCodingOrder(topo) {
  const { K, depth } = topo;
  const { restore, first, source } = meanPlan(topo);
  const roots = K - restore.length;
  const order = new Int32Array(K);
  for (let v = 0, j = 0; v < K; v++) if (depth[v] === 0) order[j++] = v;
  order.set(restore, roots);
  const ends = new Int32Array(K + 1); // a root's sources: none
  ends.set(first, roots);
  return { order, ends, source };
}

/**
 * Restores one predicted U1 column (§6.2) from its residuals.
 * @param {Int32Array} residuals the section's decoded stream
 * @param {number} offset where the column starts in it (column-major: c·K)
 * @param {number} predictor 1 (mesh parents) or 2 (mesh mean)
 * @param {Topology} topo meshTopology(...) of the file's faces
 * @param {string} where the section and column, for messages
 * @param {number} [push] predictor 2's push a, 0..9 (version 1.6's `mean_push`, already checked:
 *   R32); MEAN_PUSH when the section gives none
 * @returns {Float64Array} K values: float64(q), exact while |q| <= 2^53, else rounded to nearest
 *   (ties to even) from the exact integer, as §6.3's dequantization needs
 * @throws {TkcError} R32-predictor: predictor 2 on a forest deeper than 2048 depths, or a restored
 *   value outside −2^32..2^32
 */
export function restoreMeshColumn(residuals, offset, predictor, topo, where, push = MEAN_PUSH) {
  if (predictor === 1) return restoreParents(residuals, offset, topo);
  if (predictor !== 2) throw formatError('R32-predictor', `${where}: predictor ${predictor} is not a mesh predictor`);
  if (topo.maxDepth >= MAX_DEPTHS) {
    throw formatError(
      'R32-predictor',
      `${where}: predictor 2 needs a forest of at most ${MAX_DEPTHS} depths; this mesh has ${topo.maxDepth + 1}`,
    );
  }
  return restoreMean(residuals, offset, topo, meanPlan(topo), push, where);
}

/**
 * Predictor 1: q[v] = r[v] + q[parent[v]], in the reach order (a parent before its child).
 * @param {Int32Array} residuals
 * @param {number} offset
 * @param {Topology} topo
 */
function restoreParents(residuals, offset, topo) {
  const { K, order, parent } = topo;
  const q = new Float64Array(K);
  let exact = true;
  for (let t = 0; t < K; t++) {
    const v = order[t];
    const p = parent[v];
    const x = p < 0 ? residuals[offset + v] : residuals[offset + v] + q[p];
    // Exact while every value so far is below 2^53 in magnitude (an int32 plus such a value is
    // at most 2^53 + 2^31, and rounding never takes a value of magnitude ≥ 2^53 below it, so
    // the first inexact sum is caught here).
    if (x >= EXACT || x <= -EXACT) exact = false;
    q[v] = x;
  }
  if (exact) return q;
  // A crafted column (depths of int32 steps): 64-bit sums, then Number() rounds to nearest, ties
  // to even. K < 2^32 vertices of int32 residuals keep every sum below 2^63.
  const big = new BigInt64Array(K);
  for (let t = 0; t < K; t++) {
    const v = order[t];
    const p = parent[v];
    big[v] = p < 0 ? BigInt(residuals[offset + v]) : BigInt(residuals[offset + v]) + big[p];
    q[v] = Number(big[v]);
  }
  return q;
}

/**
 * Predictor 2, the mesh mean with push a: q[v] = r[v] + floor((2V + 6c) / (12c)) with
 * V = Σ_{w in S(v)} ((6 + a)·q[w] − a·q[anchor(w)]), restored by depth and phase, each value
 * checked against ±2^32 as soon as it is restored (so every source and anchor read is within
 * ±2^32). Push 2 (a file without `mean_push`) has V = 2U, U = Σ (4·q[w] − q[anchor(w)]), and is
 * computed as floor((2U + 3c) / (6c)), exactly as before format 1.6.
 *
 * Why float64 is exact here: each term of U is an integer of magnitude at most 5·2^32, and each
 * of V at most (6 + 2a)·2^32 <= 24·2^32. So for push 2 and c < 2^17 sources every partial sum of
 * U and 2U + 3c is an integer below 10·2^49 + 3·2^17 < 2^53, and for any other push and c < 2^16
 * every partial sum of V and V + 3c is below 24·2^48 + 3·2^16 < 2^53: exact. The quotient (2U + 3c)/(6c), resp. (V + 3c)/(6c) = (2V + 6c)/(12c), is at most
 * 2^33, resp. 2^34 + 1/2, in magnitude, where half an ulp is at most 2^−20, resp. 2^−19, while a
 * quotient that is not an integer is at least 1/(6c) > 2^−20, resp. > 2^−19, away from every
 * integer; so the correctly rounded division never crosses an integer and Math.floor of it is the
 * exact floor. Vertices with more sources use BigInt (bigMean): only a crafted mesh has them.
 * @param {Int32Array} residuals
 * @param {number} offset
 * @param {Topology} topo
 * @param {MeanPlan} plan
 * @param {number} push
 * @param {string} where
 */
function restoreMean(residuals, offset, topo, plan, push, where) {
  const { K } = topo;
  const { restore, first, source, anchor, sources } = plan;
  const q = new Float64Array(K);
  for (let v = 0; v < K; v++) q[v] = residuals[offset + v]; // depth 0: q = r (others overwritten)
  const pushed = push !== MEAN_PUSH;
  const bigFrom = pushed ? PUSHED_FLOAT_SOURCES : FLOAT_SOURCES;
  const big = sources >= bigFrom;
  const weight = 6 + push; // V's weights: (6 + a) at a source, −a at its anchor
  const rows = restore.length;
  for (let i = 0; i < rows; i++) {
    const s0 = first[i];
    const s1 = first[i + 1];
    const c = s1 - s0;
    let pred;
    if (big && c >= bigFrom) {
      pred = bigMean(q, source, anchor, s0, s1, push);
    } else if (!pushed) {
      let u = 0; // today's path, unchanged: U and (2U + 3c)/(6c)
      for (let t = s0; t < s1; t++) u += 4 * q[source[t]] - q[anchor[t]];
      pred = Math.floor((2 * u + 3 * c) / (6 * c));
    } else {
      let sum = 0; // V, then (V + 3c)/(6c)
      for (let t = s0; t < s1; t++) sum += weight * q[source[t]] - push * q[anchor[t]];
      pred = Math.floor((sum + 3 * c) / (6 * c));
    }
    const v = restore[i];
    const x = q[v] + pred; // q[v] still holds r[v]
    if (x > MEAN_RANGE || x < -MEAN_RANGE) {
      throw formatError(
        'R32-predictor',
        `${where}: vertex ${v} restores to ${x} with predictor 2, outside −2^32..2^32`,
      );
    }
    q[v] = x;
  }
  return q;
}

/**
 * The prediction of one vertex with very many sources, in BigInt: floor((2V + 6c) / (12c)) as
 * floor((V + 3c) / (6c)), floor division toward −∞.
 * @param {Float64Array} q
 * @param {Int32Array} source
 * @param {Int32Array} anchor
 * @param {number} s0
 * @param {number} s1
 * @param {number} push
 */
function bigMean(q, source, anchor, s0, s1, push) {
  let sum = 0n;
  // each term is an integer below 24·2^32 in magnitude: exact in float64
  for (let t = s0; t < s1; t++) sum += BigInt((6 + push) * q[source[t]] - push * q[anchor[t]]);
  const c = BigInt(s1 - s0);
  const numerator = sum + 3n * c;
  const denominator = 6n * c;
  let quotient = numerator / denominator; // truncates toward zero
  if (numerator % denominator !== 0n && numerator < 0n) quotient -= 1n;
  return Number(quotient);
}
