/**
 * Decodes a stream of `count` signed integers stored in `planes` byte planes.
 * The caller has checked that `planes` is an int in 1..4 (R30-planes).
 * @param {Uint8Array} payload one Zstandard frame
 * @param {number} count N
 * @param {number} planes P
 * @param {string} where the section (and stream), for messages
 * @returns {Int32Array}
 */
export declare function decodeIntStream(payload: Uint8Array, count: number, planes: number, where: string): Int32Array;
