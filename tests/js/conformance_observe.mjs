// What the JavaScript decoder makes of one conformance vector (spec/FORMAT.md §12), in node or
// in a browser: the header facts, names, segment index and SHA-256 digests of the dequantized
// arrays of a valid vector and its reconstruction's largest difference from the reference .npy,
// or, for any vector, the rule of the error it raised. The Python tests compare these
// observations with the vector's JSON, so the checks are written once, in Python.

import { openTkc, TkcError } from '../../tuckercodec/web/tkc/decoder.js';

async function sha256(bytes) {
  const digest = await globalThis.crypto.subtle.digest('SHA-256', bytes);
  return Array.from(new Uint8Array(digest), (b) => b.toString(16).padStart(2, '0')).join('');
}

function littleEndianFloat64(values) {
  const out = new Uint8Array(values.length * 8);
  const view = new DataView(out.buffer);
  values.forEach((v, j) => view.setFloat64(8 * j, v, true));
  return out;
}

function littleEndianInt64(values) {
  const out = new Uint8Array(values.length * 8);
  const view = new DataView(out.buffer);
  values.forEach((v, j) => view.setBigInt64(8 * j, BigInt(v), true));
  return out;
}

/** A C-order little-endian float64 .npy's values and shape (what the vectors' references are). */
export function readNpyFloat64(bytes) {
  const view = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
  const major = bytes[6];
  const headerLength = major === 1 ? view.getUint16(8, true) : view.getUint32(8, true);
  const start = (major === 1 ? 10 : 12) + headerLength;
  const header = new TextDecoder().decode(bytes.subarray(major === 1 ? 10 : 12, start));
  if (!header.includes("'descr': '<f8'") || !header.includes("'fortran_order': False")) {
    throw new Error(`unexpected .npy header ${header}`);
  }
  const shape = header.match(/'shape': \(([^)]*)\)/)[1].split(',').filter((s) => s.trim()).map(Number);
  const copy = bytes.slice(start);
  return { values: new Float64Array(copy.buffer, 0, copy.length / 8), shape };
}

/**
 * @param {Uint8Array} tkc the vector's bytes
 * @param {Uint8Array|null} npy its reference reconstruction, for a valid vector
 */
export async function observeVector(tkc, npy) {
  try {
    const file = openTkc(tkc).check();
    const observed = {
      accepted: true,
      header: {
        format_version: file.version,
        vertices: file.vertices,
        frames: file.frames,
        faces: file.faceCount,
        face_width: file.faceWidth,
        total_bytes: tkc.length,
        ranks: file.ranks,
        frame_rate: file.frameRate,
        kg: file.error ? file.error.kg : null,
        time_codes: file.timeCodes === null ? null : Array.from(file.timeCodes),
        meters_per_unit: file.metersPerUnit,
        up_axis: file.upAxis,
      },
      frame_names: file.names,
      segments: file.layout.segmented
        ? file.segments.map((s) => ({ first_frame: s.start, frames: s.frames, ranks: s.ranks, basis: s.basis }))
        : [],
      sha256: { faces: await sha256(littleEndianInt64(file.faces)) },
    };
    const segmented = file.layout.segmented;
    for (let s = 0; s < file.segments.length; s++) {
      const f = file.factors(s);
      const suffix = segmented ? `.${s}` : '';
      observed.sha256[`u1${suffix}`] = await sha256(littleEndianFloat64(f.u1));
      observed.sha256[`u3${suffix}`] = await sha256(littleEndianFloat64(f.u3));
      observed.sha256[`core${suffix}`] = await sha256(littleEndianFloat64(f.core));
      observed.sha256[`centroids${suffix}`] = await sha256(littleEndianFloat64(f.cent));
      // a file with corrections (§6.9, §12): the first segment's parameters, and every
      // segment's restored integers e (little-endian int64) and (1.8) codebooks' entries
      const residual = file.residual(s);
      if (residual !== null) {
        // L as decoded: a chunk_frames above the segment's frames is one chunk of them all
        const L = Math.min(residual.chunkFrames, file.segments[s].frames);
        observed.residual ??= { domain: residual.domain, scale: residual.scale, predict: residual.predict, chunk_frames: L, sha256: {} };
        observed.residual.sha256[`residual${suffix}`] = await sha256(littleEndianInt64(file.residualIntegers(s)));
        // (1.8) a section with codebooks: each axis's entries C, or null for an axis without one
        const books = file.residualCodebooks(s);
        if (books !== null) {
          observed.residual.codebooks ??= {};
          observed.residual.codebooks[`codebooks${suffix}`] = await Promise.all(books.map((C) => (C === null ? null : sha256(littleEndianInt64(C)))));
        }
      }
    }
    // every frame, each alone (§8: a frame does not depend on which others are asked for)
    const K3 = 3 * file.vertices;
    const positions = new Float64Array(file.frames * K3);
    for (let t = 0; t < file.frames; t++) positions.set(file.frame(t), t * K3);
    if (npy !== null) {
      const reference = readNpyFloat64(npy);
      let difference = 0;
      let scale = 0;
      for (let j = 0; j < positions.length; j++) {
        difference = Math.max(difference, Math.abs(positions[j] - reference.values[j]));
        scale = Math.max(scale, Math.abs(reference.values[j]));
      }
      // bit for bit (a file with corrections must be: §8.1), -0 and +0 told apart
      const mine = new Uint8Array(positions.buffer);
      const theirs = new Uint8Array(reference.values.buffer, reference.values.byteOffset, reference.values.byteLength);
      const identical = mine.length === theirs.length && mine.every((byte, j) => byte === theirs[j]);
      observed.reference = { shape: reference.shape, max_abs_difference: difference, max_abs_reference: scale, identical };
    }
    return observed;
  } catch (error) {
    if (error instanceof TkcError) return { accepted: false, kind: error.kind, rule: error.rule, message: error.message };
    return { accepted: false, crashed: true, message: `${error && error.name}: ${error && error.message}\n${error && error.stack}` };
  }
}
