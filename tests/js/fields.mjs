// node fields.mjs IN.tkc OUT.bin: what the JavaScript decoder makes of a file's animated fields
// (FLD.n, spec/FORMAT.md §6.13). Writes to OUT.bin every frame of every field, field after
// field (each frame's N*c values as decoded: float32 or float64, little-endian); prints JSON:
// each field's description (fieldInfo) with its byte offset in OUT.bin, or the error's kind and
// rule (anything but a TkcError is a crash). Run by tests/test_js_fields.py, which compares the
// values with the Python decoder's.

import { readFileSync, writeFileSync } from 'node:fs';
import { openTkc, TkcError } from '../../tuckercodec/web/tkc/decoder.js';

const [input, output] = process.argv.slice(2);
try {
  const file = openTkc(new Uint8Array(readFileSync(input)));
  /** @type {Uint8Array[]} */
  const parts = [];
  let at = 0;
  const fields = file.fieldNames.map((name, n) => {
    const info = file.fieldInfo(n);
    const start = at;
    for (let f = 0; f < file.frames; f++) {
      // by name for frame 0, by number after: both ways of asking
      const values = file.field(f === 0 ? name : n, f);
      parts.push(new Uint8Array(values.buffer, values.byteOffset, values.byteLength));
      at += values.byteLength;
    }
    return { ...info, at: start, bytes: at - start };
  });
  const all = new Uint8Array(at);
  let offset = 0;
  for (const part of parts) {
    all.set(part, offset);
    offset += part.length;
  }
  writeFileSync(output, all);
  process.stdout.write(JSON.stringify({ accepted: true, frames: file.frames, fields }));
} catch (error) {
  if (error instanceof TkcError) {
    process.stdout.write(JSON.stringify({ accepted: false, rule: error.rule, kind: error.kind, message: error.message }));
  } else {
    process.stdout.write(JSON.stringify({ accepted: false, crashed: true, message: `${error && error.name}: ${error && error.message}\n${error && error.stack}` }));
  }
}
