// One Zstandard frame, checked as spec/FORMAT.md §6.1 step 3 says (rule R29-zstd-content-size):
// exactly one frame, its content size declared and equal to what the section needs, no
// dictionary, nothing after it, and its checksum (if any) right. The frame's header and block
// headers are read here (RFC 8878 §3.1.1), before any memory is reserved; the blocks' content
// is decoded by the vendored fzstd into one buffer of the declared size.

import { decompressFrameInto } from '../vendor/fzstd/fzstd.mjs';
import { formatError } from './errors.js';
import { xxh64Low32 } from './xxh64.js';

const RULE = 'R29-zstd-content-size';
const MAGIC = [0x28, 0xb5, 0x2f, 0xfd];
const MAX_BLOCK = 128 * 1024;
// No frame of L bytes regenerates more than 32768·L bytes (§6.1): a block regenerates at most
// 128 KiB and takes at least 4 bytes.
const MAX_EXPANSION = 32768;

/**
 * @param {string} where
 * @param {string} message
 */
function fail(where, message) {
  return formatError(RULE, `${where}: ${message}`);
}

/**
 * Decompresses `payload`, which must be exactly one Zstandard frame declaring `size` bytes of
 * content, and returns those bytes.
 * @param {Uint8Array} payload
 * @param {number} size the content size the section needs
 * @param {string} where the section, for messages
 * @returns {Uint8Array}
 */
export function decompressExact(payload, size, where) {
  const length = payload.length;
  const { position: blocksStart, windowSize, declared, hasChecksum } = readFrameHeader(payload, where);
  if (declared !== size) {
    throw fail(where, `the frame declares ${declared} content bytes, the section needs ${size}`);
  }
  if (size > MAX_EXPANSION * length) {
    throw fail(where, `${length} bytes cannot regenerate ${size}`);
  }
  const position = blocksEnd(payload, blocksStart, Math.min(MAX_BLOCK, windowSize), where);
  const frameEnd = position + (hasChecksum ? 4 : 0);
  if (frameEnd > length) throw fail(where, 'the frame is truncated before its checksum');
  if (frameEnd < length) {
    throw fail(where, `${length - frameEnd} bytes follow the Zstandard frame`);
  }
  const output = new Uint8Array(size);
  let produced;
  try {
    produced = decompressFrameInto(payload.subarray(0, position), output);
  } catch (error) {
    throw fail(where, `the Zstandard frame is corrupt (${error && /** @type {Error} */ (error).message})`);
  }
  if (produced !== size) {
    throw fail(where, `the frame regenerates ${produced} bytes, it declares ${size}`);
  }
  if (hasChecksum) {
    const stored =
      (payload[position] | (payload[position + 1] << 8) | (payload[position + 2] << 16) |
        (payload[position + 3] << 24)) >>> 0;
    if (xxh64Low32(output) !== stored) throw fail(where, 'the frame content checksum differs');
  }
  return output;
}

/**
 * The frame header (RFC 8878 §3.1.1.1): the magic, no reserved bit, no dictionary, a declared
 * content size, and the window size the blocks are bounded by.
 * @param {Uint8Array} payload
 * @param {string} where the section, for messages
 * @returns {{position: number, windowSize: number, declared: number, hasChecksum: number}}
 *   where the first block header starts, the window size, the declared content size, and
 *   whether a checksum follows the blocks
 */
function readFrameHeader(payload, where) {
  const length = payload.length;
  if (length < 5 || MAGIC.some((byte, i) => payload[i] !== byte)) {
    throw fail(where, 'the payload is not a Zstandard frame (magic 28 B5 2F FD)');
  }
  const descriptor = payload[4];
  const contentSizeFlag = descriptor >> 6;
  const singleSegment = (descriptor >> 5) & 1;
  const hasChecksum = (descriptor >> 2) & 1;
  const dictionaryFlag = descriptor & 3;
  if (descriptor & 8) throw fail(where, 'the frame header sets its reserved bit');
  let position = 5;
  let windowSize = 0;
  if (!singleSegment) {
    if (position >= length) throw fail(where, 'the frame header is truncated');
    const exponent = payload[position] >> 3;
    const base = 2 ** (10 + exponent);
    windowSize = base + (base / 8) * (payload[position] & 7);
    position += 1;
  }
  const dictionaryBytes = [0, 1, 2, 4][dictionaryFlag];
  const sizeBytes = contentSizeFlag ? 1 << contentSizeFlag : singleSegment;
  if (position + dictionaryBytes + sizeBytes > length) {
    throw fail(where, 'the frame header is truncated');
  }
  let dictionary = 0;
  for (let i = 0; i < dictionaryBytes; i++) dictionary += payload[position + i] * 2 ** (8 * i);
  position += dictionaryBytes;
  if (dictionary !== 0) throw fail(where, `the frame needs dictionary ${dictionary}`);
  if (sizeBytes === 0) throw fail(where, 'the frame does not declare its content size');
  let declared = 0;
  for (let i = 0; i < sizeBytes; i++) declared += payload[position + i] * 2 ** (8 * i);
  if (sizeBytes === 2) declared += 256;
  position += sizeBytes;
  if (singleSegment) windowSize = declared;
  return { position, windowSize, declared, hasChecksum };
}

/**
 * Where the frame's blocks end, read from their headers alone (RFC 8878 §3.1.1.2), to find the
 * frame's end without decoding anything: no block of the reserved type or over `blockLimit`.
 * @param {Uint8Array} payload
 * @param {number} position where the first block header starts
 * @param {number} blockLimit the largest block allowed, min(128 KiB, the window size)
 * @param {string} where the section, for messages
 * @returns {number} the position after the last block
 */
function blocksEnd(payload, position, blockLimit, where) {
  const length = payload.length;
  for (;;) {
    if (position + 3 > length) throw fail(where, 'the frame ends inside a block header');
    const header = payload[position] | (payload[position + 1] << 8) | (payload[position + 2] << 16);
    position += 3;
    const last = header & 1;
    const type = (header >> 1) & 3;
    const blockSize = header >>> 3;
    if (type === 3) throw fail(where, 'a block has the reserved type 3');
    if (blockSize > blockLimit) {
      throw fail(where, `a block of ${blockSize} bytes exceeds the block maximum ${blockLimit}`);
    }
    position += type === 1 ? 1 : blockSize;
    if (position > length) throw fail(where, 'the frame is truncated inside a block');
    if (last) return position;
  }
}
