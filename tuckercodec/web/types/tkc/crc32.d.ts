/**
 * The CRC-32 of `bytes`, as an unsigned 32-bit number.
 * @param {Uint8Array} bytes
 */
export declare function crc32(bytes: Uint8Array): number;
