// node attached.mjs IN.tkc OUT.bin: what the JavaScript decoder makes of a file's format 1.5
// sections (spec/FORMAT.md §6.10-§6.12). Writes to OUT.bin the faces in the given order (M*n
// int32), then each attribute's values (their bytes as decoded) and indices (uint32, when
// indexed), then each face set's faces (uint32), little-endian; prints JSON: the attributes' and
// sets' descriptions with their byte offsets in OUT.bin, or the error's kind and rule (anything
// but a TkcError is a crash). Run by tests/test_js_attributes.py, which compares every bit with
// the Python decoder's.

import { readFileSync, writeFileSync } from 'node:fs';
import { openTkc, TkcError } from '../../tuckercodec/web/tkc/decoder.js';

const [input, output] = process.argv.slice(2);
try {
  const file = openTkc(new Uint8Array(readFileSync(input)));
  /** @type {Uint8Array[]} */
  const parts = [];
  let at = 0;
  const put = (array) => {
    const bytes = new Uint8Array(array.buffer, array.byteOffset, array.byteLength);
    parts.push(bytes);
    const start = at;
    at += bytes.length;
    return start;
  };
  put(file.faces);
  const attributes = file.attributes.map((a) => ({
    name: a.name, domain: a.domain, role: a.role, type: a.type, rows: a.rows, components: a.components,
    values_at: put(a.values), values_bytes: a.values.byteLength,
    indices_at: a.indices === null ? null : put(a.indices), indices: a.indices === null ? null : a.indices.length,
  }));
  const faceSets = file.faceSets.map((s) => ({ name: s.name, family: s.family, faces_at: put(s.faces), faces: s.faces.length }));
  const all = new Uint8Array(at);
  let offset = 0;
  for (const part of parts) {
    all.set(part, offset);
    offset += part.length;
  }
  writeFileSync(output, all);
  process.stdout.write(JSON.stringify({
    accepted: true, version: file.version, faces: file.faceCount, face_width: file.faceWidth, attributes, face_sets: faceSets,
  }));
} catch (error) {
  if (error instanceof TkcError) {
    process.stdout.write(JSON.stringify({ accepted: false, rule: error.rule, kind: error.kind, message: error.message }));
  } else {
    process.stdout.write(JSON.stringify({ accepted: false, crashed: true, message: `${error && error.name}: ${error && error.message}\n${error && error.stack}` }));
  }
}
