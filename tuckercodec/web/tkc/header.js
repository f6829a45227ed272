// The header's fields and the sections' table entries (spec/FORMAT.md §4, §6.6, §6.7; §5 steps
// 10-14, or 10s-13s and 14 for a segmented file). Nothing here reads a payload: the result says
// which section holds what, with every declared size checked against the limits (§7).

import { TkcError, formatError, limitError } from './errors.js';
import { MsgFloat, describe, isInt } from './msgpack.js';
import { FLAG_ADAPTIVE, FLAG_ADAPTIVE_CORRECTIONS, FLAG_CODEBOOKS, FLAG_CODING_TOOLS, FLAG_CORRECTIONS, FLAG_SEGMENTED, FLAG_UNIFORM_RANKS } from './container.js';

/**
 * @typedef {import('./msgpack.js').MsgValue} MsgValue
 * @typedef {import('./limits.js').Limits} Limits
 * @typedef {import('./container.js').Container} Container
 * @typedef {import('./container.js').Section} Section
 */

/**
 * A segment of the file (the whole file when it is not segmented) and its sections (for a
 * shared basis, u1 is the shared U1's entry; resd, its corrections, only with flag bit 2).
 * @typedef {{start: number, frames: number, ranks: number[], u2: Float64Array,
 *   basis: 'whole' | 'shared' | 'own', u1: Section, u3: Section, core: Section,
 *   cent: Section, resd: Section | null}} Segment
 */

/**
 * The layout of the file: which section holds what, every size checked.
 * @typedef {{vertices: number, frames: number, frameRate: number | null,
 *   timeCodes: Float64Array | null, metersPerUnit: number | null, upAxis: string | null,
 *   segmented: boolean,
 *   codingTools: boolean, corrections: boolean, adaptive: boolean, adaptiveCorrections: boolean,
 *   codebooks: boolean, uniformRanks: boolean,
 *   segments: Segment[], face: Section,
 *   faceShape: number[], name: Section | null, sharedU1: Section | null, sharedColumns: number}} Layout
 */

/** @type {(rule: string, message: string) => TkcError} */
const unsupported = (rule, message) => new TkcError('UnsupportedVersionError', rule, message);

/**
 * §6.6: id -> [codec, critical]
 * @type {{[id: string]: [string, boolean]}}
 */
const KINDS = {
  FACE: ['faces-delta', true],
  U1: ['qmat', true],
  U3: ['qmat', true],
  CORE: ['qmat', true],
  CENT: ['qmat', true],
  NAME: ['msgpack-zstd', false],
  RESD: ['residual', true], // §6.9: known only in a file with flag bit 2 (kindOf)
};

/**
 * Steps 10-14 (or 10s-14): the layout of the file.
 * @param {Container} container
 * @param {Limits} limits
 * @returns {Layout}
 */
export function readLayout(container, limits) {
  const { header, sections, flags } = container;
  const segmented = (flags & FLAG_SEGMENTED) !== 0;
  const codingTools = (flags & FLAG_CODING_TOOLS) !== 0;
  const corrections = (flags & FLAG_CORRECTIONS) !== 0;
  const adaptive = (flags & FLAG_ADAPTIVE) !== 0; // §6.14: a position factor may have coder 1
  // (1.7) §6.9: RESD's `coder` is read, and may be 1; without the bit it is an unknown parameter
  const adaptiveCorrections = (flags & FLAG_ADAPTIVE_CORRECTIONS) !== 0;
  // (1.8) §6.9: RESD's `codebooks` is read; without the bit it is an unknown parameter
  const codebooks = (flags & FLAG_CODEBOOKS) !== 0;
  // (1.9) §6.8: faces-traverse's `ranks` is read; without the bit it is an unknown parameter
  const uniformRanks = (flags & FLAG_UNIFORM_RANKS) !== 0;
  // step 10 / 10s
  const K = count(header, 'vertices', limits.max_vertices, 'max_vertices');
  const F = count(header, 'frames', limits.max_frames, 'max_frames');
  /** @type {Segment[]} (their sections are set at step 12) */
  const segments = segmented ? readSegmentIndex(header, K, F, limits) : [wholeSegment(header, K, F, limits)];
  // step 11: every entry known, critical as it should be, with its codec
  const known = knownSections(sections, { segmented, corrections, codingTools }, segments.length);
  // step 12 / 12s: the required sections
  const { face, sharedU1 } = requiredSections(known, segments, segmented, corrections);
  // step 13 / 13s: shapes and sizes
  const [M, n] = faceShape(face, limits);
  let sharedColumns = 0;
  if (segmented) {
    if (sharedU1 !== null) sharedColumns = sharedBasis(sharedU1, segments, K, limits);
    segments.forEach((segment, s) => checkSegmentShapes(segment, s, K, sharedColumns, limits));
  } else {
    const [segment] = segments;
    const [i, k] = segment.ranks;
    expectShape(segment.u1, K, i, limits);
    expectShape(segment.u3, F, k, limits);
    expectShape(segment.core, i * 3 * k, 1, limits);
    expectShape(segment.cent, F, 3, limits);
  }
  // step 14: the frame rate; (1.4) the time codes, the unit and the up axis
  const frameRate = readFrameRate(header);
  const { timeCodes, metersPerUnit, upAxis } = readScene(header, F);
  return { vertices: K, frames: F, frameRate, timeCodes, metersPerUnit, upAxis, segmented, codingTools, corrections, adaptive, adaptiveCorrections, codebooks, uniformRanks, segments, face, faceShape: [M, n], name: known.get('NAME') ?? null, sharedU1, sharedColumns };
}

/**
 * Step 10, not segmented: the one segment of the whole file, its ranks, u2 and sizes checked.
 * @param {Map<string, MsgValue>} header
 * @param {number} K vertices
 * @param {number} F frames
 * @param {Limits} limits
 * @returns {Segment} (its sections are set at step 12)
 */
function wholeSegment(header, K, F, limits) {
  if (K * F > limits.max_positions) {
    throw limitError('R21-header-limit', `vertices × frames = ${K * F} exceeds max_positions = ${limits.max_positions}`);
  }
  const [i, k] = ranks(header.get('ranks'), K, F, 'R22-ranks', 'ranks', Math.min(K, 3 * F));
  const factorValues = K * i + F * k + 3 * i * k + 3 * F;
  if (factorValues > limits.max_factor_values) {
    throw limitError('R21-header-limit', `the factors hold ${factorValues} values, max_factor_values = ${limits.max_factor_values}`);
  }
  return /** @type {Segment} */ ({ start: 0, frames: F, ranks: [i, k], u2: u2(header.get('u2'), 'u2'), basis: 'whole', resd: null });
}

/**
 * Step 11: the sections this decoder knows, by id, each critical as §6.6 says and with a codec
 * it reads; an unknown section is skipped unless it is critical.
 * @param {Section[]} sections the section table
 * @param {{segmented: boolean, corrections: boolean, codingTools: boolean}} flags the file's
 * @param {number} segmentCount
 * @returns {Map<string, Section>}
 */
function knownSections(sections, flags, segmentCount) {
  const known = new Map();
  for (const section of sections) {
    const kind = kindOf(section.id, flags.segmented, flags.corrections, segmentCount);
    if (kind === null) {
      if (section.critical) {
        throw unsupported('R24-unknown-critical-section', `section '${section.id}' is critical and unknown to this decoder`);
      }
      continue;
    }
    const [codec, critical] = KINDS[kind];
    if (section.critical !== critical) {
      throw formatError('R27-criticality', `section '${section.id}' has critical = ${section.critical}; §6.6 says ${critical}`);
    }
    const allowed = kind === 'FACE' && flags.codingTools ? [codec, 'faces-traverse'] : [codec];
    if (!allowed.includes(section.codec)) {
      throw unsupported('R25-unknown-codec', `section '${section.id}' has codec '${section.codec}'; this decoder reads ${allowed.map((c) => `'${c}'`).join(' or ')}`);
    }
    known.set(section.id, section);
  }
  return known;
}

/**
 * Step 12 / 12s: the sections the file must have, set on its segments; FACE, and a segmented
 * file's shared U1 if any segment uses it.
 * @param {Map<string, Section>} known
 * @param {Segment[]} segments
 * @param {boolean} segmented
 * @param {boolean} corrections
 * @returns {{face: Section, sharedU1: Section | null}}
 */
function requiredSections(known, segments, segmented, corrections) {
  /** @param {string} id */
  const need = (id) => {
    const section = known.get(id);
    if (section === undefined) throw formatError('R26-required-section-missing', `the file has no section '${id}'`);
    return section;
  };
  const face = need('FACE');
  let sharedU1 = null;
  if (segmented) {
    if (segments.some((s) => s.basis === 'shared')) sharedU1 = need('U1');
    segments.forEach((segment, s) => {
      segment.u3 = need(`U3.${s}`);
      segment.core = need(`CORE.${s}`);
      segment.cent = need(`CENT.${s}`);
      if (segment.basis === 'own') segment.u1 = need(`U1.${s}`);
    });
    if (corrections) segments.forEach((segment, s) => { segment.resd = need(`RESD.${s}`); });
  } else {
    const [segment] = segments;
    segment.u1 = need('U1');
    segment.u3 = need('U3');
    segment.core = need('CORE');
    segment.cent = need('CENT');
    if (corrections) segment.resd = need('RESD');
  }
  return { face, sharedU1 };
}

/**
 * Step 13s: the shared U1's shape [K, c] and size, set as the u1 of the segments that use it.
 * @param {Section} sharedU1
 * @param {Segment[]} segments
 * @param {number} K
 * @param {Limits} limits
 * @returns {number} its columns, c
 */
function sharedBasis(sharedU1, segments, K, limits) {
  const [rows, cols] = shape(sharedU1);
  if (rows !== K || cols < 1 || cols > K) {
    throw formatError('R28-shape', `section 'U1' has shape [${rows}, ${cols}]; a shared basis is [${K}, c] with 1 <= c <= ${K}`);
  }
  sectionBytes(sharedU1, rows, cols, limits);
  for (const segment of segments) {
    if (segment.basis === 'shared') segment.u1 = sharedU1;
  }
  return cols;
}

/**
 * Step 13s for segment s: its ranks within the shared basis, its sections' shapes, and what it
 * decodes within the limits.
 * @param {Segment} segment
 * @param {number} s its number
 * @param {number} K
 * @param {number} sharedColumns the shared U1's columns (0 without one)
 * @param {Limits} limits
 */
function checkSegmentShapes(segment, s, K, sharedColumns, limits) {
  const [i, k] = segment.ranks;
  if (segment.basis === 'shared' && i > sharedColumns) {
    throw formatError('R38-segment-ranks', `segment ${s} uses ${i} columns of a shared U1 of ${sharedColumns}`);
  }
  if (segment.basis === 'own') expectShape(segment.u1, K, i, limits);
  expectShape(segment.u3, segment.frames, k, limits);
  expectShape(segment.core, i * 3 * k, 1, limits);
  expectShape(segment.cent, segment.frames, 3, limits);
  const basisColumns = segment.basis === 'shared' ? sharedColumns : i;
  const factorValues = K * basisColumns + segment.frames * k + 3 * i * k + 3 * segment.frames;
  if (factorValues > limits.max_factor_values) {
    throw limitError('R21-header-limit', `segment ${s}'s factors hold ${factorValues} values, max_factor_values = ${limits.max_factor_values}`);
  }
  if (K * segment.frames > limits.max_positions) {
    throw limitError('R21-header-limit', `segment ${s} decodes ${K * segment.frames} positions, max_positions = ${limits.max_positions}`);
  }
}

/**
 * Step 14: the frame rate, nil or a finite float > 0 (absent: null).
 * @param {Map<string, MsgValue>} header
 * @returns {number | null}
 */
function readFrameRate(header) {
  if (!header.has('frame_rate')) return null;
  const rate = header.get('frame_rate');
  if (rate === null) return null;
  if (!(rate instanceof MsgFloat) || !Number.isFinite(rate.value) || !(rate.value > 0)) {
    throw formatError('R20-header-field', `"frame_rate" is ${describe(rate)}; it must be nil or a finite float > 0`);
  }
  return rate.value;
}

/**
 * @param {Map<string, MsgValue>} header
 * @param {string} key
 * @param {number} limit
 * @param {string} limitName
 */
function count(header, key, limit, limitName) {
  if (!header.has(key)) throw formatError('R20-header-field', `the header has no "${key}"`);
  const value = header.get(key);
  if (!isInt(value)) throw formatError('R20-header-field', `"${key}" is ${describe(value)}, not an int`);
  if (value > limit) throw limitError('R21-header-limit', `"${key}" is ${value}, ${limitName} = ${limit}`);
  if (value < 1) throw formatError('R20-header-field', `"${key}" is ${value}; it must be at least 1`);
  return Number(value);
}

/**
 * @param {MsgValue | undefined} value
 * @param {number} K
 * @param {number} frames
 * @param {string} rule
 * @param {string} where
 * @param {number} maxI
 */
function ranks(value, K, frames, rule, where, maxI) {
  if (!Array.isArray(value) || value.length !== 2 || !value.every((v) => isInt(v))) {
    throw formatError(rule, `${where} is ${describe(value)}, not an array of two ints`);
  }
  const [i, k] = /** @type {(number | bigint)[]} */ (value);
  const maxK = Math.min(frames, 3 * K);
  if (!(i >= 1 && i <= maxI)) throw formatError(rule, `${where}: i = ${i} is outside 1..${maxI}`);
  if (!(k >= 1 && k <= maxK)) throw formatError(rule, `${where}: k = ${k} is outside 1..${maxK}`);
  return [Number(i), Number(k)];
}

/**
 * @param {MsgValue | undefined} value
 * @param {string} where
 */
function u2(value, where) {
  if (!Array.isArray(value) || value.length !== 9) {
    throw formatError('R23-u2', `${where} is ${value === undefined ? 'missing' : describe(value)}, not an array of 9 floats`);
  }
  const out = new Float64Array(9);
  value.forEach((v, j) => {
    if (!(v instanceof MsgFloat)) throw formatError('R23-u2', `${where}[${j}] is ${describe(v)}, not a float`);
    if (!Number.isFinite(v.value)) throw formatError('R23-u2', `${where}[${j}] is ${v.value}, not finite`);
    out[j] = v.value;
  });
  return out;
}

/**
 * @param {Map<string, MsgValue>} header
 * @param {number} K
 * @param {number} F
 * @param {Limits} limits
 * @returns {Segment[]} (their sections are set by readLayout)
 */
function readSegmentIndex(header, K, F, limits) {
  const index = header.get('segments');
  if (!Array.isArray(index) || index.length === 0) {
    throw formatError('R37-segment-index', `"segments" is ${index === undefined ? 'missing' : describe(index)}, not a non-empty array`);
  }
  if (index.length > limits.max_segments) {
    throw limitError('R21-header-limit', `the file has ${index.length} segments, max_segments = ${limits.max_segments}`);
  }
  let start = 0;
  const segments = index.map((entry, s) => {
    const where = `segment ${s}`;
    if (!(entry instanceof Map)) throw formatError('R37-segment-index', `${where} is ${describe(entry)}, not a map`);
    const frames = entry.get('frames');
    if (!isInt(frames) || frames < 1) {
      throw formatError('R37-segment-index', `${where}: "frames" is ${frames === undefined ? 'missing' : describe(frames)}, not an int >= 1`);
    }
    if (start + Number(frames) > F) {
      throw formatError('R37-segment-index', `${where} ends at frame ${start + Number(frames) - 1}, after the file's last frame ${F - 1}`);
    }
    const basis = entry.get('basis');
    if (basis !== 'shared' && basis !== 'own') {
      throw formatError('R37-segment-index', `${where}: "basis" is ${basis === undefined ? 'missing' : describe(basis)}, not "shared" or "own"`);
    }
    const Fs = Number(frames);
    const maxI = basis === 'own' ? Math.min(K, 3 * Fs) : K;
    const segmentRanks = ranks(entry.get('ranks'), K, Fs, 'R38-segment-ranks', `${where}: "ranks"`, maxI);
    const segment = /** @type {Segment} */ ({ start, frames: Fs, ranks: segmentRanks, u2: u2(entry.get('u2'), `${where}: "u2"`), basis, resd: null });
    start += Fs;
    return segment;
  });
  if (start !== F) throw formatError('R37-segment-index', `the segments hold ${start} frames, the file ${F}`);
  return segments;
}

/**
 * The kind (§6.6) of a section id, or null for an id this file does not know: RESD (RESD.s)
 * is known only in a file with flag bit 2 (§6.9); elsewhere it is unknown, like any other id.
 * @param {string} id
 * @param {boolean} segmented
 * @param {boolean} corrections
 * @param {number} segmentCount
 * @returns {string | null}
 */
function kindOf(id, segmented, corrections, segmentCount) {
  if (id === 'FACE' || id === 'NAME' || id === 'U1') return id;
  if (!segmented) return id in KINDS && (id !== 'RESD' || corrections) ? id : null;
  const match = /^(U1|U3|CORE|CENT|RESD)\.(0|[1-9][0-9]*)$/.exec(id);
  if (match === null || Number(match[2]) >= segmentCount) return null;
  if (match[1] === 'RESD' && !corrections) return null;
  return match[1];
}

/**
 * @param {Section} section
 * @returns {number[]}
 */
function shape(section) {
  const value = section.entry.get('shape');
  if (!Array.isArray(value) || value.length !== 2 || !value.every((v) => isInt(v) && v >= 0)) {
    throw formatError('R28-shape', `section '${section.id}': "shape" is ${value === undefined ? 'missing' : describe(value)}, not an array of two ints >= 0`);
  }
  return /** @type {(number | bigint)[]} */ (value).map((v) => (typeof v === 'bigint' ? Infinity : v));
}

/**
 * @param {Section} face
 * @param {Limits} limits
 */
function faceShape(face, limits) {
  const [M, n] = shape(face);
  if (n < 3) throw formatError('R28-shape', `section 'FACE' has ${n} columns; faces have at least 3`);
  if (M > limits.max_faces) throw limitError('R21-header-limit', `section 'FACE' has ${M} faces, max_faces = ${limits.max_faces}`);
  if (n > limits.max_face_width) {
    throw limitError('R21-header-limit', `section 'FACE' is ${n} wide, max_face_width = ${limits.max_face_width}`);
  }
  sectionBytes(face, M, n, limits);
  return [M, n];
}

/**
 * @param {Section} section
 * @param {number} rows
 * @param {number} cols
 * @param {Limits} limits
 */
function expectShape(section, rows, cols, limits) {
  const [r, c] = shape(section);
  if (r !== rows || c !== cols) {
    throw formatError('R28-shape', `section '${section.id}' has shape [${r}, ${c}]; the header makes it [${rows}, ${cols}]`);
  }
  sectionBytes(section, rows, cols, limits);
}

/**
 * @param {Section} section
 * @param {number} rows
 * @param {number} cols
 * @param {Limits} limits
 */
function sectionBytes(section, rows, cols, limits) {
  if (rows * cols * 4 > limits.max_section_bytes) {
    throw limitError('R21-header-limit', `section '${section.id}' decodes to ${rows * cols * 4} bytes, max_section_bytes = ${limits.max_section_bytes}`);
  }
}

/**
 * §4 (1.4): `time_codes` (nil, or a bin of F little-endian binary64, finite and increasing),
 * `meters_per_unit` (nil, or a finite float > 0) and `up_axis` (nil, "Y" or "Z"); R20.
 * @param {Map<string, MsgValue>} header
 * @param {number} F
 * @returns {{timeCodes: Float64Array | null, metersPerUnit: number | null, upAxis: string | null}}
 */
function readScene(header, F) {
  let timeCodes = null;
  const codes = header.get('time_codes') ?? null;
  if (codes !== null) {
    if (!(codes instanceof Uint8Array) || codes.length !== 8 * F) {
      throw formatError('R20-header-field', `"time_codes" is ${describe(codes)}; it must be nil or a bin of ${8 * F} bytes`);
    }
    const view = new DataView(codes.buffer, codes.byteOffset, codes.length);
    timeCodes = new Float64Array(F);
    for (let f = 0; f < F; f++) {
      const code = view.getFloat64(8 * f, true);
      if (!Number.isFinite(code) || (f > 0 && !(code > timeCodes[f - 1]))) {
        throw formatError('R20-header-field', `"time_codes" frame ${f} is ${code}; they must be finite and increase`);
      }
      timeCodes[f] = code;
    }
  }
  let metersPerUnit = null;
  const unit = header.get('meters_per_unit') ?? null;
  if (unit !== null) {
    if (!(unit instanceof MsgFloat) || !Number.isFinite(unit.value) || !(unit.value > 0)) {
      throw formatError('R20-header-field', `"meters_per_unit" is ${describe(unit)}; it must be nil or a finite float > 0`);
    }
    metersPerUnit = unit.value;
  }
  const axis = header.get('up_axis') ?? null;
  if (axis !== null && axis !== 'Y' && axis !== 'Z') {
    throw formatError('R20-header-field', `"up_axis" is ${describe(axis)}; it must be nil, "Y" or "Z"`);
  }
  return { timeCodes, metersPerUnit, upAxis: axis };
}
