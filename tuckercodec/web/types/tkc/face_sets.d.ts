export type FaceSet = {
    name: string;
    family: string;
    faces: Uint32Array;
};
/**
 * The face sets of FSET: the table (R44, R21), the stream's size against the limits (R21), its
 * planes (R30) and stream (R29), then each set's numbers increasing and faces (R44).
 * @param {import('./container.js').Section} section the FSET entry
 * @param {Uint8Array} payload its bytes, CRC already checked
 * @param {number} M the faces
 * @param {import('./limits.js').Limits} limits
 * @returns {FaceSet[]}
 */
export declare function decodeFaceSets(section: import('./container.js').Section, payload: Uint8Array, M: number, limits: import('./limits.js').Limits): FaceSet[];
