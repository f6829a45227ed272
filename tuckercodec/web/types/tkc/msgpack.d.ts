export type MsgValue = number | bigint | MsgFloat | boolean | null | string | Uint8Array | MsgValue[] | Map<string, MsgValue>;
/**
 * A value as `unpack` returns it.
 * @typedef {number | bigint | MsgFloat | boolean | null | string | Uint8Array | MsgValue[]
 *   | Map<string, MsgValue>} MsgValue
 */
/** A msgpack float (float 32 or float 64); `value` is its number. */
export declare class MsgFloat {
    value: number;
    /** @param {number} value */
    constructor(value: number);
}
/** Why bytes are not one valid msgpack object; the caller maps it to its rule (R12, R35). */
export declare class MsgpackProblem extends Error {
}
/** Containers nested deeper than this are refused, as the reference's reader does. */
export declare const MAX_DEPTH = 1024;
/**
 * True for a msgpack int (a number or a BigInt as this reader returns them).
 * @param {unknown} value
 * @returns {value is number | bigint}
 */
export declare function isInt(value: unknown): value is number | bigint;
/**
 * Reads `bytes` as exactly one msgpack object.
 * @param {Uint8Array} bytes
 * @returns {MsgValue} the value, as described above
 * @throws {MsgpackProblem} when the bytes are not one valid object
 */
export declare function unpack(bytes: Uint8Array): MsgValue;
/**
 * A short description of a value for messages ("an int", "a str 'x'"...).
 * @param {unknown} value
 */
export declare function describe(value: unknown): string;
