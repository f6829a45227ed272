/**
 * Decompresses `payload`, which must be exactly one Zstandard frame declaring `size` bytes of
 * content, and returns those bytes.
 * @param {Uint8Array} payload
 * @param {number} size the content size the section needs
 * @param {string} where the section, for messages
 * @returns {Uint8Array}
 */
export declare function decompressExact(payload: Uint8Array, size: number, where: string): Uint8Array;
