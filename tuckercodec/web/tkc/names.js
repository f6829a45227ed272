// Section NAME (spec/FORMAT.md §6.5): one str per frame in a msgpack array, in one zstd frame.
// When absent, frame f is "frame_" and f zero-padded to 5 digits.

import { formatError, limitError } from './errors.js';
import { MsgpackProblem, describe, isInt, unpack } from './msgpack.js';
import { decompressExact } from './zstd.js';

/**
 * The `size` parameter (checked before the CRC, §5 step 17).
 * @param {import('./container.js').Section} section
 * @param {import('./limits.js').Limits} limits
 */
export function nameSize(section, limits) {
  const size = section.entry.get('size');
  if (!isInt(size) || size < 0) {
    throw formatError('R35-names', `section 'NAME': "size" is ${size === undefined ? 'missing' : describe(size)}, not an int >= 0`);
  }
  if (size > limits.max_section_bytes) {
    throw limitError('R21-header-limit', `section 'NAME': size ${size} exceeds max_section_bytes = ${limits.max_section_bytes}`);
  }
  return Number(size);
}

/**
 * The names in the payload (CRC already checked).
 * @param {Uint8Array} payload
 * @param {number} size
 * @param {number} F
 * @returns {string[]}
 */
export function decodeNames(payload, size, F) {
  const raw = decompressExact(payload, size, "section 'NAME'");
  let names;
  try {
    names = unpack(raw);
  } catch (error) {
    if (error instanceof MsgpackProblem) throw formatError('R35-names', `section 'NAME': ${error.message}`);
    throw error;
  }
  if (!Array.isArray(names) || names.length !== F || !names.every((name) => typeof name === 'string')) {
    throw formatError('R35-names', `section 'NAME' holds ${describe(names)}; it must be an array of ${F} str`);
  }
  return /** @type {string[]} */ (names);
}

/**
 * The names of a file without NAME.
 * @param {number} F
 */
export function defaultNames(F) {
  return Array.from({ length: F }, (_, f) => `frame_${String(f).padStart(5, '0')}`);
}
