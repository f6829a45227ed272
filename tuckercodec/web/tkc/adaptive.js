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
const DIRECT = -1; // decodeColumn's stage for the bits at even odds

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
   * @param {number} planes the section's P (1..4): every integer zigzags below 2^(8P)
   * @param {string} where the section, for messages
   */
  constructor(data, planes, where) {
    if (data.length < 5 || data[0] !== 0) {
      throw adaptiveError(where, `an adaptive stream starts with a zero byte and holds at least 5 bytes (this one: ${data.length} bytes${data.length ? `, the first ${data[0]}` : ''})`);
    }
    this.data = data;
    this.where = where;
    this.code = ((data[1] << 24) | (data[2] << 16) | (data[3] << 8) | data[4]) >>> 0;
    this.range = 0xffffffff;
    this.next = 5;
    this.probs = new Uint16Array(CONTEXTS * MODELS_PER_CONTEXT).fill(PROB_INIT);
    this.shifts = new Uint8Array(CONTEXTS * MODELS_PER_CONTEXT).fill(FIRST_SHIFT);
    this.planes = planes;
    /** 2^(8P − 1): a positive integer is below it, a negative one's magnitude at most it */
    this.half = 2 ** (8 * planes - 1);
    /** the largest exponent (bit length − 1) of a magnitude within the planes (<= 31) */
    this.longest = 8 * planes - 1;
  }

  ended() {
    return adaptiveError(this.where, 'the adaptive stream ends before its last integer');
  }

  unbounded() {
    return adaptiveError(this.where, `an integer of the adaptive stream does not zigzag below 2^${8 * this.planes} (planes ${this.planes})`);
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
  const out = new Int32Array(rows * cols);
  let magnitudes = new Float64Array(rows);
  let before = new Float64Array(rows); // the column before's magnitudes
  const left = new Uint8Array(rows); // each row's class from the two columns before
  for (let c = 0; c < cols; c++) {
    decodeColumn(decoder, out.subarray(c * rows, (c + 1) * rows), magnitudes, left, order);
    // B = min(bitlen(2·|x[r, c]| + |x[r, c−1]|), 5) for the next column
    for (let r = 0; r < rows; r++) {
      const v = 2 * magnitudes[r] + before[r];
      left[r] = v >= 16 ? LEFT_CLASSES - 1 : 32 - Math.clz32(v);
    }
    [before, magnitudes] = [magnitudes, before];
  }
  decoder.finish();
  return out;
}

/**
 * A row's context t = 6·A + B as its first model, 130·t (§6.14 "Order and contexts"). A is
 * 1 + min(bitlen(m), 14) for the magnitude m of the earlier neighbours, 0 without any. Every
 * magnitude is at most 2^31: the sequence's m is exact; the mesh's sum s is exact while below
 * 2^53, and so are 3s and floor(3s / |S(v)|) (a quotient that is not an integer is 1/|S(v)| from
 * the next, more than half its ulp); past 2^53, 3s / |S(v)| is far above 2^13 (|S(v)| < 2^31)
 * and the class is the last whatever the rounding.
 * @param {number} j the row's place in the coding order
 * @param {number} v the row
 * @param {Float64Array} magnitudes the column's magnitudes so far
 * @param {Uint8Array} left B of each row
 * @param {CodingOrder | null} order
 */
function contextBase(j, v, magnitudes, left, order) {
  let m = -1; // no earlier neighbours
  if (order !== null) {
    const { ends, source } = order;
    const s0 = ends[j];
    const s1 = ends[j + 1];
    if (s1 > s0) {
      let s = 0;
      for (let t = s0; t < s1; t++) s += magnitudes[source[t]];
      m = Math.floor((3 * s) / (s1 - s0));
    }
  } else if (j >= 2) {
    m = 2 * magnitudes[j - 1] + magnitudes[j - 2];
  } else if (j === 1) {
    m = 3 * magnitudes[0];
  }
  const a = m < 0 ? 0 : m >= 8192 ? NEIGHBOUR_CLASSES - 1 : 33 - Math.clz32(m);
  return (a * LEFT_CLASSES + left[v]) * MODELS_PER_CONTEXT;
}

/**
 * One column, every integer binarized as §6.14 "One integer" says, in one loop whose `stage` is
 * the decision to make: zero, sign, the exponent's unary steps, the first and second bits under
 * the leading one (modelled), then the bits below (direct, at even odds). The coder's registers
 * stay in locals for the whole column: through a method per integer or per decision, which reads
 * and writes them on the decoder, this runs 1.2 to 1.3 times slower. An exponent past the
 * planes' (|x| >= 2^e would not zigzag below 2^(8P)) is refused at once, so a magnitude never
 * passes 2^32. R46 as decodeAdaptive says.
 * @param {RangeDecoder} d
 * @param {Int32Array} column out: the column's integers, by row
 * @param {Float64Array} magnitudes out: their magnitudes
 * @param {Uint8Array} left each row's B
 * @param {CodingOrder | null} order
 */
function decodeColumn(d, column, magnitudes, left, order) {
  const { probs, shifts, data, half, longest } = d;
  // loaded as 32-bit words: from a number the loop's arithmetic runs in doubles, 1.15 times slower
  let range = d.range >>> 0;
  let code = d.code >>> 0;
  let next = d.next | 0;
  for (let j = 0; j < column.length; j++) {
    const v = order === null ? j : order.order[j];
    const base = contextBase(j, v, magnitudes, left, order);
    let m = base + ZERO;
    let stage = ZERO;
    let negative = 0;
    let e = 0; // the exponent: at most longest <= 31, so no model is shared (§6.14's min(·, 31))
    let magnitude = 0;
    let remaining = 0; // bits under the leading one still to come
    for (;;) {
      let bit = 0;
      if (stage !== DIRECT) {
        const p = probs[m];
        const s = shifts[m];
        const bound = Math.imul(range >>> PROB_BITS, p) >>> 0;
        if (code < bound) {
          range = bound;
          probs[m] = p + ((PROB_ONE - p) >> s);
        } else {
          code = (code - bound) >>> 0;
          range = (range - bound) >>> 0;
          probs[m] = p - (p >> s);
          bit = 1;
        }
        if (s < LAST_SHIFT) shifts[m] = s + 1;
      } else {
        range >>>= 1;
        if (code >= range) {
          code = (code - range) >>> 0;
          bit = 1;
        }
      }
      while (range < TOP) {
        if (next >= data.length) throw d.ended();
        range = (range << 8) >>> 0;
        code = ((code << 8) | data[next++]) >>> 0;
      }
      if (stage === ZERO) {
        if (!bit) break; // x = 0
        stage = SIGN;
        m = base + SIGN;
      } else if (stage === SIGN) {
        negative = bit;
        stage = EXPONENT;
        m = base + EXPONENT;
      } else if (stage === EXPONENT) {
        if (bit) {
          if (++e > longest) throw d.unbounded();
          m = base + EXPONENT + e;
          continue;
        }
        magnitude = 1;
        remaining = e;
        if (remaining === 0) break;
        stage = FIRST_BIT;
        m = base + FIRST_BIT + e;
      } else {
        // FIRST_BIT, SECOND_BIT, DIRECT: one more bit under the leading one
        magnitude = 2 * magnitude + bit;
        if (--remaining === 0) break;
        if (stage === FIRST_BIT) m = base + SECOND_BIT + 2 * e + bit;
        stage = stage === FIRST_BIT ? SECOND_BIT : DIRECT;
      }
    }
    if (negative ? magnitude > half : magnitude >= half) throw d.unbounded();
    column[v] = negative ? -magnitude : magnitude;
    magnitudes[v] = magnitude;
  }
  d.range = range;
  d.code = code;
  d.next = next;
}
