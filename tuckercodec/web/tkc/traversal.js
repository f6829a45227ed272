// Codec `faces-traverse` (spec/FORMAT.md §6.8, version 1.2): the faces coded by a walk over
// them. Four integer streams (ops, degrees, vertices, references) drive the walk; the decoded
// table lists the faces in walk order. Every failure is R39-traversal (R30/R29 for a stream's
// planes and zstd frame, R21 for the bytes the streams decompress to), checked in the order of
// §5 step 15: the stream counts' bounds of §6.8 and the limit before any stream is decompressed.
//
// Linear in every input: the boundary is a hash table of directed edges (random multipliers, so
// no file can aim at collisions), into(v) and out(v) are stacks with lazy deletion (an entry is
// live while its edge is present and entered the boundary at that entry), the gates a stack.
// Its memory grows with the values read: nothing is sized by K, M or a declared count.
//
// With `coder` 1 (format 1.6, a file with flag bit 3) each stream is one column of §6.14's
// adaptive coder (planes 0), and the vertices stream holds each NEW vertex's signed rank among
// the vertices not seen yet. The ranks' running sum is u(w), the unseen vertices below w, so
// they are turned into gaps (w − last − 1) before the walk, by a Fenwick tree over the placed
// vertices (UnseenVertices), and the walk is the same for both coders.
//
// With `ranks` 1 (format 1.9, a file with flag bit 6; `coder` 1 only) the vertices stream is a
// uniform stream of each NEW vertex's place among the vertices not seen yet (decodeUniform): the
// places are those running sums themselves, so their differences are the ranks, and they take
// the same way to the walk.

import { adaptiveError, decodeAdaptive, decodeUniform } from './adaptive.js';
import { formatError, limitError } from './errors.js';
import { DEFAULT_LIMITS } from './limits.js';
import { describe, isInt } from './msgpack.js';
import { decodeIntStream } from './streams.js';

/** @typedef {import('./msgpack.js').MsgValue} MsgValue */
/** @typedef {import('./limits.js').Limits} Limits */

const WHERE = "section 'FACE' (faces-traverse)";
const STREAMS = ['ops', 'degrees', 'vertices', 'references'];
const NEW = 0;
const PREV = 1;
const NEXT = 2;
const FAR = 3;
const ZSTD = 0; // the coder values (§6.8, §6.14): §6.1's byte planes ...
const ADAPTIVE = 1; // ... or one adaptive column per stream
const ADAPTIVE_PLANES = 4; // with coder 1 every integer is a 32-bit one
const RANKS_ADAPTIVE = 0; // the ranks values (§6.8, version 1.9): NEW vertices as adaptive ranks ...
const RANKS_UNIFORM = 1; // ... or as places among the unseen in a uniform stream
const VERTICES = 2; // the vertices stream's place among the four
/** The most vertices `ranks` 1 takes: its places are 32-bit integers. */
const MAX_UNIFORM_TOTAL = 2 ** 31;

/** @param {string} message */
function fail(message) {
  return formatError('R39-traversal', `${WHERE}: ${message}`);
}

/**
 * An int ≥ 0 as the msgpack reader returns it (a number, or a BigInt beyond 2^53).
 * @param {unknown} value
 * @returns {value is number | bigint}
 */
function isNonNegativeInt(value) {
  return isInt(value) && value >= 0;
}

/**
 * Decodes a FACE section coded with faces-traverse.
 * @param {Map<string, MsgValue>} entry the section-table entry (codec parameters corner_order, streams)
 * @param {Uint8Array} payload the section's bytes, CRC already checked
 * @param {number} K vertices
 * @param {number} M faces (the checked `shape`)
 * @param {number} n face width
 * @param {Limits} [limits] the decoder's limits (§7): max_section_bytes bounds the streams
 * @param {boolean} [adaptive] the file sets flag bit 3 (format 1.6): `coder` may be 1
 * @param {boolean} [uniform] the file sets flag bit 6 (format 1.9): `ranks` is read, and may be 1
 * @returns {Int32Array} M*n vertex indices, row-major, in walk order, −1 padded
 * @throws {TkcError} R39-traversal, R30-planes, R21-header-limit, R29-zstd-content-size or
 *   R46-adaptive-stream
 */
export function decodeTraverse(entry, payload, K, M, n, limits = DEFAULT_LIMITS, adaptive = false, uniform = false) {
  const cornerOrder = entry.get('corner_order');
  if (cornerOrder !== 0 && cornerOrder !== 1) {
    throw fail(`"corner_order" is ${cornerOrder === undefined ? 'missing' : describe(cornerOrder)}, not 0 or 1`);
  }
  const coder = readCoder(entry, adaptive);
  // without flag bit 6, `ranks` is an unknown parameter (§3): ignored, as before 1.9
  const ranks = uniform ? readRanks(entry, coder, K) : RANKS_ADAPTIVE;
  const table = streamTable(entry.get('streams'), K, M, n);
  let total = 0;
  for (const item of table) total += Number(item[2]); // a BigInt length is past any payload: the sum cannot match
  if (total !== payload.length) {
    const lengths = table.map((item) => String(item[2])).join(' + ');
    throw fail(`the stream lengths ${lengths} add up to ${total}, not the payload's ${payload.length} bytes`);
  }
  for (let s = 0; s < 4; s++) {
    const planes = table[s][1];
    if (coder === ADAPTIVE ? planes !== 0 : !(planes >= 1 && planes <= 4)) {
      const allowed = coder === ADAPTIVE ? '0 (coder 1)' : 'an int in 1..4';
      throw formatError('R30-planes', `${WHERE} stream ${s} (${STREAMS[s]}): "planes" is ${planes}, not ${allowed}`);
    }
  }
  // the bytes the streams decompress to, before any is: counts are below 2^36 and planes 1..4
  // (with coder 1, 32-bit integers: as 4 planes)
  const raw = table.reduce((sum, [count, planes]) => sum + Number(count) * (coder === ADAPTIVE ? ADAPTIVE_PLANES : Number(planes)), 0);
  if (raw > limits.max_section_bytes) {
    throw limitError('R21-header-limit', `${WHERE}: the streams decompress to ${raw} bytes, max_section_bytes = ${limits.max_section_bytes}`);
  }
  const streams = [];
  let at = 0;
  for (let s = 0; s < 4; s++) {
    const [count, planes, length] = table[s];
    const where = `${WHERE} stream ${s} (${STREAMS[s]})`;
    const part = payload.subarray(at, at + Number(length));
    if (s === VERTICES && ranks === RANKS_UNIFORM) {
      // the places; §6.14's bound on the count is decodeUniform's first check, before it allocates
      streams.push(differences(decodeUniform(part, Number(count), K, where)));
    } else if (coder === ADAPTIVE) {
      // §6.14's bound on the count is decodeAdaptive's first check, before it allocates
      streams.push(decodeAdaptive(part, Number(count), 1, null, ADAPTIVE_PLANES, where));
    } else {
      streams.push(decodeIntStream(part, Number(count), Number(planes), where));
    }
    at += Number(length);
  }
  if (coder === ADAPTIVE) streams[2] = gapsFromRanks(streams[2], K);
  return walk(streams, cornerOrder, K, M, n);
}

/**
 * The section's `coder` (§6.8): absent or 0, §6.1's zstd planes; 1, adaptive streams with the
 * NEW vertices as ranks, only in a file with flag bit 3; anything else R46.
 * @param {Map<string, MsgValue>} entry
 * @param {boolean} adaptive
 */
function readCoder(entry, adaptive) {
  const coder = entry.get('coder');
  if (coder === undefined || coder === ZSTD) return ZSTD;
  if (coder === ADAPTIVE && adaptive) return ADAPTIVE;
  const allowed = adaptive ? '0 or 1' : '0 (1 needs preamble flag bit 3, format 1.6)';
  throw adaptiveError(WHERE, `"coder" is ${describe(coder)}; this section allows ${allowed}`);
}

/**
 * The section's `ranks` (§6.8), read in a file with flag bit 6 only: absent or 0, adaptive ranks;
 * 1, places in a uniform stream, only with `coder` 1 and K <= 2^31; anything else R46.
 * @param {Map<string, MsgValue>} entry
 * @param {number} coder
 * @param {number} K
 */
function readRanks(entry, coder, K) {
  const ranks = entry.get('ranks');
  if (ranks === undefined || ranks === RANKS_ADAPTIVE) return RANKS_ADAPTIVE;
  if (ranks !== RANKS_UNIFORM) throw adaptiveError(WHERE, `"ranks" is ${describe(ranks)}, not 0 or 1`);
  if (coder !== ADAPTIVE) throw adaptiveError(WHERE, '"ranks" 1 needs "coder" 1');
  if (K > MAX_UNIFORM_TOTAL) throw adaptiveError(WHERE, `"ranks" 1 takes at most ${MAX_UNIFORM_TOTAL} vertices, not ${K}`);
  return RANKS_UNIFORM;
}

/**
 * The ranks of places p (r_i = p_i − p_{i−1}, p_{−1} = 0), in place: places below 2^31 differ by
 * less, so each fits an int32.
 * @param {Int32Array} places
 * @returns {Int32Array}
 */
function differences(places) {
  for (let i = places.length - 1; i > 0; i--) places[i] -= places[i - 1];
  return places;
}

/**
 * The vertices placed so far among 0..K−1: a Fenwick tree of their counts, whose nodes are a
 * table where K is within a few times the vertices the stream can place, else a Map filled as
 * vertices are placed (K is only the header's claim and must not size an allocation).
 */
class UnseenVertices {
  /**
   * @param {number} K
   * @param {number} most the count of the vertices stream
   */
  constructor(K, most) {
    this.top = 1; // a power of two >= K, for the descent
    while (this.top < K) this.top *= 2;
    /** @type {Int32Array | null} */
    this.table = this.top <= 4 * most + 1024 ? new Int32Array(this.top + 1) : null;
    /** @type {Map<number, number>} */
    this.map = new Map();
  }

  /** @param {number} i */
  node(i) {
    return this.table !== null ? this.table[i] : this.map.get(i) ?? 0;
  }

  /**
   * Marks vertex v (unplaced, below K) as placed.
   * @param {number} v
   */
  place(v) {
    for (let i = v + 1; i <= this.top; i += lowestBit(i)) {
      if (this.table !== null) this.table[i]++;
      else this.map.set(i, (this.map.get(i) ?? 0) + 1);
    }
  }

  /**
   * The unplaced vertex with exactly t unplaced vertices below it (t below their count): the
   * binary descent of a Fenwick tree.
   * @param {number} t
   */
  unplaced(t) {
    let position = 0;
    for (let step = this.top; step >= 1; step /= 2) {
      const free = step - this.node(position + step); // unplaced vertices in position..position+step−1
      if (free <= t) {
        position += step;
        t -= free;
      }
    }
    return position;
  }
}

/**
 * The lowest set bit of i ≥ 1 (i & −i, which holds for 32-bit ints only; K may be larger).
 * @param {number} i
 */
function lowestBit(i) {
  return i < 2 ** 30 ? i & -i : Number(BigInt(i) & -BigInt(i));
}

/**
 * The vertices stream of coder 1 as the walk reads it: each rank r turned into its vertex w (the
 * unseen vertex with t unseen below it, t the ranks' running sum), then into the gap
 * w − last − 1. R39 at the first rank that names no unseen vertex.
 * @param {Int32Array} ranks
 * @param {number} K
 * @returns {Int32Array}
 */
function gapsFromRanks(ranks, K) {
  const placed = new UnseenVertices(K, ranks.length);
  const gaps = new Int32Array(ranks.length);
  let t = 0; // in 0..K−1 after each check, so within ±2^31 of it before: exact in a double
  let last = -1;
  for (let i = 0; i < ranks.length; i++) {
    t += ranks[i];
    if (!(t >= 0 && t < K - i)) throw fail(`new vertex rank ${ranks[i]} names no unseen vertex`);
    const w = placed.unplaced(t);
    placed.place(w);
    gaps[i] = w - last - 1;
    last = w;
  }
  return gaps;
}

/**
 * The `streams` table: four [count, planes, length] arrays of ints ≥ 0, whose counts keep the
 * four bounds of §6.8 in their order (every walk of M faces reads that many values and no more
 * than these allow), all checked before any stream is decompressed.
 * @param {MsgValue | undefined} table
 * @param {number} K
 * @param {number} M
 * @param {number} n
 * @returns {(number | bigint)[][]}
 */
function streamTable(table, K, M, n) {
  if (!Array.isArray(table) || table.length !== 4) {
    throw fail(`"streams" is ${table === undefined ? 'missing' : describe(table)}, not an array of 4 [count, planes, length] arrays`);
  }
  for (let s = 0; s < 4; s++) {
    const item = table[s];
    if (!Array.isArray(item) || item.length !== 3 || !item.every(isNonNegativeInt)) {
      throw fail(`stream ${s} (${STREAMS[s]}) is ${describe(item)}, not an array [count, planes, length] of 3 ints >= 0`);
    }
  }
  const checked = /** @type {(number | bigint)[][]} */ (table);
  const [o, g, v, r] = checked.map((item) => item[0]); // a count beyond 2^53 is a BigInt: compared, never added
  const corners = M * (g === 0 ? 3 : n); // the most corners the faces can have
  if (g !== 0 && g !== M) throw fail(`stream 1 (degrees) has count ${g}: one per face (${M}) or none`);
  if (!(o >= M && o <= 2 * corners)) throw fail(`stream 0 (ops) has count ${o}, outside the ${M}..${2 * corners} that ${M} faces read`);
  if (v > K) throw fail(`stream 2 (vertices) has count ${v}, more new vertices than the ${K} there are`);
  if (r > corners - Number(v)) throw fail(`streams 2 and 3 (vertices, references) have counts ${v} + ${r}, more than the ${corners} corners of the faces`);
  return checked;
}

/**
 * The vertices the walk has seen, numbered in the order seen: a hash table (open addressing,
 * random multiplier) from a vertex index to its number, sized by the count of *vertices* (every
 * seen vertex was a NEW), never by K, which is only the header's claim when FACE is decoded.
 */
class VertexTable {
  /** @param {number} most the count of the vertices stream */
  constructor(most) {
    this.bits = 1; // at most half full (up to 2^29 vertices: 1 << 31 is not a size)
    while (this.bits < 30 && 2 ** this.bits < 2 * most + 2) this.bits++;
    this.slots = new Int32Array(1 << this.bits).fill(-1);
    this.index = new Int32Array(most); // the vertex index of each number
    this.size = 0;
    this.m1 = (Math.random() * 2 ** 32) | 1;
    this.m2 = (Math.random() * 2 ** 32) | 0;
  }

  /**
   * The slot of vertex w, or of the empty one where it would go.
   * @param {number} w
   */
  slot(w) {
    const mask = (1 << this.bits) - 1;
    let h = (Math.imul(w, this.m1) + this.m2) >>> (32 - this.bits);
    while (this.slots[h] >= 0 && this.index[this.slots[h]] !== w) h = (h + 1) & mask;
    return h;
  }

  /**
   * Vertex w's number, or −1 if it is not seen.
   * @param {number} w
   */
  find(w) {
    return this.slots[this.slot(w)];
  }

  /**
   * Numbers vertex w, which is not seen (at most `most` times: one per value of *vertices*).
   * @param {number} w
   */
  add(w) {
    this.slots[this.slot(w)] = this.size;
    this.index[this.size] = w;
    return this.size++;
  }
}

/**
 * Directed edges of the boundary with their copy counts: open addressing keyed by (a, b) with
 * a multiply-add-shift hash of random multipliers. An edge keeps its id once created (count 0
 * when absent), so nothing is ever deleted from the table and ids stay valid for the stacks.
 */
class EdgeTable {
  constructor() {
    this.bits = 10;
    this.slots = new Int32Array(1 << this.bits).fill(-1);
    this.size = 0;
    this.from = new Int32Array(512);
    this.to = new Int32Array(512);
    this.count = new Int32Array(512);
    this.entered = new Int32Array(512); // the entry number of the edge's latest 0 → 1
    this.m1 = (Math.random() * 2 ** 32) | 1;
    this.m2 = (Math.random() * 2 ** 32) | 1;
    this.m3 = (Math.random() * 2 ** 32) | 0;
  }

  /**
   * @param {number} a
   * @param {number} b
   */
  slot(a, b) {
    return (Math.imul(a, this.m1) + Math.imul(b, this.m2) + this.m3) >>> (32 - this.bits);
  }

  /**
   * The edge a → b's id, or −1 if it never entered the boundary.
   * @param {number} a
   * @param {number} b
   */
  find(a, b) {
    const mask = (1 << this.bits) - 1;
    for (let h = this.slot(a, b); ; h = (h + 1) & mask) {
      const e = this.slots[h];
      if (e < 0 || (this.from[e] === a && this.to[e] === b)) return e;
    }
  }

  /**
   * The edge a → b's id, created (count 0) if new.
   * @param {number} a
   * @param {number} b
   */
  add(a, b) {
    const mask = (1 << this.bits) - 1;
    let h = this.slot(a, b);
    for (; ; h = (h + 1) & mask) {
      const e = this.slots[h];
      if (e < 0) break;
      if (this.from[e] === a && this.to[e] === b) return e;
    }
    const e = this.size++;
    if (e === this.from.length) {
      this.from = grow(this.from);
      this.to = grow(this.to);
      this.count = grow(this.count);
      this.entered = grow(this.entered);
    }
    this.from[e] = a;
    this.to[e] = b;
    this.count[e] = 0;
    this.slots[h] = e;
    if (2 * this.size > this.slots.length) this.rehash();
    return e;
  }

  rehash() {
    this.bits++;
    const mask = (1 << this.bits) - 1;
    this.slots = new Int32Array(1 << this.bits).fill(-1);
    for (let e = 0; e < this.size; e++) {
      let h = this.slot(this.from[e], this.to[e]);
      while (this.slots[h] >= 0) h = (h + 1) & mask;
      this.slots[h] = e;
    }
  }
}

/** @param {Int32Array} array */
function grow(array) {
  const bigger = new Int32Array(2 * array.length);
  bigger.set(array);
  return bigger;
}

/**
 * The walk of §6.8 over decoded streams. Vertices are numbered in the order seen (VertexTable):
 * the corners, edges, gates and lists hold those numbers, and every array grows with the values
 * read (the decoded faces too, up to M*n), so no declared count or K sizes an allocation.
 * @param {Int32Array[]} streams
 * @param {0 | 1} cornerOrder
 * @param {number} K
 * @param {number} M
 * @param {number} n
 */
function walk(streams, cornerOrder, K, M, n) {
  return new Walk(streams, cornerOrder, K, M, n).run();
}

/**
 * One walk's state: the streams and how far each is read, the vertices seen, the boundary (its
 * edges, the into/out stacks of their entries, the gates) and the faces decoded so far.
 */
class Walk {
  /**
   * @param {Int32Array[]} streams ops, degrees, vertices, references
   * @param {0 | 1} cornerOrder
   * @param {number} K
   * @param {number} M
   * @param {number} n
   */
  constructor(streams, cornerOrder, K, M, n) {
    this.ops = streams[0];
    this.degrees = streams[1];
    this.vertices = streams[2];
    this.references = streams[3];
    this.cornerOrder = cornerOrder;
    this.K = K;
    this.M = M;
    this.n = n;
    this.opsAt = 0;
    this.degreesAt = 0;
    this.verticesAt = 0;
    this.referencesAt = 0;
    this.faces = new Int32Array(Math.min(M, 1024) * n).fill(-1);
    this.seen = new VertexTable(this.vertices.length);
    this.index = this.seen.index; // each seen vertex's index in the file
    this.last = -1; // the latest NEW's vertex index
    this.edges = new EdgeTable();
    // into(v) and out(v): stacks of entries; entry t (one per 0 → 1 of an edge) is node 2t in
    // into(to) and node 2t + 1 in out(from). It is live while its edge is present and entered == t.
    this.entryEdge = new Int32Array(512);
    this.below = new Int32Array(1024); // the node under each node in its stack
    this.entries = 0;
    this.topInto = new Int32Array(this.vertices.length).fill(-1);
    this.topOut = new Int32Array(this.vertices.length).fill(-1);
    this.gates = new Int32Array(1024); // pairs a, b
    this.gateCount = 0;
    this.corners = new Int32Array(n); // the face being decoded, in walk order
    this.face = 0;
  }

  /** Decodes the M faces, then checks that every stream is read to its end. */
  run() {
    while (this.face < this.M) {
      const row = this.face * this.n;
      if (row === this.faces.length) this.growFaces();
      if (this.gateCount === 0) this.seed(row);
      else this.acrossGate(row);
    }
    this.checkEveryValueRead();
    return this.faces;
  }

  /** The decoded faces double as they come, up to M*n: M is a claim until they are decoded. */
  growFaces() {
    const faces = this.faces;
    const more = new Int32Array(Math.min(2 * faces.length, this.M * this.n)).fill(-1, faces.length);
    more.set(faces);
    this.faces = more;
  }

  /**
   * A seed, when no gate is left: the degree, then m tips; stored as decoded.
   * @param {number} row where the face goes in the table
   */
  seed(row) {
    const { corners, index } = this;
    const m = this.readDegree();
    for (let j = 0; j < m; j++) corners[j] = this.tip(this.nextOp(`operation of seed corner ${j}`), j);
    for (let j = 0; j < m; j++) this.faces[row + j] = index[corners[j]];
    this.addFace(m, 0);
    this.face++;
  }

  /**
   * The next gate: nothing if it closed meanwhile or its operation is 0, else the face across
   * it, its first two corners the gate's (flipped or not), rotated as the operation says.
   * @param {number} row where a face goes in the table
   */
  acrossGate(row) {
    const { corners, index, n } = this;
    const b = this.gates[--this.gateCount];
    const a = this.gates[--this.gateCount];
    const gate = this.edges.find(a, b);
    if (gate < 0 || this.edges.count[gate] === 0) return; // closed meanwhile: nothing is read
    const o = this.nextOp(`gate ${index[a]} → ${index[b]}`);
    if (o === 0) return;
    if (o < 0 || o > 8 * n) throw fail(`face ${this.face}: operation ${o} across gate ${index[a]} → ${index[b]} is outside 0..${8 * n}`);
    const v = o - 1;
    const q = v >> 3;
    const flipped = (v & 7) >= 4;
    const m = this.readDegree();
    if (q >= m) throw fail(`face ${this.face}: rotation ${q} is not below its degree ${m}`);
    corners[0] = flipped ? a : b;
    corners[1] = flipped ? b : a;
    corners[2] = this.tip(v & 3, 2);
    for (let j = 3; j < m; j++) corners[j] = this.tip(this.nextOp(`operation of corner ${j}`), j);
    let s = q;
    if (this.cornerOrder === 1) {
      let h = 0;
      for (let j = 1; j < m; j++) if (index[corners[j]] < index[corners[h]]) h = j;
      s = q - h + m; // the same place mod m, kept non-negative
    }
    for (let j = 0; j < m; j++) this.faces[row + ((s + j) % m)] = index[corners[j]];
    this.addFace(m, 1);
    this.face++;
  }

  /**
   * The next value of the ops stream.
   * @param {string} what what it is read for, to name in the error where the stream ends
   */
  nextOp(what) {
    if (this.opsAt === this.ops.length) throw fail(`face ${this.face}: the ops stream ends before the ${what}`);
    return this.ops[this.opsAt++];
  }

  /** The face's degree: 3 without a degrees stream, else the next value + 3, within 3..n. */
  readDegree() {
    const degrees = this.degrees;
    if (degrees.length === 0) return 3;
    if (this.degreesAt === degrees.length) throw fail(`face ${this.face}: the degrees stream ends before its degree`);
    const m = 3 + degrees[this.degreesAt++];
    if (m < 3 || m > this.n) throw fail(`face ${this.face}: degree ${m} is outside 3..${this.n}`);
    return m;
  }

  /**
   * The vertex (its number) named by tip j (c_0 .. c_{j−1} in corners) with operation op.
   * @param {number} op
   * @param {number} j
   */
  tip(op, j) {
    if (op === NEW) return this.newVertex(j);
    if (op === PREV || op === NEXT) return this.listedVertex(op, j);
    if (op === FAR) return this.farVertex(j);
    throw fail(`face ${this.face} corner ${j}: operation ${op} is not 0..3`);
  }

  /**
   * NEW: a vertex not seen yet, the next value of *vertices* past the latest NEW's.
   * @param {number} j the corner
   */
  newVertex(j) {
    const { K, face } = this;
    if (this.verticesAt === this.vertices.length) throw fail(`face ${face} corner ${j}: the vertices stream ends before this NEW`);
    const w = this.last + 1 + this.vertices[this.verticesAt++];
    if (w < 0 || w >= K) throw fail(`face ${face} corner ${j}: NEW names vertex ${w}, outside 0..${K - 1}`);
    if (this.seen.find(w) >= 0) throw fail(`face ${face} corner ${j}: NEW names vertex ${w}, which is already seen`);
    this.last = w;
    return this.seen.add(w);
  }

  /**
   * PREV: the last live entry of into(c_{j−1}), from where it comes; NEXT: the last live entry
   * of out(c_0), where it goes.
   * @param {number} op PREV or NEXT
   * @param {number} j the corner
   */
  listedVertex(op, j) {
    const { corners, edges, face } = this;
    const name = op === PREV ? 'PREV' : 'NEXT';
    if (j === 0) throw fail(`face ${face} corner 0: ${name} at the first corner of a face`);
    const w = op === PREV ? this.lastOf(this.topInto, corners[j - 1], edges.from) : this.lastOf(this.topOut, corners[0], edges.to);
    if (w < 0) {
      const list = op === PREV ? `into(${this.index[corners[j - 1]]})` : `out(${this.index[corners[0]]})`;
      throw fail(`face ${face} corner ${j}: ${name} on an empty ${list}`);
    }
    return w;
  }

  /**
   * FAR: a vertex already seen, the next value of *references* away from c_{j−1} (from 0 at the
   * first corner).
   * @param {number} j the corner
   */
  farVertex(j) {
    const { K, face, references } = this;
    const p = j === 0 ? 0 : this.index[this.corners[j - 1]];
    if (this.referencesAt === references.length) throw fail(`face ${face} corner ${j}: the references stream ends before this FAR`);
    const w = p + references[this.referencesAt++];
    if (w < 0 || w >= K) throw fail(`face ${face} corner ${j}: FAR names vertex ${w}, outside 0..${K - 1}`);
    const number = this.seen.find(w);
    if (number < 0) throw fail(`face ${face} corner ${j}: FAR names vertex ${w}, which is not seen yet`);
    return number;
  }

  /**
   * The last live entry of into(v) (other = from) or out(v) (other = to), or −1.
   * @param {Int32Array} tops
   * @param {number} v
   * @param {Int32Array} other
   */
  lastOf(tops, v, other) {
    const { entryEdge, below, edges } = this;
    let node = tops[v];
    while (node >= 0) {
      const t = node >> 1;
      const e = entryEdge[t];
      if (edges.count[e] > 0 && edges.entered[e] === t) break;
      node = below[node]; // stale: drop it for good
    }
    tops[v] = node;
    return node < 0 ? -1 : other[entryEdge[node >> 1]];
  }

  /**
   * Adds corners[0..m−1] to the boundary and pushes its gates from corner g on.
   * @param {number} m
   * @param {number} g
   */
  addFace(m, g) {
    const { corners, edges } = this;
    if (this.gateCount + 2 * m > this.gates.length) this.gates = grow(this.gates);
    const gates = this.gates;
    for (let j = 0; j < m; j++) {
      const x = corners[j];
      const y = corners[j + 1 === m ? 0 : j + 1];
      const back = edges.find(y, x);
      if (back >= 0 && edges.count[back] > 0) {
        edges.count[back]--; // its last copy gone: its entries in into(x), out(y) go stale
      } else {
        const e = edges.add(x, y);
        if (edges.count[e]++ === 0) this.enter(e, x, y);
      }
      if (j >= g) {
        gates[this.gateCount++] = x;
        gates[this.gateCount++] = y;
      }
    }
  }

  /**
   * A new entry for edge e = x → y, which has just entered the boundary: on top of into(y) and
   * of out(x).
   * @param {number} e
   * @param {number} x
   * @param {number} y
   */
  enter(e, x, y) {
    if (this.entries === this.entryEdge.length) {
      this.entryEdge = grow(this.entryEdge);
      this.below = grow(this.below);
    }
    const { below, topInto, topOut } = this;
    const t = this.entries++;
    this.entryEdge[t] = e;
    this.edges.entered[e] = t;
    below[2 * t] = topInto[y];
    topInto[y] = 2 * t;
    below[2 * t + 1] = topOut[x];
    topOut[x] = 2 * t + 1;
  }

  /** Every stream read to its end by the M faces: a value left over is an error. */
  checkEveryValueRead() {
    const { ops, degrees, vertices, references } = this;
    for (const [s, stream, used] of /** @type {[number, Int32Array, number][]} */ ([
      [0, ops, this.opsAt],
      [1, degrees, degrees.length === 0 ? 0 : this.degreesAt],
      [2, vertices, this.verticesAt],
      [3, references, this.referencesAt],
    ])) {
      if (used !== stream.length) {
        throw fail(`stream ${s} (${STREAMS[s]}) has ${stream.length - used} values left after the ${this.M} faces`);
      }
    }
  }
}
