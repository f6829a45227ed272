// Sections ATTR.n (codec `attribute`, format 1.5, spec/FORMAT.md §6.11): static attributes
// (UVs, normals, colours...), bit for bit. An attribute is a table of `rows` rows of `cols`
// values (float32, float64 or int32) and, when indexed, an index per element (vertex, corner or
// face) into the table.
//
// The values are stored as their ordered integers (§6.9; an int32 is its own), component by
// component, and with `predict` 1 each as its difference from the row before, wrapping in the
// type's width. The indices are stored less their prediction: a corner's, the index its vertex
// used last; a first use, one more than the largest so far; a face's, the face before's.
// Both streams are §6.1's zigzag byte planes, up to 8 of them: they are decoded as 64-bit
// integers held in 32-bit halves (streams.js decodeWideStream), so the float64 bit patterns are
// made exactly, with no BigInt per value.
//
// checkAttributeParams checks the parameters in the order of §6.11 (R43-attribute), then the
// streams' sizes against the limits (R21), before the payload is read; decodeAttribute decodes.

import { formatError, limitError } from './errors.js';
import { describe, isInt } from './msgpack.js';
import { decodeWideStream } from './streams.js';

const RULE = 'R43-attribute';
export const DOMAINS = Object.freeze(['vertex', 'corner', 'face']);
export const ROLES = Object.freeze(['uv', 'normal', 'color', 'generic']);
/** The components each role allows: a role that does not fit is read as `generic`. */
const ROLE_COMPONENTS = Object.freeze({ uv: [2], normal: [3], color: [3, 4], generic: [1, 2, 3, 4] });
const TYPES = Object.freeze(['f32', 'f64', 'i32']);
/** The longest name in UTF-8 bytes (the model's). */
export const MAX_NAME_BYTES = 255;

/**
 * @typedef {Float32Array | Float64Array | Int32Array} AttributeValues
 * @typedef {{name: string, domain: 'vertex' | 'corner' | 'face',
 *   role: 'uv' | 'normal' | 'color' | 'generic', type: 'f32' | 'f64' | 'i32', rows: number,
 *   components: number, values: AttributeValues, indices: Uint32Array | null}} Attribute
 *   An attribute as decoded: `values` holds rows × components values row-major (each row a
 *   value's components), the same bits the encoder was given; `indices` (one per element, into
 *   the rows) or null, when there is a row per element.
 * @typedef {{name: string, domain: 'vertex' | 'corner' | 'face',
 *   role: 'uv' | 'normal' | 'color' | 'generic', type: 'f32' | 'f64' | 'i32', rows: number,
 *   cols: number, indexed: boolean, predict: number, elements: number,
 *   streams: number[][]}} AttributeParams
 * @typedef {{vertices: number, faces: Int32Array, faceCount: number, faceWidth: number,
 *   corners: number}} Mesh the faces in the given order (§6.10) and their counts
 */

/**
 * Why a name is not one the model allows (1 to 255 UTF-8 bytes, no control character), or null.
 * @param {string} name
 */
export function nameProblem(name) {
  if (name.length === 0) return 'is empty';
  if (new TextEncoder().encode(name).length > MAX_NAME_BYTES) return `is longer than ${MAX_NAME_BYTES} bytes`;
  // eslint-disable-next-line no-control-regex
  if (/[\x00-\x1f\x7f]/.test(name)) return 'has a control character';
  return null;
}

/**
 * The number of elements of a domain.
 * @param {string} domain
 * @param {Mesh} mesh
 */
function elementCount(domain, mesh) {
  if (domain === 'face') return mesh.faceCount;
  if (domain === 'corner') return mesh.corners;
  return mesh.vertices;
}

/**
 * @param {string} where
 * @param {string} message
 * @returns {never}
 */
function refuse(where, message) {
  throw formatError(RULE, `${where}: ${message}`);
}

/**
 * A non-empty str parameter, or R43.
 * @param {Map<string, import('./msgpack.js').MsgValue>} entry
 * @param {string} key
 * @param {string} where
 */
function strParam(entry, key, where) {
  const value = entry.get(key);
  if (typeof value !== 'string' || value.length === 0) refuse(where, `"${key}" must be a non-empty str, got ${shown(value)}`);
  return value;
}

/** @param {import('./msgpack.js').MsgValue | undefined} value */
function shown(value) {
  return value === undefined ? 'nothing' : describe(value);
}

/**
 * §5 step 19 for one ATTR section's parameters, in the order of §6.11 (R43), then its streams'
 * sizes against the limits (R21): everything checked before the payload is read.
 * @param {import('./container.js').Section} section
 * @param {Mesh} mesh
 * @param {import('./limits.js').Limits} limits
 * @returns {AttributeParams}
 */
export function checkAttributeParams(section, mesh, limits) {
  const entry = section.entry;
  const where = `section '${section.id}'`;
  const name = strParam(entry, 'name', where);
  const domain = strParam(entry, 'domain', where);
  if (!DOMAINS.includes(domain)) refuse(where, `"domain" must be one of ${DOMAINS.join(', ')}, got '${domain}'`);
  const givenRole = entry.get('role');
  let role = typeof givenRole === 'string' && ROLES.includes(givenRole) ? givenRole : 'generic';
  const type = strParam(entry, 'type', where);
  if (!TYPES.includes(type)) refuse(where, `"type" must be one of ${TYPES.join(', ')}, got '${type}'`);
  const shape = entry.get('shape');
  if (!Array.isArray(shape) || shape.length !== 2 || !shape.every(isInt) || shape[0] < 0 || !(shape[1] >= 1 && shape[1] <= 4)) {
    refuse(where, `"shape" must be [rows >= 0, components 1..4], got ${shown(shape)}`);
  }
  const rows = BigInt(/** @type {number | bigint} */ (shape[0]));
  const cols = Number(shape[1]);
  const indexed = entry.get('indexed');
  if (typeof indexed !== 'boolean') refuse(where, `"indexed" must be a bool, got ${shown(indexed)}`);
  const elements = elementCount(domain, mesh);
  if (!indexed && rows !== BigInt(elements)) {
    refuse(where, `an attribute that is not indexed has one row per ${domain}: ${elements}, not ${rows}`);
  }
  const predict = entry.get('predict');
  if (!isInt(predict)) refuse(where, `"predict" must be an int, got ${shown(predict)}`);
  if (predict !== 0 && predict !== 1) refuse(where, `"predict" must be 0 or 1, got ${predict}`);
  const table = checkedStreams(entry.get('streams'), section.length, where);
  const want = [rows * BigInt(cols), BigInt(indexed ? elements : 0)];
  table.forEach((stream, n) => {
    if (stream[0] !== want[n]) refuse(where, `stream ${n} must hold ${want[n]} values, not ${stream[0]}`);
  });
  if (!(/** @type {{[role: string]: number[]}} */ (ROLE_COMPONENTS)[role].includes(cols))) role = 'generic'; // a role is a hint
  for (const [count, planes] of table) {
    if (count * planes > BigInt(limits.max_section_bytes)) {
      throw limitError('R21-header-limit', `${where}: ${count} values of ${planes} bytes exceed this decoder's limit max_section_bytes = ${limits.max_section_bytes}`);
    }
  }
  return {
    name, domain: /** @type {AttributeParams['domain']} */ (domain), role: /** @type {AttributeParams['role']} */ (role),
    type: /** @type {AttributeParams['type']} */ (type), rows: Number(rows), cols, indexed, predict, elements,
    streams: table.map((stream) => stream.map(Number)),
  };
}

/**
 * The `streams` parameter: two [count, planes 1..8, length] of ints >= 0 whose lengths add up
 * to the payload's (R43), as BigInts (the caller compares products of them exactly).
 * @param {import('./msgpack.js').MsgValue | undefined} table
 * @param {number} payloadLength
 * @param {string} where
 * @returns {bigint[][]}
 */
function checkedStreams(table, payloadLength, where) {
  if (!Array.isArray(table) || table.length !== 2) refuse(where, '"streams" must be an array of two [count, planes, length]');
  const checked = table.map((stream, n) => {
    const ints = Array.isArray(stream) && stream.length === 3 && stream.every((x) => isInt(x) && x >= 0)
      ? stream.map((x) => BigInt(/** @type {number | bigint} */ (x))) : null;
    if (ints === null || !(ints[1] >= 1n && ints[1] <= 8n)) {
      refuse(where, `stream ${n} must be [count, planes 1..8, length] of ints >= 0, got ${shown(stream)}`);
    }
    return ints;
  });
  const total = checked[0][2] + checked[1][2];
  if (total !== BigInt(payloadLength)) refuse(where, `the streams' lengths add up to ${total}, the payload has ${payloadLength} bytes`);
  return checked;
}

/**
 * The attribute of an ATTR section whose parameters checkAttributeParams gave.
 * @param {AttributeParams} params
 * @param {Uint8Array} payload its bytes, CRC already checked
 * @param {Mesh} mesh
 * @param {string} id the section's id, for messages
 * @returns {Attribute}
 */
export function decodeAttribute(params, payload, mesh, id) {
  const where = `section '${id}'`;
  const [[valueCount, valuePlanes, valueLength], [indexCount, indexPlanes]] = params.streams;
  const stream = decodeWideStream(payload.subarray(0, valueLength), valueCount, valuePlanes, `${where} values`);
  const values = valuesOf(stream, params);
  let indices = null;
  if (params.indexed) {
    const residuals = decodeWideStream(payload.subarray(valueLength), indexCount, indexPlanes, `${where} indices`);
    indices = params.domain === 'face' ? faceIndices(residuals, params.rows, where) : predictedIndices(residuals, params, mesh, where);
  }
  const problem = nameProblem(params.name);
  if (problem !== null) refuse(where, `the name ${JSON.stringify(params.name)} ${problem}`);
  const { name, domain, role, type, rows, cols: components } = params;
  return { name, domain, role, type, rows, components, values, indices };
}

/**
 * The values from their stream (component-major ordered integers, predicted): each row's
 * components together, as the bits of the type.
 * @param {Int32Array} stream 64-bit halves
 * @param {AttributeParams} params
 * @returns {AttributeValues}
 */
function valuesOf(stream, params) {
  const { rows, cols, type, predict } = params;
  const wide = type === 'f64';
  const bits = new Int32Array(rows * cols * (wide ? 2 : 1));
  for (let c = 0; c < cols; c++) {
    let lo = 0;
    let hi = 0;
    for (let r = 0; r < rows; r++) {
      const j = 2 * (c * rows + r);
      if (predict === 1) {
        // the running sum wraps in the type's width: 64 bits carry from the low half
        const sum = (lo >>> 0) + (stream[j] >>> 0);
        hi = wide ? (hi + stream[j + 1] + (sum > 0xffffffff ? 1 : 0)) | 0 : (sum | 0) >> 31;
        lo = sum | 0;
      } else {
        lo = stream[j];
        hi = stream[j + 1];
      }
      // the ordered integer o of a negative pattern is o XOR 0x7FF...F (§6.9); with predict 0
      // a 32-bit type keeps the low half of the 64-bit value, its sign that of the whole
      const at = r * cols + c;
      if (wide) {
        bits[2 * at] = hi < 0 ? ~lo : lo;
        bits[2 * at + 1] = hi < 0 ? hi ^ 0x7fffffff : hi;
      } else {
        bits[at] = type === 'f32' && hi < 0 ? lo ^ 0x7fffffff : lo;
      }
    }
  }
  if (type === 'f64') return new Float64Array(bits.buffer);
  if (type === 'f32') return new Float32Array(bits.buffer);
  return bits;
}

/**
 * A residual of 64 bits as a Number: exact within ±2^53; beyond, a value out of every range.
 * @param {Int32Array} halves
 * @param {number} j
 */
function residualAt(halves, j) {
  return halves[2 * j + 1] * 4294967296 + (halves[2 * j] >>> 0);
}

/**
 * Face-domain indices: each the one before plus its residual (a running sum wrapping at 64
 * bits, as the reference's), each checked to name a row (R43).
 * @param {Int32Array} residuals 64-bit halves
 * @param {number} rows
 * @param {string} where
 */
function faceIndices(residuals, rows, where) {
  const count = residuals.length / 2;
  const indices = new Uint32Array(count);
  let lo = 0;
  let hi = 0;
  let bad = -1;
  for (let e = 0; e < count; e++) {
    const sum = (lo >>> 0) + (residuals[2 * e] >>> 0);
    hi = (hi + residuals[2 * e + 1] + (sum > 0xffffffff ? 1 : 0)) | 0;
    lo = sum | 0;
    if (hi !== 0 || lo >>> 0 >= rows) {
      if (bad < 0) bad = e;
    } else {
      indices[e] = lo;
    }
  }
  if (bad >= 0) refuse(where, `element ${bad} has an index outside 0..${rows - 1}`);
  return indices;
}

/**
 * Vertex- and corner-domain indices: a corner's predicted by the index its vertex used last,
 * else (and a vertex's) by one more than the largest so far; each checked to name a row (R43).
 * @param {Int32Array} residuals 64-bit halves
 * @param {AttributeParams} params
 * @param {Mesh} mesh
 * @param {string} where
 */
function predictedIndices(residuals, params, mesh, where) {
  const { rows, elements, domain } = params;
  const indices = new Uint32Array(elements);
  const corners = domain === 'corner';
  // the index each vertex used last, or -1
  const lastUsed = corners ? new Float64Array(mesh.vertices).fill(-1) : null;
  const faces = mesh.faces;
  let largest = -1;
  let j = 0; // the corner's entry in the face table
  for (let e = 0; e < elements; e++) {
    let predicted = largest + 1;
    let vertex = -1;
    if (lastUsed !== null) {
      while (faces[j] < 0) j++;
      vertex = faces[j++];
      if (lastUsed[vertex] >= 0) predicted = lastUsed[vertex];
    }
    const index = predicted + residualAt(residuals, e);
    if (!(index >= 0 && index < rows)) refuse(where, `element ${e} has index ${index}, outside 0..${rows - 1}`);
    if (lastUsed !== null) lastUsed[vertex] = index;
    indices[e] = index;
    if (index > largest) largest = index;
  }
  return indices;
}
