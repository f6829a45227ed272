/**
 * Area-weighted vertex normals of an indexed triangle mesh, written into `normals`.
 * Each triangle adds its cross product (twice its area times its unit normal) to its three
 * corners; a vertex no triangle with area touches gets (0, 0, 1), never a zero vector.
 * @param {Float32Array} positions K*3
 * @param {Uint32Array} index T*3 vertex numbers
 * @param {Float32Array} normals K*3, overwritten
 */
export declare function computeNormals(positions: Float32Array, index: Uint32Array, normals: Float32Array): void;
/**
 * The box around the finite positions, into `box` ([minx, miny, minz, maxx, maxy, maxz]), and
 * the largest squared distance of a finite position from the box's centre, for a bounding sphere
 * centred there. A frame without a finite position leaves the box empty (min > max) and gives -1.
 * @param {Float32Array} positions K*3
 * @param {number[]} box six numbers, overwritten
 * @returns {number} the squared radius
 */
export declare function computeBounds(positions: Float32Array, box: number[]): number;
/**
 * Grow `box` ([minx, miny, minz, maxx, maxy, maxz], start from emptyBox()) by the positions.
 * Non-finite values are skipped.
 * @param {number[]} box
 * @param {ArrayLike<number>} positions
 */
export declare function extendBox(box: number[], positions: ArrayLike<number>): number[];
