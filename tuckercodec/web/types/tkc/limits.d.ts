export declare const DEFAULT_LIMITS: Readonly<{
    max_header_bytes: number;
    max_sections: number;
    max_segments: number;
    max_vertices: number;
    max_frames: number;
    max_positions: number;
    max_factor_values: number;
    max_faces: number;
    max_face_width: 64;
    max_section_bytes: number;
    max_chunk_values: number;
}>;
export type Limits = {
    readonly [name in keyof typeof DEFAULT_LIMITS]: number;
};
/** @typedef {{readonly [name in keyof typeof DEFAULT_LIMITS]: number}} Limits */
/**
 * The defaults with the caller's overrides; unknown names are refused (a typo is a bug).
 * @param {{[name: string]: number}} [overrides]
 * @returns {Limits}
 */
export declare function resolveLimits(overrides?: {
    [name: string]: number;
}): Limits;
