// node corrections.mjs JOBS.json: decodes files with corrections (spec/FORMAT.md §6.9) with the
// JavaScript decoder. JOBS.json is an array of {path, out?, order?, limits?, float32?}; for each
// job the file is opened (with `limits`, if given), checked whole (file.check()), then every
// frame is decoded alone in `order` ("forward", the default, or "backward": no frame may depend
// on which were decoded before it), as float64 (or with `float32`, with frameFloat32, widened),
// and written to `out` (F*K*3 float64, little-endian), followed by every segment's restored
// integers e (F*K*3 int64, little-endian). Prints a JSON array: per job its verdict ("accepted",
// or the error's kind, rule and message; anything but a TkcError is a crash), the version, and
// each segment's residual parameters, and the time the frames took. Run by
// tests/test_js_corrections.py.

import { readFileSync, writeFileSync } from 'node:fs';
import { openTkc, TkcError } from '../../tuckercodec/web/tkc/decoder.js';

const jobs = JSON.parse(readFileSync(process.argv[2], 'utf8'));
const results = jobs.map((job) => {
  try {
    const file = openTkc(new Uint8Array(readFileSync(job.path)), job.limits ? { limits: job.limits } : {});
    const opened = { version: file.version, residual: file.segments.map((_, s) => file.residual(s)) };
    if (job.open_only) return { accepted: true, ...opened };
    file.check();
    const K3 = 3 * file.vertices;
    const positions = new Float64Array(file.frames * K3);
    const order = Array.from({ length: file.frames }, (_, t) => t);
    if (job.order === 'backward') order.reverse();
    const began = performance.now();
    if (job.float32) {
      const out = new Float32Array(K3);
      for (const t of order) positions.set(file.frameFloat32(t, out), t * K3);
    } else {
      for (const t of order) positions.set(file.frame(t), t * K3);
    }
    const framesMs = performance.now() - began;
    if (job.out) {
      const integers = file.segments.map((_, s) => file.residualIntegers(s) ?? new BigInt64Array(0));
      const parts = [positions, ...integers].map((a) => new Uint8Array(a.buffer, a.byteOffset, a.byteLength));
      const all = new Uint8Array(parts.reduce((n, p) => n + p.length, 0));
      let at = 0;
      for (const part of parts) {
        all.set(part, at);
        at += part.length;
      }
      writeFileSync(job.out, all);
    }
    return { accepted: true, ...opened, frames: file.frames, vertices: file.vertices, frames_ms: framesMs, error: file.error };
  } catch (error) {
    if (error instanceof TkcError) return { accepted: false, rule: error.rule, kind: error.kind, message: error.message };
    return { accepted: false, crashed: true, message: `${error && error.name}: ${error && error.message}\n${error && error.stack}` };
  }
});
process.stdout.write(JSON.stringify(results));
