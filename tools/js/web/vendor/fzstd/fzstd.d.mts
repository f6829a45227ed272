// The part of the vendored fzstd (tuckercodec/web/vendor/fzstd/fzstd.mjs, PATCHES.md) that the
// decoder uses. tkc/zstd.js imports `../vendor/fzstd/fzstd.mjs`; in this folder, which is
// tuckercodec/web seen through symbolic links (tkc/, viewer/) with the vendored scripts left out,
// that import finds this declaration, so tsc checks the calls without checking fzstd itself.

/**
 * Decodes the one Zstandard frame `dat` into `buf`, the caller's buffer of the frame's declared
 * content size, and returns how many bytes the frame's blocks regenerated. Throws fzstd's error
 * (an Error with a numeric `code`) on a malformed frame.
 */
export function decompressFrameInto(dat: Uint8Array, buf: Uint8Array): number;
