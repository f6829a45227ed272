// Section ORDER (codec `face-order`, format 1.5, spec/FORMAT.md §6.10): for the t-th face of
// FACE's walk, its number in the order the faces were given, as the differences of consecutive
// numbers less one in an integer stream (§6.1). The decoder puts the faces back in that order.

import { formatError } from './errors.js';
import { describe, isInt } from './msgpack.js';
import { decodeIntStream } from './streams.js';

const RULE = 'R42-face-order';

/**
 * The given number of each decoded face: a permutation of 0..M-1 (R42), after the parameters
 * `faces` (R42) and `planes` (R30).
 * @param {import('./container.js').Section} section the ORDER entry
 * @param {Uint8Array} payload its bytes, CRC already checked
 * @param {number} M the FACE section's faces
 * @returns {Int32Array}
 */
export function decodeFaceOrder(section, payload, M) {
  const faces = section.entry.get('faces');
  if (!isInt(faces) || Number(faces) !== M) {
    throw formatError(RULE, `section 'ORDER': "faces" must be the FACE section's ${M} faces, got ${faces === undefined ? 'nothing' : describe(faces)}`);
  }
  const planes = section.entry.get('planes');
  if (!isInt(planes) || planes < 1 || planes > 4) {
    throw formatError('R30-planes', `section 'ORDER': "planes" is ${planes === undefined ? 'missing' : describe(planes)}, not an int in 1..4`);
  }
  const steps = decodeIntStream(payload, M, Number(planes), "section 'ORDER'");
  const order = new Int32Array(M);
  const seen = new Uint8Array(M);
  // each number is checked as it is made, so the running sum stays exact
  let number = -1;
  for (let t = 0; t < M; t++) {
    number += steps[t] + 1;
    if (number < 0 || number >= M) {
      throw formatError(RULE, `section 'ORDER': face ${t} of the walk has the number ${number}, outside 0..${M - 1}`);
    }
    order[t] = number;
    seen[number] = 1;
  }
  const missing = seen.indexOf(0);
  if (missing >= 0) {
    throw formatError(RULE, `section 'ORDER': no face has the number ${missing}: the numbers are not a permutation`);
  }
  return order;
}

/**
 * The faces of the walk (M × n, as FACE decodes them) put back in the given order.
 * @param {Int32Array} walked
 * @param {Int32Array} order
 * @param {number} n the face width
 */
export function inGivenOrder(walked, order, n) {
  const given = new Int32Array(walked.length);
  for (let t = 0; t < order.length; t++) given.set(walked.subarray(t * n, (t + 1) * n), order[t] * n);
  return given;
}
