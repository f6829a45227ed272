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
/**
 * Decodes a stream of `count` signed 64-bit integers stored in `planes` byte planes (1..8: the
 * streams of format 1.5's attributes, whose float64 values' ordered integers take 64 bits). The
 * caller has checked `planes`. The values are held as interleaved 32-bit halves, low half first:
 * v[j] = out[2j+1]·2^32 + (out[2j] >>> 0), so no BigInt is made per value.
 * @param {Uint8Array} payload one Zstandard frame
 * @param {number} count N
 * @param {number} planes P
 * @param {string} where the section (and stream), for messages
 * @returns {Int32Array} 2·N halves
 */
export declare function decodeWideStream(payload: Uint8Array, count: number, planes: number, where: string): Int32Array;
