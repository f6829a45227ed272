// How a file's faces and static attributes (format 1.5) become a GPU mesh, without three.js:
// three.js holds one value of each attribute per vertex, so a vertex whose corners carry
// different UVs, normals or colours (a UV seam, a hard edge, a face's colour) is drawn as one
// copy per distinct combination of values. Copy d of the file's vertex v takes v's position every
// frame. Vertex v itself is copy v (the first K drawn vertices are the file's, in order); the
// other copies follow. The triangles are the faces fanned, grouped by material (face sets of
// family `materialBind`).

import { computeNormals } from './normals.js';

/**
 * @typedef {import('../tkc/attributes.js').Attribute} Attribute
 * @typedef {{start: number, count: number, materialIndex: number}} Group
 */

/**
 * The row of `attribute` for a corner (of face f, vertex v, number c in corner order).
 * @param {Attribute} attribute
 * @param {number} f
 * @param {number} c
 * @param {number} v
 */
function rowAt(attribute, f, c, v) {
  const element = attribute.domain === 'vertex' ? v : attribute.domain === 'corner' ? c : f;
  return attribute.indices === null ? element : attribute.indices[element];
}

/**
 * The bits of an attribute's values, to compare rows exactly (two rows with the same values
 * give one drawn vertex, whatever their numbers).
 * @param {Attribute} attribute
 */
function bitsOf(attribute) {
  const values = attribute.values;
  return new Int32Array(values.buffer, values.byteOffset, values.byteLength / 4);
}

/**
 * Splits the file's vertices by the rows their corners use of each of `attributes`: the drawn
 * vertex of every corner, and the file's vertex of every drawn vertex.
 * @param {import('../tkc/decoder.js').TkcFile} file
 * @param {Attribute[]} attributes
 * @returns {{ofCorner: Uint32Array, vertexOf: Uint32Array, rows: Uint32Array[]}} `rows[a][d]`:
 *   the row of attribute a that drawn vertex d shows
 */
function split(file, attributes) {
  const K = file.vertices;
  const { faces, faceCount: M, faceWidth: n } = file;
  const bits = attributes.map(bitsOf);
  const widths = attributes.map((a) => (a.values.BYTES_PER_ELEMENT / 4) * a.components);
  let capacity = K + 1024;
  let rows = attributes.map(() => new Uint32Array(capacity));
  let vertexOf = new Uint32Array(capacity);
  let next = new Int32Array(capacity).fill(-1); // the vertex's next copy, or -1
  const used = new Uint8Array(K);
  for (let v = 0; v < K; v++) vertexOf[v] = v;
  let corners = 0;
  for (const v of faces) if (v >= 0) corners++;
  const ofCorner = new Uint32Array(corners);
  let count = K;
  /** @param {number} d @param {number[]} want */
  const same = (d, want) => want.every((row, a) => {
    const have = rows[a][d];
    if (have === row) return true;
    const w = widths[a];
    for (let j = 0; j < w; j++) if (bits[a][have * w + j] !== bits[a][row * w + j]) return false;
    return true;
  });
  let c = 0;
  for (let f = 0; f < M; f++) {
    for (let j = 0; j < n; j++) {
      const v = faces[f * n + j];
      if (v < 0) continue;
      const want = attributes.map((a) => rowAt(a, f, c, v));
      c++;
      if (!used[v]) {
        used[v] = 1;
        want.forEach((row, a) => { rows[a][v] = row; });
        ofCorner[c - 1] = v;
        continue;
      }
      let d = v;
      while (!same(d, want) && next[d] >= 0) d = next[d];
      if (!same(d, want)) {
        if (count === capacity) {
          capacity *= 2;
          const grow = (/** @type {Uint32Array} */ old) => { const out = new Uint32Array(capacity); out.set(old); return out; };
          rows = rows.map(grow);
          vertexOf = grow(vertexOf);
          const longer = new Int32Array(capacity).fill(-1);
          longer.set(next);
          next = longer;
        }
        next[d] = count;
        d = count++;
        vertexOf[d] = v;
        want.forEach((row, a) => { rows[a][d] = row; });
      }
      ofCorner[c - 1] = d;
    }
  }
  // a vertex no face uses shows its own row of a vertex attribute
  attributes.forEach((a, i) => {
    if (a.domain !== 'vertex') return;
    for (let v = 0; v < K; v++) if (!used[v]) rows[i][v] = rowAt(a, 0, 0, v);
  });
  return { ofCorner, vertexOf: vertexOf.slice(0, count), rows: rows.map((r) => r.slice(0, count)) };
}

/**
 * Drawn values of `attribute` as float32, `rows[d]` for each drawn vertex (a vertex no face
 * uses shows row 0 of a vertex attribute, its own, or zeros).
 * @param {Attribute} attribute
 * @param {Uint32Array} rows
 */
function drawnValues(attribute, rows) {
  const c = attribute.components;
  const out = new Float32Array(rows.length * c);
  const values = attribute.values;
  for (let d = 0; d < rows.length; d++) {
    const row = rows[d];
    if (row >= attribute.rows) continue;
    for (let j = 0; j < c; j++) out[d * c + j] = values[row * c + j];
  }
  return out;
}

/**
 * The triangles (corners fanned per face, as drawn vertices), faces grouped by material: the
 * faces of each `materialBind` set in order, then the faces in none (a face in two sets is drawn
 * with the first).
 * @param {import('../tkc/decoder.js').TkcFile} file
 * @param {Uint32Array} ofCorner the drawn vertex of every corner
 * @returns {{triangles: Uint32Array, groups: Group[], materialNames: (string | null)[]}}
 */
function groupedTriangles(file, ofCorner) {
  const { faces, faceCount: M, faceWidth: n } = file;
  const starts = new Uint32Array(M + 1);
  for (let f = 0; f < M; f++) {
    let real = 0;
    while (real < n && faces[f * n + real] >= 0) real++;
    starts[f + 1] = starts[f] + real;
  }
  const materials = file.faceSets.filter((s) => s.family === 'materialBind');
  const material = new Int32Array(M).fill(materials.length);
  for (let m = materials.length - 1; m >= 0; m--) for (const f of materials[m].faces) material[f] = m;
  const unbound = material.includes(materials.length);
  const materialNames = [...materials.map((s) => s.name), ...(unbound && materials.length ? [null] : [])];
  const triangles = new Uint32Array(3 * (starts[M] - 2 * M));
  /** @type {Group[]} */
  const groups = [];
  let t = 0;
  for (let m = 0; m <= materials.length; m++) {
    const start = t;
    for (let f = 0; f < M; f++) {
      if (material[f] !== m) continue;
      const first = starts[f];
      for (let j = first + 1; j + 1 < starts[f + 1]; j++) {
        triangles[t++] = ofCorner[first];
        triangles[t++] = ofCorner[j];
        triangles[t++] = ofCorner[j + 1];
      }
    }
    if (materials.length && t > start) groups.push({ start, count: t - start, materialIndex: m });
  }
  return { triangles, groups, materialNames };
}

/**
 * A file drawn with its UVs, normals, colours and materials (the first attribute of each role).
 * Without any, it is the file's vertices and faces as they are.
 */
export class DrawLayout {
  /** @param {import('../tkc/decoder.js').TkcFile} file */
  constructor(file) {
    /** @param {string} role */
    const first = (role) => file.attributes.find((a) => a.role === role) ?? null;
    const [uv, normal, color] = [first('uv'), first('normal'), first('color')];
    /** @type {Attribute[]} */
    const drawn = [uv, normal, color].filter((a) => a !== null);
    const { ofCorner, vertexOf, rows } = split(file, drawn);
    const at = (/** @type {Attribute | null} */ a) => (a === null ? null : drawnValues(a, rows[drawn.indexOf(a)]));
    /** The file's vertex of each drawn vertex (the first K are the file's own). */
    this.vertexOf = vertexOf;
    /** The number of drawn vertices. */
    this.count = vertexOf.length;
    /** The drawn vertices' UVs (2 each), normals (3), colours (3 or 4), or null. */
    this.uv = at(uv);
    this.normal = at(normal);
    this.color = at(color);
    this.colorSize = color === null ? 0 : color.components;
    const { triangles, groups, materialNames } = groupedTriangles(file, ofCorner);
    this.triangles = triangles;
    /** Ranges of `triangles` drawn with one material each (none without materialBind sets). */
    this.groups = groups;
    /** The material of each group's materialIndex (null: the faces of no material). */
    this.materialNames = materialNames;
    // normals are recomputed per group of drawn vertices: the file's vertex, or with authored
    // normals, each (vertex, normal) pair, so that hard edges stay hard and UV seams smooth
    /** @type {{groupOf: Uint32Array, vertexOf: Uint32Array | null, triangles: Uint32Array, positions: Float32Array, normals: Float32Array} | null} null: the drawn vertices are the file's */
    this._groups = null;
    if (normal === null && this.count === file.vertices) return;
    const groupsOf = normal === null ? null : split(file, [normal]);
    const groupOf = new Uint32Array(this.count);
    if (groupsOf === null) groupOf.set(vertexOf);
    else ofCorner.forEach((d, c) => { groupOf[d] = groupsOf.ofCorner[c]; });
    const groupCount = groupsOf === null ? file.vertices : groupsOf.vertexOf.length;
    this._groups = {
      groupOf,
      vertexOf: groupsOf === null ? null : groupsOf.vertexOf,
      triangles: triangles.map((d) => groupOf[d]),
      positions: new Float32Array(groupsOf === null ? 0 : 3 * groupCount),
      normals: new Float32Array(3 * groupCount),
    };
  }

  /**
   * The drawn vertices' positions from a frame's (K*3), into `out` (count*3).
   * @param {Float32Array} frame
   * @param {Float32Array} out
   */
  positionsInto(frame, out) {
    if (out !== frame) {
      out.set(frame);
      gather(frame, this.vertexOf, frame.length / 3, out);
    }
  }

  /**
   * The drawn vertices' normals from a frame's positions (K*3): area-weighted per normal group.
   * @param {Float32Array} frame
   * @param {Float32Array} out count*3
   */
  normalsInto(frame, out) {
    const groups = this._groups;
    if (groups === null) {
      computeNormals(frame, this.triangles, out);
      return;
    }
    let positions = frame;
    if (groups.vertexOf !== null) {
      gather(frame, groups.vertexOf, 0, groups.positions);
      positions = groups.positions;
    }
    computeNormals(positions, groups.triangles, groups.normals);
    gather(groups.normals, groups.groupOf, 0, out);
  }
}

/**
 * out[d] = values[source[d]] (3 components) for d from `from` on.
 * @param {Float32Array} values
 * @param {Uint32Array} source
 * @param {number} from
 * @param {Float32Array} out
 */
function gather(values, source, from, out) {
  for (let d = from; d < source.length; d++) {
    const s = 3 * source[d];
    out[3 * d] = values[s];
    out[3 * d + 1] = values[s + 1];
    out[3 * d + 2] = values[s + 2];
  }
}
