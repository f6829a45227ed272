// The FACE section (spec/FORMAT.md §6.4 faces-delta, §6.8 faces-traverse): the M × n face
// table, -1 padded, checked against R33 and R34 (faces-delta) or decoded by the walk (§6.8).

import { formatError } from './errors.js';
import { describe, isInt } from './msgpack.js';
import { decodeIntStream } from './streams.js';
import { decodeTraverse } from './traversal.js';

/**
 * @param {import('./container.js').Section} section the FACE entry
 * @param {Uint8Array} payload its bytes, CRC already checked
 * @param {number} K vertices
 * @param {number} M faces
 * @param {number} n face width
 * @param {import('./limits.js').Limits} limits the decoder's limits (§7)
 * @param {boolean} [adaptive] the file sets flag bit 3 (format 1.6): faces-traverse's `coder` may be 1
 * @param {boolean} [uniform] the file sets flag bit 6 (format 1.9): faces-traverse's `ranks` is read
 * @returns {Int32Array} M*n indices, row-major
 */
export function decodeFaces(section, payload, K, M, n, limits, adaptive = false, uniform = false) {
  if (section.codec === 'faces-traverse') return decodeTraverse(section.entry, payload, K, M, n, limits, adaptive, uniform);
  const planes = section.entry.get('planes');
  if (!isInt(planes) || planes < 1 || planes > 4) {
    throw formatError('R30-planes', `section 'FACE': "planes" is ${planes === undefined ? 'missing' : describe(planes)}, not an int in 1..4`);
  }
  const stream = decodeIntStream(payload, M * n, Number(planes), "section 'FACE'");
  const faces = new Int32Array(M * n);
  // e[j] = s[0] + ... + s[j]; face = e − 1. Each e is checked at once, so the sum stays small.
  let e = 0;
  for (let j = 0; j < stream.length; j++) {
    e += stream[j];
    if (e < 0 || e > K) {
      throw formatError('R33-face-index', `section 'FACE': face ${Math.floor(j / n)} corner ${j % n} is ${e - 1}, outside -1..${K - 1}`);
    }
    faces[j] = e - 1;
  }
  checkPadding(faces, M, n);
  return faces;
}

/**
 * R34: in every row −1 only after the real corners, and at least 3 real corners.
 * @param {Int32Array} faces
 * @param {number} M
 * @param {number} n
 */
function checkPadding(faces, M, n) {
  for (let r = 0; r < M; r++) {
    let real = 0;
    while (real < n && faces[r * n + real] >= 0) real++;
    for (let c = real; c < n; c++) {
      if (faces[r * n + c] >= 0) {
        throw formatError('R34-face-padding', `section 'FACE': face ${r} has a real corner at ${c} after padding`);
      }
    }
    if (real < 3) throw formatError('R34-face-padding', `section 'FACE': face ${r} has ${real} real corners; a face has at least 3`);
  }
}

/**
 * A fan triangulation of the faces, for drawing: (c0, cj, cj+1) for each polygon.
 * @param {Int32Array} faces
 * @param {number} M
 * @param {number} n
 */
export function fanTriangles(faces, M, n) {
  let count = 0;
  for (let r = 0; r < M; r++) {
    let real = 0;
    while (real < n && faces[r * n + real] >= 0) real++;
    count += real - 2;
  }
  const out = new Uint32Array(3 * count);
  let t = 0;
  for (let r = 0; r < M; r++) {
    const row = r * n;
    for (let j = 1; j + 1 < n && faces[row + j + 1] >= 0; j++) {
      out[t++] = faces[row];
      out[t++] = faces[row + j];
      out[t++] = faces[row + j + 1];
    }
  }
  return out;
}
