// The viewer's arithmetic on flat position arrays (x, y, z per vertex, in the file's vertex
// order): vertex normals, bounding boxes, the error of a frame against the original, and the
// colour scale. No three.js and no DOM here, so node can run it too; nothing allocates, so the
// page can call it every frame. The normals are the loader's (../three/normals.js), the same
// function for the decoded mesh and the original.

export { computeNormals, extendBox } from '../three/normals.js';

/** What the KG error of one frame means, as the page labels it. */
export const FRAME_KG_DEFINITION =
  "KG error of this frame (Karni-Gotsman): 100·‖A_t − B_t‖ / ‖A_t − mean_v(A_t)‖, " +
  'A_t the original positions of frame t, B_t the decoded ones, mean_v(A_t) the mean ' +
  "of A_t's vertices: this frame's positions only";

/** A box no point is in yet. */
export function emptyBox() {
  return [Infinity, Infinity, Infinity, -Infinity, -Infinity, -Infinity];
}

/**
 * The error of one decoded frame against the original's frame, and each vertex's distance.
 * @param {ArrayLike<number>} original A_t, K*3
 * @param {ArrayLike<number>} decoded B_t, K*3
 * @param {Float32Array|null} distances K, overwritten with |A_t,v − B_t,v| when given
 * @returns {{kg: number|null, maxError: number}} kg in percent (null when A_t has no spread:
 *   every vertex at its mean), maxError the largest vertex distance in scene units. Sums are
 *   accumulated in binary64.
 */
export function frameError(original, decoded, distances) {
  const count = original.length / 3;
  let mx = 0, my = 0, mz = 0;
  for (let i = 0; i < original.length; i += 3) {
    mx += original[i]; my += original[i + 1]; mz += original[i + 2];
  }
  mx /= count; my /= count; mz /= count;
  let difference = 0, spread = 0, largest = 0;
  for (let v = 0, i = 0; v < count; v++, i += 3) {
    const ax = original[i], ay = original[i + 1], az = original[i + 2];
    const dx = ax - decoded[i], dy = ay - decoded[i + 1], dz = az - decoded[i + 2];
    const squared = dx * dx + dy * dy + dz * dz;
    difference += squared;
    const distance = Math.sqrt(squared);
    if (distance > largest) largest = distance;
    if (distances) distances[v] = distance;
    const cx = ax - mx, cy = ay - my, cz = az - mz;
    spread += cx * cx + cy * cy + cz * cz;
  }
  const kg = spread > 0 ? (100 * Math.sqrt(difference)) / Math.sqrt(spread) : null;
  return { kg, maxError: largest };
}

// ColorBrewer's YlOrRd (Cynthia Brewer, Penn State; sequential, colour-blind safe): pale yellow
// for no error, through orange, to dark red for the scale's largest, at 0, 1/8, ..., 1, in sRGB
// 0-255. The low end is light so that a good reconstruction still shows its shading.
const SCALE = [
  [255, 255, 204], [255, 237, 160], [254, 217, 118], [254, 178, 76], [253, 141, 60],
  [252, 78, 42], [227, 26, 28], [189, 0, 38], [128, 0, 38],
];

/** The colour scale in sRGB, 0..1: `steps` entries of [r, g, b] from 0 to the largest value. */
export function colourScale(steps = 256) {
  const table = [];
  for (let s = 0; s < steps; s++) {
    const where = (s / (steps - 1)) * (SCALE.length - 1);
    const low = Math.min(Math.floor(where), SCALE.length - 2);
    const part = where - low;
    table.push(SCALE[low].map((c, i) => (c + (SCALE[low + 1][i] - c) * part) / 255));
  }
  return table;
}

/**
 * Write each vertex's colour for its distance: `lut` a Float32Array steps*3 (linear RGB, as the
 * renderer wants vertex colours), distances at or beyond `scale` take the last colour.
 * @param {Float32Array} distances K
 * @param {number} scale
 * @param {Float32Array} lut
 * @param {Float32Array} colours K*3, overwritten
 */
export function paintDistances(distances, scale, lut, colours) {
  const top = lut.length / 3 - 1;
  const factor = scale > 0 ? top / scale : 0;
  for (let v = 0, n = distances.length; v < n; v++) {
    let s = Math.round(distances[v] * factor);
    if (!(s <= top)) s = top; // also NaN
    const from = s * 3, to = v * 3;
    colours[to] = lut[from]; colours[to + 1] = lut[from + 1]; colours[to + 2] = lut[from + 2];
  }
}
