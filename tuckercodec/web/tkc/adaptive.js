// Adaptive coding (spec/FORMAT.md §6.14, version 1.6): a qmat section's integers through LZMA's
// binary range coder, with 15-bit probabilities that adapt after every decision and 96 contexts
// drawn from the integers already decoded (the row's earlier neighbours in its column, and the
// same row in the two columns before). Strict: a stream that is not exactly the coding of the
// section's integers is refused (R46-adaptive-stream), whichever way it is not.
//
//   const mesh = relation === 'mesh' ? () => meshCodingOrder(topology) : null;  // null: ascending rows
//   const stream = decodeAdaptive(payload, rows, cols, mesh, planes, "section 'U1'");
//
// The result is the Int32Array that §6.1's zstd path gives (stream order, column-major), so the
// prediction and dequantization after it are the same. Every integer must zigzag below
// 2^(8·planes) <= 2^32 (R46), so a decoded magnitude never needs more than 32 bits: one that would
// is refused as soon as its bit length is known.
//
// Version 1.7's adaptive corrections (§6.9) have up to 8 planes, integers of up to 63 bits:
// decodeAdaptiveWide gives them as 64-bit halves (rows in ascending order, the only order a RESD
// chunk has), and decodeAdaptive stays the 32-bit path of every other section.

import { formatError } from './errors.js';

const RULE = 'R46-adaptive-stream';
/** No payload of L bytes holds more than MAX_EXPANSION·L integers (§6.14 "Bound"). */
export const MAX_EXPANSION = 32768;
const PROB_BITS = 15;
const PROB_ONE = 1 << PROB_BITS;
const PROB_INIT = 1 << (PROB_BITS - 1);
const FIRST_SHIFT = 2;
const LAST_SHIFT = 6;
const TOP = 2 ** 24; // below this the range takes in a byte
const PADDING = 256;
const NEIGHBOUR_CLASSES = 16;
const LEFT_CLASSES = 6;
const CONTEXTS = NEIGHBOUR_CLASSES * LEFT_CLASSES;
// a context's models, by offset: zero, sign, 32 exponent steps, first and second bits
const EXPONENT_MODELS = 32;
const ZERO = 0;
const SIGN = 1;
const EXPONENT = 2;
const FIRST_BIT = EXPONENT + EXPONENT_MODELS;
const SECOND_BIT = FIRST_BIT + EXPONENT_MODELS;
const MODELS_PER_CONTEXT = SECOND_BIT + 2 * EXPONENT_MODELS; // 130
/** The largest exponent (bit length − 1) of a magnitude: no integer has more than 63 bits. */
const MAX_EXPONENT = 62;
/**
 * decodeAdaptiveWide's magnitudes for the contexts are saturated here: the classes they enter
 * are the same (a sum of them of 2^29 or more is in the last class of either kind, whose
 * thresholds are 16 and 8192), and three of them add up below 2^31.
 */
const MAGNITUDE_CAP = 2 ** 29;

/**
 * A coding order (§6.14): `order` lists the rows in the order they are coded, and the row coded
 * j-th has the earlier neighbours `source[ends[j] .. ends[j+1]−1]` (rows coded before it in the
 * same column; none for a depth-0 vertex). U1's is meshCodingOrder's (topology.js); the
 * ascending order of U3, CORE and CENT, each row after the two before it, is given as null.
 * @typedef {{order: Int32Array, ends: Int32Array, source: Int32Array}} CodingOrder
 */

/**
 * The error of every R46 failure (also qmat.js's, for a `coder` that is not allowed).
 * @param {string} where
 * @param {string} message
 */
export function adaptiveError(where, message) {
  return formatError(RULE, `${where}: ${message}`);
}

/**
 * LZMA's range decoder over a payload, with the section's 12,480 adaptive models. Its registers
 * `range` and `code` are unsigned 32-bit values: every operation that can pass 2^31 is taken
 * back to unsigned with `>>> 0`, and (range >>> 15)·p, below 2^32, is Math.imul's low word.
 */
export class RangeDecoder {
  /**
   * @param {Uint8Array} data the payload
   * @param {number} planes the section's P (1..4; 1..8 for decodeAdaptiveWide): every integer
   *   zigzags below 2^(8P)
   * @param {string} where the section, for messages
   */
  constructor(data, planes, where) {
    if (data.length < 5 || data[0] !== 0) {
      throw adaptiveError(where, `an adaptive stream starts with a zero byte and holds at least 5 bytes (this one: ${data.length} bytes${data.length ? `, the first ${data[0]}` : ''})`);
    }
    this.data = data;
    /**
     * the payload then PADDING zeros: decodeColumn reads on past the payload's end until the
     * integer's end, where it refuses the stream (an integer is at most 67 decisions of a
     * model, each taking in at most two bytes, and 60 at even odds, each at most one: 194
     * bytes), so that no byte read checks the end
     */
    this.padded = new Uint8Array(data.length + PADDING);
    this.padded.set(data);
    this.where = where;
    this.code = ((data[1] << 24) | (data[2] << 16) | (data[3] << 8) | data[4]) >>> 0;
    this.range = 0xffffffff;
    this.next = 5;
    this.probs = new Uint16Array(CONTEXTS * MODELS_PER_CONTEXT).fill(PROB_INIT);
    this.shifts = new Uint8Array(CONTEXTS * MODELS_PER_CONTEXT).fill(FIRST_SHIFT);
    this.planes = planes;
    /** 2^(8P − 1): a positive integer is below it, a negative one's magnitude at most it */
    this.half = 2 ** (8 * planes - 1);
    /** the largest exponent (bit length − 1) of a magnitude within the planes (<= 31 for P <= 4) */
    this.longest = Math.min(8 * planes - 1, MAX_EXPONENT);
  }

  ended() {
    return adaptiveError(this.where, 'the adaptive stream ends before its last integer');
  }

  unbounded() {
    return adaptiveError(this.where, `an integer of the adaptive stream does not zigzag below 2^${8 * this.planes} (planes ${this.planes})`);
  }

  /** For an exponent past `longest`: beyond the planes, or (P = 8) beyond 63 bits. */
  tooLong() {
    if (8 * this.planes - 1 <= MAX_EXPONENT) return this.unbounded();
    return adaptiveError(this.where, `an integer of the adaptive stream has more than ${MAX_EXPONENT + 1} bits`);
  }

  /** After the last integer: every byte read and code below range, else R46. */
  finish() {
    if (this.next !== this.data.length) {
      throw adaptiveError(this.where, `the adaptive stream holds ${this.data.length - this.next} bytes after its last integer`);
    }
    if (this.code >= this.range) throw adaptiveError(this.where, "the adaptive stream's last bytes are not a range coder's ending");
  }
}

/**
 * The integers of an adaptive stream (§6.14), in stream order (column-major, j = c·rows + r):
 * what §6.1's decodeIntStream gives for a zstd payload. The caller has checked `planes` (1..4).
 * @param {Uint8Array} payload the section's bytes, CRC checked
 * @param {number} rows
 * @param {number} cols
 * @param {(() => CodingOrder) | null} meshOrder U1's order (meshCodingOrder), made once the
 *   payload's size and first bytes have passed (its arrays are K long); null: ascending rows
 * @param {number} planes P: every integer zigzags below 2^(8P)
 * @param {string} where the section, for messages
 * @returns {Int32Array}
 * @throws {import('./errors.js').TkcError} R46-adaptive-stream
 */
export function decodeAdaptive(payload, rows, cols, meshOrder, planes, where) {
  if (rows * cols > MAX_EXPANSION * payload.length) {
    throw adaptiveError(where, `${rows * cols} integers cannot come from ${payload.length} bytes (at most ${MAX_EXPANSION} per byte)`);
  }
  const decoder = new RangeDecoder(payload, planes, where);
  const order = meshOrder === null ? null : meshOrder();
  const mesh = order === null ? null : sourcePositions(order, rows);
  const out = new Int32Array(rows * cols);
  // By coding position j (the row coded j-th, every column the same), |x| of the column being
  // decoded up to j − 1 and of the column before from j on (a row's earlier neighbours are coded
  // before it); one more, always 0, that the padded sources point to.
  const magnitudes = new Uint32Array(rows + 1);
  const left = new Uint8Array(rows); // by coding position, the class B from the two columns before
  for (let c = 0; c < cols; c++) {
    const column = out.subarray(c * rows, (c + 1) * rows);
    if (order === null || mesh === null) decodeColumn(decoder, column, magnitudes, left, null, null, null, null);
    else decodeColumn(decoder, column, magnitudes, left, order.order, order.ends, mesh.first, mesh.source);
  }
  decoder.finish();
  return out;
}

/**
 * The integers of an adaptive stream (§6.14) of up to 63 bits, rows in ascending order (each
 * after the two before it): a RESD chunk's with `coder` 1 (§6.9, version 1.7). In stream order
 * (column-major, j = c·rows + r) as 64-bit two's complement halves, low half first: out[2j] and
 * out[2j + 1]. Any planes 1..8 (the caller has checked them); decodeAdaptive is the faster path
 * where P <= 4 and 32-bit integers will do.
 * @param {Uint8Array} payload
 * @param {number} rows
 * @param {number} cols
 * @param {number} planes P: every integer zigzags below 2^(8P), on 64 bits
 * @param {string} where the section and chunk, for messages
 * @returns {Int32Array} 2·rows·cols halves
 * @throws {import('./errors.js').TkcError} R46-adaptive-stream
 */
export function decodeAdaptiveWide(payload, rows, cols, planes, where) {
  if (rows * cols > MAX_EXPANSION * payload.length) {
    throw adaptiveError(where, `${rows * cols} integers cannot come from ${payload.length} bytes (at most ${MAX_EXPANSION} per byte)`);
  }
  const decoder = new RangeDecoder(payload, planes, where);
  const out = new Int32Array(2 * rows * cols);
  // by row: |x| (saturated) of the column being decoded up to the row before, of the column
  // before from the row on; and each row's B
  const magnitudes = new Uint32Array(rows);
  const left = new Uint8Array(rows);
  for (let c = 0; c < cols; c++) decodeWideColumn(decoder, out.subarray(2 * c * rows, 2 * (c + 1) * rows), magnitudes, left);
  decoder.finish();
  return out;
}

/**
 * The `count` integers of a uniform stream over `total` (§6.8, version 1.9): value i in
 * 0..total−i−1 as truncated binary in §6.14's direct bits, most significant first. With
 * n = total − i, k = floor(log2 n) and u = 2^(k+1) − n, k bits x give x when x < u, else one
 * more bit b gives 2x + b − u. Every value so read is in its range, so the stream fails only as
 * an adaptive stream does (R46): more values than §6.14's bound lets its bytes hold (checked
 * before anything is allocated), a bad start, an end reached too soon or not at all, a bad
 * ending. The caller has checked count <= total <= 2^31: every value fits an int32.
 * @param {Uint8Array} payload
 * @param {number} count
 * @param {number} total T (the vertices, K)
 * @param {string} where the stream, for messages
 * @returns {Int32Array}
 * @throws {import('./errors.js').TkcError} R46-adaptive-stream
 */
export function decodeUniform(payload, count, total, where) {
  if (count > MAX_EXPANSION * payload.length) {
    throw adaptiveError(where, `${count} integers cannot come from ${payload.length} bytes (at most ${MAX_EXPANSION} per byte)`);
  }
  const d = new RangeDecoder(payload, 4, where);
  const data = d.padded;
  const end = payload.length;
  const out = new Int32Array(count);
  // the registers as 32-bit locals, as decodeColumn keeps them; a value reads at most 32 direct
  // bits, so at most 4 bytes past the end (into the padding) before the check after it
  let range = d.range >>> 0;
  let code = d.code >>> 0;
  let next = d.next;
  for (let i = 0; i < count; i++) {
    const n = total - i; // 1..2^31
    const k = 31 - Math.clz32(n);
    const u = 2 ** (k + 1) - n; // 1..2^k
    let x = 0; // below 2^31: built in doubles
    for (let b = 0; b <= k; b++) {
      if (b === k && x < u) break; // the k bits were enough
      range >>>= 1;
      const bit = code >= range ? 1 : 0;
      code = (code - (range & -bit)) >>> 0;
      for (; range < TOP; range = (range << 8) >>> 0) code = ((code << 8) | data[next++]) >>> 0;
      x = 2 * x + bit;
    }
    if (next > end) throw d.ended();
    out[i] = x < u ? x : x - u; // after k + 1 bits x is 2·x' + b, which is at least 2u > u
  }
  d.range = range;
  d.code = code;
  d.next = next;
  d.finish();
  return out;
}

/**
 * How many of a row's earlier neighbours sourcePositions lays out in a fixed slot: with four, 92%
 * of samba's rows (1 to 7 neighbours) are summed without a loop whose end the processor would
 * mispredict.
 */
const FIRST_SOURCES = 4;

/**
 * The mesh order's earlier neighbours as coding positions (where their magnitudes are, see
 * decodeAdaptive): `source` is the order's, each row replaced by its position; `first` holds
 * each position's first FIRST_SOURCES, padded with `rows`, whose magnitude is always 0.
 * @param {CodingOrder} order
 * @param {number} rows
 */
function sourcePositions(order, rows) {
  const at = new Int32Array(rows);
  for (let j = 0; j < rows; j++) at[order.order[j]] = j;
  const source = new Int32Array(order.source.length);
  for (let t = 0; t < source.length; t++) source[t] = at[order.source[t]];
  const first = new Int32Array(FIRST_SOURCES * rows).fill(rows);
  for (let j = 0; j < rows; j++) {
    const s0 = order.ends[j];
    const n = Math.min(order.ends[j + 1] - s0, FIRST_SOURCES);
    for (let i = 0; i < n; i++) first[FIRST_SOURCES * j + i] = source[s0 + i];
  }
  return { first, source };
}

/**
 * The class A of the row coded j-th (§6.14 "Order and contexts"): 1 + min(bitlen(m), 14) for
 * the magnitude m of its earlier neighbours, 0 without any. Every magnitude is at most 2^31: the
 * sequence's m is exact; the mesh's sum s is exact while below 2^53, and so are x = 3s and
 * m = floor(x / n) for its n neighbours (a quotient that is not an integer is 1/n from the next,
 * more than half its ulp); past 2^53, x / n is far above 2^13 (n < 2^31) and the class is the
 * last whatever the rounding. Below 2^31, x needs no division (which would sit between one
 * integer and the next): with k = bitlen(x) − bitlen(n), bitlen(m) is k + 1 if x >= n·2^k, else
 * k (0 if k < 0), and n·2^k < 2^bitlen(x) <= 2^31 is exact as an int32 shift. Both tests are
 * taken from the sign of a difference rather than a branch, as the processor could not predict
 * them.
 * @param {number} j
 * @param {Uint32Array} magnitudes by coding position (decodeAdaptive)
 * @param {Int32Array | null} ends the mesh order's, or null for ascending rows
 * @param {Int32Array | null} first sourcePositions' for the mesh order
 * @param {Int32Array | null} source
 */
function neighbourClass(j, magnitudes, ends, first, source) {
  if (ends === null || first === null || source === null) {
    if (j >= 2) return magnitudeClass(2 * magnitudes[j - 1] + magnitudes[j - 2]);
    return j === 1 ? magnitudeClass(3 * magnitudes[0]) : 0;
  }
  const s0 = ends[j];
  const n = ends[j + 1] - s0;
  if (n === 0) return 0;
  const f = FIRST_SOURCES * j;
  let s = magnitudes[first[f]] + magnitudes[first[f + 1]] + magnitudes[first[f + 2]] + magnitudes[first[f + 3]];
  for (let t = s0 + FIRST_SOURCES; t < s0 + n; t++) s += magnitudes[source[t]];
  const x = 3 * s;
  if (x >= 8192 * n) return NEIGHBOUR_CLASSES - 1;
  if (x >= 2 ** 31) return magnitudeClass(Math.floor(x / n));
  const gap = Math.clz32(n) - Math.clz32(x);
  const k = gap & ~(gap >> 31); // max(gap, 0) without a branch: if gap < 0, x < n = n << k
  return 2 + k - ((x - (n << k)) >>> 31);
}

/**
 * 1 + min(bitlen(m), 14) for a magnitude m >= 0.
 * @param {number} m
 */
function magnitudeClass(m) {
  return m >= 8192 ? NEIGHBOUR_CLASSES - 1 : 33 - Math.clz32(m);
}

/**
 * One column, every integer binarized as §6.14 "One integer" says. The decisions whose odds are
 * mostly far from even, the zero and the exponent's unary steps, branch on their bit; the sign
 * and the first and second bits under the leading one, close to even, and the bits at even odds
 * below them are computed with masks (one = −bit) instead, as a branch on them would be
 * mispredicted about every other time. The coder's registers stay in locals for the whole
 * column: through a method per integer or per decision, which reads and writes them on the
 * decoder, this runs 1.2 to 1.3 times slower. An exponent past the planes' (|x| >= 2^e would
 * not zigzag below 2^(8P)) is refused at once, so a magnitude never passes 2^32; a read past
 * the payload's end (into the decoder's padding), at the integer's end or before that refusal.
 * R46 as decodeAdaptive says.
 * @param {RangeDecoder} d
 * @param {Int32Array} column out: the column's integers, by row
 * @param {Uint32Array} magnitudes in and out, by coding position (decodeAdaptive)
 * @param {Uint8Array} left in and out, by coding position: each row's B
 * @param {Int32Array | null} rows the mesh order's rows by coding position (null: ascending),
 *   its ends, and its sources as sourcePositions gives them
 * @param {Int32Array | null} ends
 * @param {Int32Array | null} first
 * @param {Int32Array | null} source
 */
function decodeColumn(d, column, magnitudes, left, rows, ends, first, source) {
  const { probs, shifts, padded: data, half, longest } = d;
  const end = d.data.length;
  // loaded as 32-bit words: from a number the loop's arithmetic runs in doubles, 1.15 times slower
  let range = d.range >>> 0;
  let code = d.code >>> 0;
  let next = d.next | 0;
  for (let j = 0; j < column.length; j++) {
    const base = (neighbourClass(j, magnitudes, ends, first, source) * LEFT_CLASSES + left[j]) * MODELS_PER_CONTEXT;
    let e = -1; // -1: the zero decision, then the exponent's steps so far
    let negative = 0;
    for (;;) {
      const m = e < 0 ? base + ZERO : base + EXPONENT + e;
      const p = probs[m];
      const s = shifts[m];
      const bound = Math.imul(range >>> PROB_BITS, p) >>> 0;
      if (s < LAST_SHIFT) shifts[m] = s + 1;
      if (code < bound) {
        range = bound;
        probs[m] = p + ((PROB_ONE - p) >> s);
        for (; range < TOP; range = (range << 8) >>> 0) code = ((code << 8) | data[next++]) >>> 0;
        break;
      }
      code = (code - bound) >>> 0;
      range = (range - bound) >>> 0;
      probs[m] = p - (p >> s);
      for (; range < TOP; range = (range << 8) >>> 0) code = ((code << 8) | data[next++]) >>> 0;
      if (e >= 0) {
        if (++e > longest) throw next > end ? d.ended() : d.tooLong();
        continue;
      }
      const ps = probs[base + SIGN]; // the sign, after a 1 for "not zero"
      const ss = shifts[base + SIGN];
      const sb = Math.imul(range >>> PROB_BITS, ps) >>> 0;
      negative = code >= sb ? 1 : 0;
      const one = -negative;
      code = (code - (sb & one)) >>> 0;
      range = ((sb & ~one) | ((range - sb) & one)) >>> 0;
      probs[base + SIGN] = ps + (((PROB_ONE - ps) >> ss) & ~one) - ((ps >> ss) & one);
      if (ss < LAST_SHIFT) shifts[base + SIGN] = ss + 1;
      for (; range < TOP; range = (range << 8) >>> 0) code = ((code << 8) | data[next++]) >>> 0;
      e = 0;
    }
    let magnitude = e < 0 ? 0 : 1;
    for (let b = 0; b < e; b++) {
      let bit = 0;
      if (b < 2) {
        const m = b === 0 ? base + FIRST_BIT + e : base + SECOND_BIT + 2 * e + (magnitude & 1);
        const p = probs[m];
        const s = shifts[m];
        const bound = Math.imul(range >>> PROB_BITS, p) >>> 0;
        bit = code >= bound ? 1 : 0;
        const one = -bit;
        code = (code - (bound & one)) >>> 0;
        range = ((bound & ~one) | ((range - bound) & one)) >>> 0;
        probs[m] = p + (((PROB_ONE - p) >> s) & ~one) - ((p >> s) & one);
        if (s < LAST_SHIFT) shifts[m] = s + 1;
      } else {
        range >>>= 1;
        bit = code >= range ? 1 : 0;
        code = (code - (range & -bit)) >>> 0;
      }
      for (; range < TOP; range = (range << 8) >>> 0) code = ((code << 8) | data[next++]) >>> 0;
      magnitude = 2 * magnitude + bit;
    }
    // past the payload's end, the padding's zeros were read: R46 for that before anything else
    if (next > end || (negative ? magnitude > half : magnitude >= half)) throw next > end ? d.ended() : d.unbounded();
    column[rows === null ? j : rows[j]] = (magnitude ^ -negative) + negative; // −magnitude if negative
    // B = min(bitlen(2·|x[r, c]| + |x[r, c−1]|), 5) for the next column
    const b = 2 * magnitude + magnitudes[j];
    left[j] = b >= 16 ? LEFT_CLASSES - 1 : 32 - Math.clz32(b);
    magnitudes[j] = magnitude;
  }
  d.range = range;
  d.code = code;
  d.next = next;
}

/**
 * One column of decodeAdaptiveWide: decodeColumn's decisions (the exponent's models shared past
 * 31 steps, §6.14), each magnitude built in two halves, `hi` taking the bits from 2^32 up. The
 * contexts come from magnitudes saturated at MAGNITUDE_CAP, which give the same classes. An
 * exponent past the planes' (or past 62) is refused at once, the bound 2^(8P − 1) itself
 * (allowed for a negative integer only) on the halves at the integer's end. R46 as
 * decodeAdaptive says.
 * @param {RangeDecoder} d
 * @param {Int32Array} column out: the column's integers as halves, by row
 * @param {Uint32Array} magnitudes in and out, by row (decodeAdaptiveWide)
 * @param {Uint8Array} left in and out, by row: each row's B
 */
function decodeWideColumn(d, column, magnitudes, left) {
  const { probs, shifts, padded: data, longest } = d;
  const end = d.data.length;
  const halfHi = Math.floor(d.half / 2 ** 32); // 2^(8P − 1) in halves
  const halfLo = d.half % 2 ** 32;
  let range = d.range >>> 0;
  let code = d.code >>> 0;
  let next = d.next | 0;
  let one = 0; // the saturated magnitudes of the row before and the one before it
  let two = 0;
  for (let j = 0; 2 * j < column.length; j++) {
    const a = j >= 2 ? magnitudeClass(2 * one + two) : j === 1 ? magnitudeClass(3 * one) : 0;
    const base = (a * LEFT_CLASSES + left[j]) * MODELS_PER_CONTEXT;
    let e = -1; // -1: the zero decision, then the exponent's steps so far
    let negative = 0;
    for (;;) {
      const m = e < 0 ? base + ZERO : base + EXPONENT + (e < EXPONENT_MODELS ? e : EXPONENT_MODELS - 1);
      const p = probs[m];
      const s = shifts[m];
      const bound = Math.imul(range >>> PROB_BITS, p) >>> 0;
      if (s < LAST_SHIFT) shifts[m] = s + 1;
      if (code < bound) {
        range = bound;
        probs[m] = p + ((PROB_ONE - p) >> s);
        for (; range < TOP; range = (range << 8) >>> 0) code = ((code << 8) | data[next++]) >>> 0;
        break;
      }
      code = (code - bound) >>> 0;
      range = (range - bound) >>> 0;
      probs[m] = p - (p >> s);
      for (; range < TOP; range = (range << 8) >>> 0) code = ((code << 8) | data[next++]) >>> 0;
      if (e >= 0) {
        if (++e > longest) throw next > end ? d.ended() : d.tooLong();
        continue;
      }
      const sb = Math.imul(range >>> PROB_BITS, probs[base + SIGN]) >>> 0; // the sign: masks
      negative = code >= sb ? 1 : 0;
      code = (code - (sb & -negative)) >>> 0;
      range = ((sb & (negative - 1)) | ((range - sb) & -negative)) >>> 0;
      adapt(probs, shifts, base + SIGN, negative);
      for (; range < TOP; range = (range << 8) >>> 0) code = ((code << 8) | data[next++]) >>> 0;
      e = 0;
    }
    // the bits under the leading one, into `acc`: from 2^32 up they make `hi`, then `lo`
    let acc = e < 0 ? 0 : 1;
    let hi = 0;
    let first = 0;
    const slot = e < EXPONENT_MODELS ? e : EXPONENT_MODELS - 1;
    for (let b = 0; b < e; b++) {
      if (b === e - 32) {
        hi = acc;
        acc = 0;
      }
      let bit = 0;
      if (b < 2) {
        const m = b === 0 ? base + FIRST_BIT + slot : base + SECOND_BIT + 2 * slot + first;
        const bound = Math.imul(range >>> PROB_BITS, probs[m]) >>> 0;
        bit = code >= bound ? 1 : 0;
        code = (code - (bound & -bit)) >>> 0;
        range = ((bound & (bit - 1)) | ((range - bound) & -bit)) >>> 0;
        adapt(probs, shifts, m, bit);
        first = bit;
      } else {
        range >>>= 1;
        bit = code >= range ? 1 : 0;
        code = (code - (range & -bit)) >>> 0;
      }
      for (; range < TOP; range = (range << 8) >>> 0) code = ((code << 8) | data[next++]) >>> 0;
      acc = 2 * acc + bit;
    }
    if (next > end) throw d.ended();
    if (hi > halfHi || (hi === halfHi && (negative ? acc > halfLo : acc >= halfLo))) throw d.unbounded();
    two = one;
    one = store(column, j, hi, acc, negative, magnitudes, left);
  }
  d.range = range;
  d.code = code;
  d.next = next;
}

/**
 * Row j's integer, −(hi·2^32 + lo) if negative, into decodeWideColumn's column as halves (each
 * complemented, plus one carried in from the low); its magnitude saturated at MAGNITUDE_CAP
 * into `magnitudes`, and its B for the next column into `left`.
 * @param {Int32Array} column
 * @param {number} j
 * @param {number} hi
 * @param {number} lo
 * @param {number} negative 1 or 0
 * @param {Uint32Array} magnitudes
 * @param {Uint8Array} left
 * @returns {number} the saturated magnitude
 */
function store(column, j, hi, lo, negative, magnitudes, left) {
  column[2 * j] = ((lo ^ -negative) + negative) | 0;
  column[2 * j + 1] = ((hi ^ -negative) + (lo === 0 ? negative : 0)) | 0;
  const magnitude = hi > 0 || lo >= MAGNITUDE_CAP ? MAGNITUDE_CAP : lo;
  const b = 2 * magnitude + magnitudes[j];
  left[j] = b >= 16 ? LEFT_CLASSES - 1 : 32 - Math.clz32(b);
  magnitudes[j] = magnitude;
  return magnitude;
}

/**
 * A model's update after its decision `bit` (§6.14): the probability moved toward it by its
 * shift, with masks rather than a branch (the decisions near even odds would mispredict one),
 * and the shift one more up to LAST_SHIFT.
 * @param {Uint16Array} probs
 * @param {Uint8Array} shifts
 * @param {number} m
 * @param {number} bit
 */
function adapt(probs, shifts, m, bit) {
  const p = probs[m];
  const s = shifts[m];
  const one = -bit;
  probs[m] = p + (((PROB_ONE - p) >> s) & ~one) - ((p >> s) & one);
  if (s < LAST_SHIFT) shifts[m] = s + 1;
}
