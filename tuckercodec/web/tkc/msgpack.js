// A strict MessagePack reader for the header (spec/FORMAT.md §1, §4) and the NAME section
// (§6.5). Written here rather than taken from a package because the spec needs what general
// readers drop: an int and a float must stay distinguishable (a `u2` of integral *ints* is
// invalid), maps may not repeat a key, map keys are str, no extension type is allowed (not
// even the timestamp), strings must be valid UTF-8, and nothing may follow the object.
//
// Values: maps are JS Maps with string keys, arrays are Arrays, ints are numbers when within
// ±(2^53 − 1) and BigInts beyond, floats are MsgFloat objects (never plain numbers), bool is
// boolean, nil is null, str is string, bin is a Uint8Array (a view into the input).

/**
 * A value as `unpack` returns it.
 * @typedef {number | bigint | MsgFloat | boolean | null | string | Uint8Array | MsgValue[]
 *   | Map<string, MsgValue>} MsgValue
 */

/** A msgpack float (float 32 or float 64); `value` is its number. */
export class MsgFloat {
  /** @param {number} value */
  constructor(value) {
    this.value = value;
  }
}

/** Why bytes are not one valid msgpack object; the caller maps it to its rule (R12, R35). */
export class MsgpackProblem extends Error {}

/** Containers nested deeper than this are refused, as the reference's reader does. */
export const MAX_DEPTH = 1024;

const utf8 = new TextDecoder('utf-8', { fatal: true });

/**
 * True for a msgpack int (a number or a BigInt as this reader returns them).
 * @param {unknown} value
 * @returns {value is number | bigint}
 */
export function isInt(value) {
  return (typeof value === 'number' && Number.isInteger(value)) || typeof value === 'bigint';
}

/**
 * Reads `bytes` as exactly one msgpack object.
 * @param {Uint8Array} bytes
 * @returns {MsgValue} the value, as described above
 * @throws {MsgpackProblem} when the bytes are not one valid object
 */
export function unpack(bytes) {
  const reader = new Reader(bytes);
  const value = reader.value(0);
  if (reader.position !== bytes.length) {
    throw new MsgpackProblem(`${bytes.length - reader.position} bytes follow the msgpack object`);
  }
  return value;
}

class Reader {
  /** @param {Uint8Array} bytes */
  constructor(bytes) {
    this.bytes = bytes;
    this.view = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
    this.position = 0;
  }

  /** @param {number} count */
  take(count) {
    const start = this.position;
    if (count > this.bytes.length - start) {
      throw new MsgpackProblem(`the msgpack data ends early (at byte ${start}, ${count} more needed)`);
    }
    this.position = start + count;
    return start;
  }

  /** @param {number} size */
  uint(size) {
    const at = this.take(size);
    const v = this.view;
    if (size === 1) return v.getUint8(at);
    if (size === 2) return v.getUint16(at, false);
    if (size === 4) return v.getUint32(at, false);
    return narrow(v.getBigUint64(at, false));
  }

  /**
   * A length or a count, stored in 1, 2 or 4 bytes: always a number.
   * @param {number} size 1, 2 or 4
   */
  length(size) {
    return /** @type {number} */ (this.uint(size));
  }

  /** @param {number} size */
  int(size) {
    const at = this.take(size);
    const v = this.view;
    if (size === 1) return v.getInt8(at);
    if (size === 2) return v.getInt16(at, false);
    if (size === 4) return v.getInt32(at, false);
    return narrow(v.getBigInt64(at, false));
  }

  /** @param {number} length */
  str(length) {
    const at = this.take(length);
    try {
      return utf8.decode(this.bytes.subarray(at, at + length));
    } catch {
      throw new MsgpackProblem(`a msgpack str at byte ${at} is not valid UTF-8`);
    }
  }

  /**
   * @param {number} depth
   * @returns {MsgValue}
   */
  value(depth) {
    const at = this.take(1);
    const type = this.bytes[at];
    if (type <= 0x7f) return type;
    if (type >= 0xe0) return type - 0x100;
    if (type >= 0xa0 && type <= 0xbf) return this.str(type & 0x1f);
    if (type >= 0x90 && type <= 0x9f) return this.array(type & 0x0f, depth);
    if (type >= 0x80 && type <= 0x8f) return this.map(type & 0x0f, depth);
    switch (type) {
      case 0xc0:
        return null;
      case 0xc2:
        return false;
      case 0xc3:
        return true;
      case 0xc4:
      case 0xc5:
      case 0xc6: {
        const length = this.length(1 << (type - 0xc4));
        const start = this.take(length);
        return this.bytes.subarray(start, start + length);
      }
      case 0xca:
        return new MsgFloat(this.view.getFloat32(this.take(4), false));
      case 0xcb:
        return new MsgFloat(this.view.getFloat64(this.take(8), false));
      case 0xcc:
      case 0xcd:
      case 0xce:
      case 0xcf:
        return this.uint(1 << (type - 0xcc));
      case 0xd0:
      case 0xd1:
      case 0xd2:
      case 0xd3:
        return this.int(1 << (type - 0xd0));
      case 0xd9:
      case 0xda:
      case 0xdb:
        return this.str(this.length(1 << (type - 0xd9)));
      case 0xdc:
      case 0xdd:
        return this.array(this.length(type === 0xdc ? 2 : 4), depth);
      case 0xde:
      case 0xdf:
        return this.map(this.length(type === 0xde ? 2 : 4), depth);
      case 0xc7:
      case 0xc8:
      case 0xc9:
      case 0xd4:
      case 0xd5:
      case 0xd6:
      case 0xd7:
      case 0xd8: {
        const size = type >= 0xd4 ? 1 << (type - 0xd4) : this.length(1 << (type - 0xc7));
        const code = this.int(1);
        this.take(size);
        const name = code === -1 ? ' (timestamp)' : '';
        throw new MsgpackProblem(`msgpack extension type ${code}${name} is not allowed`);
      }
      default:
        throw new MsgpackProblem(`byte 0x${type.toString(16)} at ${at} is not a msgpack type`);
    }
  }

  /**
   * @param {number} length
   * @param {number} depth
   */
  array(length, depth) {
    if (depth + 1 > MAX_DEPTH) throw new MsgpackProblem(`msgpack nests deeper than ${MAX_DEPTH} levels`);
    // every element takes at least one byte: a declared length beyond the data is refused
    // before anything is reserved
    if (length > this.bytes.length - this.position) {
      throw new MsgpackProblem(`a msgpack array declares ${length} elements past the data's end`);
    }
    /** @type {MsgValue[]} */
    const out = new Array(length);
    for (let i = 0; i < length; i++) out[i] = this.value(depth + 1);
    return out;
  }

  /**
   * @param {number} length
   * @param {number} depth
   */
  map(length, depth) {
    if (depth + 1 > MAX_DEPTH) throw new MsgpackProblem(`msgpack nests deeper than ${MAX_DEPTH} levels`);
    if (2 * length > this.bytes.length - this.position) {
      throw new MsgpackProblem(`a msgpack map declares ${length} entries past the data's end`);
    }
    /** @type {Map<string, MsgValue>} */
    const out = new Map();
    for (let i = 0; i < length; i++) {
      const key = this.value(depth + 1);
      if (typeof key !== 'string') throw new MsgpackProblem(`map keys must be strings, got ${describe(key)}`);
      if (out.has(key)) throw new MsgpackProblem(`the key '${key}' appears twice in one map`);
      out.set(key, this.value(depth + 1));
    }
    return out;
  }
}

/** @param {bigint} big */
function narrow(big) {
  return big >= -(2n ** 53n) + 1n && big <= 2n ** 53n - 1n ? Number(big) : big;
}

/**
 * A short description of a value for messages ("an int", "a str 'x'"...).
 * @param {unknown} value
 */
export function describe(value) {
  if (value === null) return 'nil';
  if (value instanceof MsgFloat) return `a float ${value.value}`;
  if (typeof value === 'number' || typeof value === 'bigint') return `an int ${value}`;
  if (typeof value === 'boolean') return `a bool ${value}`;
  if (typeof value === 'string') return `a str '${value.length > 40 ? `${value.slice(0, 40)}…` : value}'`;
  if (value instanceof Uint8Array) return `a bin of ${value.length} bytes`;
  if (Array.isArray(value)) return `an array of ${value.length}`;
  if (value instanceof Map) return `a map of ${value.size}`;
  return String(value);
}
