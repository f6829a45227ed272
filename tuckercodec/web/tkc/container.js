// The container (spec/FORMAT.md §2, §3, §5 steps 1-9): signature, preamble, header bytes and
// their CRCs, and the section table. Nothing here reads a payload; `sectionPayload` checks a
// section's CRC when the section is about to be decoded (step 9).

import { crc32 } from './crc32.js';
import { TkcError, formatError, limitError } from './errors.js';
import { MsgpackProblem, describe, unpack } from './msgpack.js';

export const SIGNATURE = Object.freeze([0x89, 0x54, 0x4b, 0x43, 0x0d, 0x0a, 0x1a, 0x0a]);
export const FLAG_SEGMENTED = 1 << 0; // §6.7, version 1.1
export const FLAG_CODING_TOOLS = 1 << 1; // §6.8, version 1.2
export const FLAG_CORRECTIONS = 1 << 2; // §6.9 and §8.1, version 1.3
export const FLAG_ADAPTIVE = 1 << 3; // §6.14, version 1.6
export const FLAG_ADAPTIVE_CORRECTIONS = 1 << 4; // §6.9's adaptive chunks, version 1.7
export const FLAG_CODEBOOKS = 1 << 5; // §6.9's codebooks, version 1.8
export const FLAG_UNIFORM_RANKS = 1 << 6; // §6.8's new vertices in a uniform stream, version 1.9
const KNOWN_CRITICAL_FLAGS = FLAG_SEGMENTED | FLAG_CODING_TOOLS | FLAG_CORRECTIONS | FLAG_ADAPTIVE | FLAG_ADAPTIVE_CORRECTIONS | FLAG_CODEBOOKS | FLAG_UNIFORM_RANKS;
const PREAMBLE_END = 32;

/**
 * @typedef {import('./msgpack.js').MsgValue} MsgValue
 * @typedef {import('./limits.js').Limits} Limits
 */

/**
 * An entry of the section table (§3), every field checked; `entry` is the whole msgpack map,
 * parameters included.
 * @typedef {{id: string, offset: number, length: number, crc32: number, critical: boolean,
 *   codec: string, entry: Map<string, MsgValue>}} Section
 */

/**
 * What steps 1-8 read.
 * @typedef {{major: number, minor: number, flags: number, headerLength: number,
 *   totalLength: number, header: Map<string, MsgValue>, sections: Section[],
 *   dataStart: number}} Container
 */

/** @type {(rule: string, message: string) => TkcError} */
const truncated = (rule, message) => new TkcError('TruncatedFileError', rule, message);
/** @type {(rule: string, message: string) => TkcError} */
const checksum = (rule, message) => new TkcError('ChecksumError', rule, message);
/** @type {(rule: string, message: string) => TkcError} */
const unsupported = (rule, message) => new TkcError('UnsupportedVersionError', rule, message);

/**
 * Steps 1-8 of §5 on the whole file.
 * @param {Uint8Array} bytes
 * @param {Limits} limits
 * @returns {Container}
 */
export function readContainer(bytes, limits) {
  const size = bytes.length;
  // step 1: the signature
  if (size < 8) throw truncated('R03-preamble-truncated', `the file has ${size} bytes, a preamble needs 32`);
  if (bytes[1] !== 0x54 || bytes[2] !== 0x4b || bytes[3] !== 0x43) {
    throw formatError('R01-signature', 'not a tuckercodec file (bytes 1-3 are not "TKC")');
  }
  if (bytes[0] !== SIGNATURE[0]) {
    throw formatError('R02-signature-transfer', 'signature byte 0 lost its high bit: the file went through a 7-bit channel');
  }
  for (let i = 4; i < 8; i++) {
    if (bytes[i] !== SIGNATURE[i]) {
      throw formatError('R02-signature-transfer', 'the signature\'s line-ending bytes 4-7 changed: the file went through a text-mode transfer');
    }
  }
  // step 2: the preamble's CRC
  if (size < PREAMBLE_END) {
    throw truncated('R03-preamble-truncated', `the file has ${size} bytes, a preamble needs 32`);
  }
  const view = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
  const storedPreambleCrc = view.getUint32(28, true);
  const preambleCrc = crc32(bytes.subarray(0, 28));
  if (storedPreambleCrc !== preambleCrc) {
    throw checksum('R04-preamble-crc', `preamble_crc is 0x${hex(storedPreambleCrc)}, bytes 0..27 give 0x${hex(preambleCrc)}`);
  }
  const major = view.getUint16(8, true);
  const minor = view.getUint16(10, true);
  const flags = view.getUint32(12, true);
  const headerLength = view.getUint32(16, true);
  const totalLength = view.getUint32(20, true) + view.getUint32(24, true) * 2 ** 32;
  // step 3: version and critical flags
  if (major !== 1) throw unsupported('R05-major-version', `format major version ${major}; this decoder reads 1`);
  const unknown = flags & 0xffff & ~KNOWN_CRITICAL_FLAGS;
  if (unknown) {
    throw unsupported('R06-critical-flag', `critical flag bits 0x${hex(unknown)} are set; this decoder knows bits 0 to 6 (version 1.9)`);
  }
  // step 4: the header's size
  if (headerLength > limits.max_header_bytes) {
    throw limitError('R07-header-limit', `header_length ${headerLength} exceeds max_header_bytes = ${limits.max_header_bytes}`);
  }
  if (totalLength < 36 + headerLength) {
    throw formatError('R08-total-length', `total_length ${totalLength} is below 36 + header_length (${36 + headerLength})`);
  }
  // step 5: nothing after the file
  if (size > totalLength) {
    throw formatError('R09-trailing-bytes', `${size - totalLength} bytes follow the file's total_length of ${totalLength}`);
  }
  // step 6: the header's CRC, then the whole file present
  const headerEnd = PREAMBLE_END + headerLength;
  if (size < headerEnd + 4) {
    throw truncated('R10-file-truncated', `the file has ${size} of its ${totalLength} bytes`);
  }
  const storedHeaderCrc = view.getUint32(headerEnd, true);
  const headerBytes = bytes.subarray(PREAMBLE_END, headerEnd);
  const headerCrc = crc32(headerBytes);
  if (storedHeaderCrc !== headerCrc) {
    throw checksum('R11-header-crc', `header_crc is 0x${hex(storedHeaderCrc)}, the header gives 0x${hex(headerCrc)}`);
  }
  if (size < totalLength) {
    throw truncated('R10-file-truncated', `the file has ${size} of its ${totalLength} bytes`);
  }
  // step 7: one msgpack map
  let header;
  try {
    header = unpack(headerBytes);
  } catch (error) {
    if (error instanceof MsgpackProblem) throw formatError('R12-header-not-map', `header: ${error.message}`);
    throw error;
  }
  if (!(header instanceof Map)) {
    throw formatError('R12-header-not-map', `the header is ${describe(header)}, not a map`);
  }
  // step 8: the section table
  const dataStart = headerEnd + 4;
  const sections = readSectionTable(header, totalLength - dataStart, limits);
  return { major, minor, flags, headerLength, totalLength, header, sections, dataStart };
}

/** @type {[string, (value: MsgValue | undefined) => boolean, string][]} */
const ENTRY_FIELDS = [
  ['id', (v) => typeof v === 'string', 'a str'],
  ['offset', isIntValue, 'an int'],
  ['length', isIntValue, 'an int'],
  ['crc32', isIntValue, 'an int'],
  ['critical', (v) => typeof v === 'boolean', 'a bool'],
  ['codec', (v) => typeof v === 'string', 'a str'],
];

/** @param {MsgValue | undefined} value */
function isIntValue(value) {
  return (typeof value === 'number' && Number.isInteger(value)) || typeof value === 'bigint';
}

/**
 * @param {Map<string, MsgValue>} header
 * @param {number} dataLength
 * @param {Limits} limits
 * @returns {Section[]}
 */
function readSectionTable(header, dataLength, limits) {
  const table = header.get('sections');
  if (!Array.isArray(table)) {
    throw formatError('R13-section-table-missing', table === undefined ? 'the header has no "sections"' : `"sections" is ${describe(table)}, not an array`);
  }
  if (table.length > limits.max_sections) {
    throw limitError('R21-header-limit', `the section table has ${table.length} entries, max_sections = ${limits.max_sections}`);
  }
  const seen = new Set();
  /** @type {Section[]} */
  const sections = [];
  let expectedOffset = 0;
  table.forEach((entry, index) => {
    const where = `section table entry ${index}`;
    if (!(entry instanceof Map)) throw formatError('R14-section-entry-field', `${where} is ${describe(entry)}, not a map`);
    for (const [field, test, kind] of ENTRY_FIELDS) {
      if (!entry.has(field)) throw formatError('R14-section-entry-field', `${where} has no "${field}"`);
      if (!test(entry.get(field))) {
        throw formatError('R14-section-entry-field', `${where}: "${field}" is ${describe(entry.get(field))}, not ${kind}`);
      }
    }
    // the types ENTRY_FIELDS checked
    const id = /** @type {string} */ (entry.get('id'));
    if (id.length < 1 || id.length > 16 || !/^[\x20-\x7e]+$/.test(id)) {
      throw formatError('R14-section-entry-field', `${where}: the id '${id}' is not 1 to 16 printable ASCII characters`);
    }
    const named = `section '${id}'`;
    if (seen.has(id)) throw formatError('R15-section-duplicate-id', `${named} appears twice in the section table`);
    seen.add(id);
    const offset = /** @type {number | bigint} */ (entry.get('offset'));
    if (offset !== expectedOffset) {
      throw formatError('R16-section-not-contiguous', `${named} starts at offset ${offset}, the sections before it end at ${expectedOffset}`);
    }
    const length = /** @type {number | bigint} */ (entry.get('length'));
    if (typeof length === 'bigint' || length < 0 || offset + length > dataLength) {
      throw formatError('R17-section-past-end', `${named} (offset ${offset}, length ${length}) does not lie inside the data area of ${dataLength} bytes`);
    }
    const crc = /** @type {number | bigint} */ (entry.get('crc32'));
    if (typeof crc === 'bigint' || crc < 0 || crc > 0xffffffff) {
      throw formatError('R14-section-entry-field', `${named}: crc32 ${crc} is not in 0..2^32-1`);
    }
    expectedOffset = offset + length;
    const critical = /** @type {boolean} */ (entry.get('critical'));
    const codec = /** @type {string} */ (entry.get('codec'));
    sections.push({ id, offset, length, crc32: crc, critical, codec, entry });
  });
  if (expectedOffset !== dataLength) {
    throw formatError('R18-section-coverage', `the sections cover ${expectedOffset} bytes of a data area of ${dataLength}`);
  }
  return sections;
}

/**
 * A section's payload, its CRC checked first (§5 step 9, R19-section-crc).
 * @param {Uint8Array} bytes the whole file
 * @param {number} dataStart where the data area starts
 * @param {Section} section an entry of readContainer's `sections`
 * @returns {Uint8Array}
 */
export function sectionPayload(bytes, dataStart, section) {
  const start = dataStart + section.offset;
  const payload = bytes.subarray(start, start + section.length);
  const crc = crc32(payload);
  if (crc !== section.crc32) {
    throw checksum('R19-section-crc', `section '${section.id}': crc32 is 0x${hex(section.crc32)}, its payload gives 0x${hex(crc)}`);
  }
  return payload;
}

/** @param {number} value */
function hex(value) {
  return value.toString(16).toUpperCase().padStart(8, '0');
}
