// Section FSET (codec `face-sets`, format 1.5, spec/FORMAT.md §6.12): named sets of faces
// (materials, groups, GeomSubsets). Each set's face numbers (in the given order, §6.10) are
// strictly increasing; the one integer stream (§6.1) holds, set after set, the first number and
// then each number's difference from the one before less one.

import { formatError, limitError } from './errors.js';
import { describe, isInt } from './msgpack.js';
import { nameProblem } from './attributes.js';
import { decodeIntStream } from './streams.js';

const RULE = 'R44-face-sets';
const WHERE = "section 'FSET'";

/**
 * @typedef {{name: string, family: string, faces: Uint32Array}} FaceSet a set's name, its
 *   family (`materialBind` for materials, `group` for OBJ groups, any other, or ""), and its
 *   faces' numbers in the given order, increasing
 */

/** @param {string} message @returns {never} */
function refuse(message) {
  throw formatError(RULE, `${WHERE}: ${message}`);
}

/**
 * The `sets` table: [name, family, count 0..M] each (R44), no more than max_sections (R21).
 * @param {import('./msgpack.js').MsgValue | undefined} table
 * @param {number} M
 * @param {import('./limits.js').Limits} limits
 * @returns {[string, string, number][]}
 */
function checkedTable(table, M, limits) {
  if (!Array.isArray(table)) refuse(`"sets" must be an array, got ${table === undefined ? 'nothing' : describe(table)}`);
  if (table.length > limits.max_sections) {
    throw limitError('R21-header-limit', `${WHERE}: ${table.length} face sets exceed this decoder's limit max_sections = ${limits.max_sections}`);
  }
  return table.map((entry, n) => {
    if (
      !Array.isArray(entry) || entry.length !== 3 || typeof entry[0] !== 'string' || entry[0].length === 0
      || typeof entry[1] !== 'string' || !isInt(entry[2]) || !(entry[2] >= 0 && entry[2] <= M)
    ) {
      refuse(`set ${n} must be [name, family, count 0..${M}], got ${describe(entry)}`);
    }
    return /** @type {[string, string, number]} */ ([entry[0], entry[1], Number(entry[2])]);
  });
}

/**
 * The face sets of FSET: the table (R44, R21), the stream's size against the limits (R21), its
 * planes (R30) and stream (R29), then each set's numbers increasing and faces (R44).
 * @param {import('./container.js').Section} section the FSET entry
 * @param {Uint8Array} payload its bytes, CRC already checked
 * @param {number} M the faces
 * @param {import('./limits.js').Limits} limits
 * @returns {FaceSet[]}
 */
export function decodeFaceSets(section, payload, M, limits) {
  const table = checkedTable(section.entry.get('sets'), M, limits);
  const total = table.reduce((sum, [, , count]) => sum + count, 0);
  if (total * 4 > limits.max_section_bytes) {
    throw limitError('R21-header-limit', `${WHERE}: ${total} face numbers exceed this decoder's limit max_section_bytes = ${limits.max_section_bytes}`);
  }
  const planes = section.entry.get('planes');
  if (!isInt(planes) || planes < 1 || planes > 4) {
    throw formatError('R30-planes', `${WHERE}: "planes" is ${planes === undefined ? 'missing' : describe(planes)}, not an int in 1..4`);
  }
  const stream = decodeIntStream(payload, total, Number(planes), WHERE);
  let start = 0;
  // one past the last face of the nearest earlier set that has any: where the next set's first
  // face is counted from
  let following = 0;
  const named = new Set();
  return table.map(([name, family, count]) => {
    const key = JSON.stringify([family, name]);
    if (named.has(key)) refuse(`two sets of family ${JSON.stringify(family)} are named ${JSON.stringify(name)}`);
    named.add(key);
    const steps = stream.subarray(start, start + count);
    start += count;
    for (let j = 1; j < count; j++) if (steps[j] < 0) refuse(`set ${JSON.stringify(name)}: its face numbers do not increase`);
    const faces = new Uint32Array(count);
    // increasing after the first, so the last is the largest: the sum is exact until it is
    // beyond every face
    const first = following + (count ? steps[0] : 0);
    let face = first;
    for (let j = 0; j < count; j++) {
      if (j) face += steps[j] + 1;
      faces[j] = face;
    }
    if (count && !(first >= 0 && face < M)) refuse(`set ${JSON.stringify(name)} names a face outside 0..${M - 1}`);
    if (count) following = face + 1;
    const problem = nameProblem(name) ?? (family ? nameProblem(family) : null);
    if (problem !== null) refuse(`set ${JSON.stringify(name)}: its name or family ${problem}`);
    return { name, family, faces };
  });
}
