// Decoder limits (spec/FORMAT.md §7): checked against the sizes a file declares before any
// memory that depends on them is reserved. These are the reference defaults; a caller may pass
// others to openTkc ({limits: {...}}), for example lower ones in a browser.

export const DEFAULT_LIMITS = Object.freeze({
  max_header_bytes: 2 ** 24,
  max_sections: 2 ** 18,
  max_segments: 2 ** 15,
  max_vertices: 2 ** 26,
  max_frames: 2 ** 24,
  max_positions: 2 ** 28,
  max_factor_values: 2 ** 27,
  max_faces: 2 ** 28,
  max_face_width: 64,
  max_section_bytes: 2 ** 32,
  max_chunk_values: 2 ** 21,
});

/** @typedef {{readonly [name in keyof typeof DEFAULT_LIMITS]: number}} Limits */

/**
 * The defaults with the caller's overrides; unknown names are refused (a typo is a bug).
 * @param {{[name: string]: number}} [overrides]
 * @returns {Limits}
 */
export function resolveLimits(overrides = {}) {
  for (const name of Object.keys(overrides)) {
    if (!(name in DEFAULT_LIMITS)) throw new TypeError(`unknown decoder limit '${name}'`);
  }
  return Object.freeze({ ...DEFAULT_LIMITS, ...overrides });
}
