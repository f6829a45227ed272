// Codec `qmat` (spec/FORMAT.md §6.3): a matrix stored as integers with one quantization step per
// column, each column optionally predicted (§6.2). Checked in the order of §5 step 16: planes,
// the length and type of steps, of predict, the values of steps, of predict, (1.6) mean_push
// (predictor 2's push per column, §6.2), (1.6) the coder, then the stream: §6.1's zstd frame, or
// with coder 1 §6.14's adaptive stream.

import { adaptiveError, decodeAdaptive } from './adaptive.js';
import { formatError } from './errors.js';
import { describe, isInt } from './msgpack.js';
import { decodeIntStream } from './streams.js';
import { MEAN_PUSH, meshCodingOrder, restoreMeshColumn } from './topology.js';

const EXACT = 2 ** 53; // float64 holds every integer up to here
const LINEAR_VALUE = 2 ** 32; // §6.2 predictor 3: the restored values ...
const LINEAR_STEP = 2 ** 33; // ... and the running differences
const ZSTD = 0; // §6.14's coder values: §6.1's byte planes ...
const ADAPTIVE = 1; // ... or the adaptive stream
const MAX_PUSH = 9; // §6.2: mean_push's bytes are 0..9 (sixths of a step)

/**
 * What the file allows a qmat section: `tools`, preamble flag bit 1 (version 1.2: predictors 2
 * and 3); `adaptive` (§6.14), whether `coder` may be 1 (flag bit 3, in a position factor: U1,
 * U3, CORE, CENT or a `.s` form), else it must be absent or 0 (R46; a field's factors too, as
 * the reference decoder has it).
 * @typedef {{tools: boolean, adaptive: boolean}} Coding
 */

/**
 * Decodes a qmat section into its dequantized matrix, row-major (C order).
 * @param {import('./container.js').Section} section the section entry (readContainer)
 * @param {Uint8Array} payload its bytes, CRC already checked
 * @param {number} rows
 * @param {number} cols
 * @param {'mesh'|'time'|'none'} relation the parents §6.6 assigns: U1 mesh, U3/CENT time, CORE none
 * @param {Coding} coding what the file allows the section
 * @param {() => import('./topology.js').Topology} topology the mesh topology, built on first
 *   use (for U1 only)
 * @param {{q?: Float64Array, steps?: Float64Array}} [keep] when given, also the restored
 *   integers q (rows*cols, row-major, as binary64) and the steps (the f32 widened) are set in
 *   it: §8.1 multiplies U1's integers
 * @returns {Float64Array} rows*cols values
 */
export function decodeQmat(section, payload, rows, cols, relation, coding, topology, keep) {
  const where = `section '${section.id}'`;
  const { planes, step, predict } = checkedParams(section.entry, cols, relation, coding.tools, where);
  const push = readPush(section.entry, cols, relation === 'mesh' && coding.adaptive, where);
  const coder = readCoder(section.entry, coding.adaptive, where);
  const stream =
    coder === ADAPTIVE
      ? decodeAdaptive(payload, rows, cols, relation === 'mesh' ? () => meshCodingOrder(topology()) : null, planes, where)
      : decodeIntStream(payload, rows * cols, planes, where);
  const out = new Float64Array(rows * cols);
  const integers = keep ? new Float64Array(rows * cols) : null;
  if (keep) {
    keep.q = /** @type {Float64Array} */ (integers);
    keep.steps = step;
  }
  for (let c = 0; c < cols; c++) {
    const offset = c * rows; // stream order is column-major (§6.3)
    let q;
    const p = predict[c];
    if (p === 0) q = stream.subarray(offset, offset + rows);
    else if (relation === 'mesh') q = restoreMeshColumn(stream, offset, p, topology(), `${where} column ${c}`, push ? push[c] : MEAN_PUSH);
    else if (p === 1) q = restoreRunningSum(stream, offset, rows);
    else q = restoreLinear(stream, offset, rows, `${where} column ${c}`);
    const s = step[c];
    for (let r = 0; r < rows; r++) out[r * cols + c] = s * q[r];
    if (integers) for (let r = 0; r < rows; r++) integers[r * cols + c] = q[r];
  }
  return out;
}

/**
 * §5 step 16's checks of the parameters before the coder: planes (R30), the length and type of
 * steps (R31), of predict (R32), the values of steps (R31), of predict (R32).
 * @param {Map<string, import('./msgpack.js').MsgValue>} entry
 * @param {number} cols
 * @param {'mesh'|'time'|'none'} relation
 * @param {boolean} codingTools
 * @param {string} where
 */
function checkedParams(entry, cols, relation, codingTools, where) {
  const planes = entry.get('planes');
  if (!isInt(planes) || planes < 1 || planes > 4) {
    throw formatError('R30-planes', `${where}: "planes" is ${planes === undefined ? 'missing' : describe(planes)}, not an int in 1..4`);
  }
  const steps = entry.get('steps');
  if (!(steps instanceof Uint8Array) || steps.length !== 4 * cols) {
    throw formatError('R31-steps', `${where}: "steps" is ${steps === undefined ? 'missing' : describe(steps)}, not a bin of ${4 * cols} bytes`);
  }
  const predict = entry.get('predict');
  if (!(predict instanceof Uint8Array) || predict.length !== cols) {
    throw formatError('R32-predictor', `${where}: "predict" is ${predict === undefined ? 'missing' : describe(predict)}, not a bin of ${cols} bytes`);
  }
  const stepView = new DataView(steps.buffer, steps.byteOffset, steps.byteLength);
  const step = new Float64Array(cols);
  for (let c = 0; c < cols; c++) {
    step[c] = stepView.getFloat32(4 * c, true); // the exact widening of the stored f32
    if (!Number.isFinite(step[c]) || !(step[c] > 0)) {
      throw formatError('R31-steps', `${where}: step ${c} is ${step[c]}; steps are finite and > 0`);
    }
  }
  const allowed = relation === 'none' ? [0] : [0, 1];
  if (codingTools && relation === 'mesh') allowed.push(2);
  if (codingTools && relation === 'time') allowed.push(3);
  for (let c = 0; c < cols; c++) {
    if (!allowed.includes(predict[c])) {
      throw formatError('R32-predictor', `${where}: column ${c} has predictor ${predict[c]}; this section allows ${allowed.join(', ')}`);
    }
  }
  return { planes: Number(planes), step, predict };
}

/**
 * The section's `mean_push` (§6.2, version 1.6), checked (R32-predictor): null where absent
 * (push 2 for every column); else a bin of exactly cols bytes each in 0..9, allowed only where
 * `allowed` says (a position U1 or U1.s of a file with flag bit 3; never a field's factor).
 * @param {Map<string, import('./msgpack.js').MsgValue>} entry
 * @param {number} cols
 * @param {boolean} allowed
 * @param {string} where
 * @returns {Uint8Array | null}
 */
function readPush(entry, cols, allowed, where) {
  const push = entry.get('mean_push');
  if (push === undefined) return null;
  if (!allowed) {
    throw formatError('R32-predictor', `${where}: "mean_push" is allowed only in U1 of a file with preamble flag bit 3 (format 1.6)`);
  }
  if (!(push instanceof Uint8Array) || push.length !== cols) {
    throw formatError('R32-predictor', `${where}: "mean_push" is ${describe(push)}, not a bin of ${cols} bytes`);
  }
  for (let c = 0; c < cols; c++) {
    if (push[c] > MAX_PUSH) {
      throw formatError('R32-predictor', `${where}: column ${c} has push ${push[c]}; pushes are 0..${MAX_PUSH}`);
    }
  }
  return push;
}

/**
 * The section's `coder` (§6.14): absent or 0, the zstd planes of §6.1; 1, the adaptive stream,
 * only where `adaptive` allows it; anything else (a float, a bool, nil...) R46.
 * @param {Map<string, import('./msgpack.js').MsgValue>} entry
 * @param {boolean} adaptive
 * @param {string} where
 * @returns {number} ZSTD or ADAPTIVE
 */
function readCoder(entry, adaptive, where) {
  const coder = entry.get('coder');
  if (coder === undefined || coder === ZSTD) return ZSTD;
  if (coder === ADAPTIVE && adaptive) return ADAPTIVE;
  const allowed = adaptive ? '0 or 1' : '0 (1 needs preamble flag bit 3, format 1.6)';
  throw adaptiveError(where, `"coder" is ${describe(coder)}; this section allows ${allowed}`);
}

/**
 * Previous-row parents (§6.2): q[f] = r[f] + q[f − 1], exact; BigInt when past 2^53.
 * @param {Int32Array} stream
 * @param {number} offset
 * @param {number} rows
 */
function restoreRunningSum(stream, offset, rows) {
  const q = new Float64Array(rows);
  let sum = 0;
  let exact = true;
  for (let f = 0; f < rows; f++) {
    sum += stream[offset + f];
    if (sum >= EXACT || sum <= -EXACT) exact = false; // 2^53 + 1 rounds to 2^53: >= catches it
    q[f] = sum;
  }
  if (!exact) {
    // a crafted column: 64-bit sums, then float64(q) rounded to nearest as §6.3 says
    let big = 0n;
    for (let f = 0; f < rows; f++) {
      big += BigInt(stream[offset + f]);
      q[f] = Number(big);
    }
  }
  return q;
}

/**
 * Predictor 3 (§6.2): two running sums, each checked against its range (R32-predictor).
 * @param {Int32Array} stream
 * @param {number} offset
 * @param {number} rows
 * @param {string} where
 */
function restoreLinear(stream, offset, rows, where) {
  const q = new Float64Array(rows);
  let difference = 0;
  let value = 0;
  for (let f = 0; f < rows; f++) {
    difference += stream[offset + f];
    if (difference > LINEAR_STEP || difference < -LINEAR_STEP) {
      throw formatError('R32-predictor', `${where}: the running difference at row ${f} is ${difference}, outside ±2^33`);
    }
    value += difference;
    if (value > LINEAR_VALUE || value < -LINEAR_VALUE) {
      throw formatError('R32-predictor', `${where}: the value at row ${f} is ${value}, outside ±2^32`);
    }
    q[f] = value;
  }
  return q;
}
