// The viewer's arithmetic on flat position arrays (x, y, z per vertex, in the file's vertex
// order): vertex normals, bounding boxes, the error of a frame against the original, and the
// colour scale. No three.js and no DOM here, so node can run it too; nothing allocates, so the
// page can call it every frame.

/** What the KG error of one frame means, as the page labels it. */
export const FRAME_KG_DEFINITION =
  "KG error of this frame (Karni-Gotsman): 100·‖A_t − B_t‖ / ‖A_t − mean_v(A_t)‖, " +
  'A_t the original positions of frame t, B_t the decoded ones, mean_v(A_t) the mean ' +
  "of A_t's vertices: this frame's positions only";

/**
 * Area-weighted vertex normals of an indexed triangle mesh, written into `normals`.
 * Each triangle adds its cross product (twice its area times its unit normal) to its three
 * corners; a vertex no triangle with area touches gets (0, 0, 1), never a zero vector.
 * @param {Float32Array} positions K*3
 * @param {Uint32Array} index T*3 vertex numbers
 * @param {Float32Array} normals K*3, overwritten
 */
export function computeNormals(positions, index, normals) {
  normals.fill(0);
  for (let t = 0, n = index.length; t < n; t += 3) {
    const a = index[t] * 3, b = index[t + 1] * 3, c = index[t + 2] * 3;
    const ax = positions[a], ay = positions[a + 1], az = positions[a + 2];
    const e1x = positions[b] - ax, e1y = positions[b + 1] - ay, e1z = positions[b + 2] - az;
    const e2x = positions[c] - ax, e2y = positions[c + 1] - ay, e2z = positions[c + 2] - az;
    const nx = e1y * e2z - e1z * e2y, ny = e1z * e2x - e1x * e2z, nz = e1x * e2y - e1y * e2x;
    normals[a] += nx; normals[a + 1] += ny; normals[a + 2] += nz;
    normals[b] += nx; normals[b + 1] += ny; normals[b + 2] += nz;
    normals[c] += nx; normals[c + 1] += ny; normals[c + 2] += nz;
  }
  for (let v = 0, n = normals.length; v < n; v += 3) {
    const x = normals[v], y = normals[v + 1], z = normals[v + 2];
    const length = Math.sqrt(x * x + y * y + z * z);
    if (length > 0 && Number.isFinite(length)) {
      normals[v] = x / length; normals[v + 1] = y / length; normals[v + 2] = z / length;
    } else {
      normals[v] = 0; normals[v + 1] = 0; normals[v + 2] = 1;
    }
  }
}

/**
 * Grow `box` ([minx, miny, minz, maxx, maxy, maxz], start from emptyBox()) by the positions.
 * Non-finite values are skipped.
 * @param {number[]} box
 * @param {ArrayLike<number>} positions
 */
export function extendBox(box, positions) {
  for (let v = 0, n = positions.length; v < n; v += 3) {
    for (let axis = 0; axis < 3; axis++) {
      const value = positions[v + axis];
      if (!Number.isFinite(value)) continue;
      if (value < box[axis]) box[axis] = value;
      if (value > box[axis + 3]) box[axis + 3] = value;
    }
  }
  return box;
}

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
