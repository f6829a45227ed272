// The vertex normals and bounds of one frame, on flat position arrays (x, y, z per vertex):
// what TKCLoader's animation recomputes each frame, and the viewer for the original beside it.
// No three.js here, and nothing allocates, so a page can call them every frame.

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
 * The box around the finite positions, into `box` ([minx, miny, minz, maxx, maxy, maxz]), and
 * the largest squared distance of a finite position from the box's centre, for a bounding sphere
 * centred there. A frame without a finite position leaves the box empty (min > max) and gives -1.
 * @param {Float32Array} positions K*3
 * @param {number[]} box six numbers, overwritten
 * @returns {number} the squared radius
 */
export function computeBounds(positions, box) {
  box.fill(Infinity, 0, 3);
  box.fill(-Infinity, 3, 6);
  extendBox(box, positions);
  if (!(box[0] <= box[3] && box[1] <= box[4] && box[2] <= box[5])) return -1;
  const cx = (box[0] + box[3]) / 2, cy = (box[1] + box[4]) / 2, cz = (box[2] + box[5]) / 2;
  let radius2 = 0;
  for (let v = 0, n = positions.length; v < n; v += 3) {
    const dx = positions[v] - cx, dy = positions[v + 1] - cy, dz = positions[v + 2] - cz;
    const d2 = dx * dx + dy * dy + dz * dz;
    if (d2 > radius2 && Number.isFinite(d2)) radius2 = d2;
  }
  return radius2;
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
