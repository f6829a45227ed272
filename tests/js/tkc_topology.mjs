// node tkc_topology.mjs MANIFEST.json [--repeat N]: runs the JavaScript decoder's topology.js
// (U1's mesh prediction, spec §6.2) and traversal.js (faces-traverse, §6.8) on the cases that
// tests/test_js_topology.py wrote from the Python reference, and prints one JSON result per case:
//   {name, accepted: true, sha256, ms, ...}  the output's SHA-256 (faces as int32 LE, restored
//                                            columns as float64 LE, column after column); a
//                                            traverse case also gives array_buffer_bytes, the
//                                            typed arrays' bytes made by its first decode
//   {name, accepted: false, rule, kind, message}  a TkcError
//   {name, crash: "..."}                      anything else thrown (always a test failure)
// With --repeat N each case runs N times and `ms` is the fastest run (for measurements).
//
// Cases (paths relative to the manifest):
//   {kind: "traverse", name, entry: FILE (the section-table entry, msgpack), payload: FILE, K, M, n,
//    adaptive (the file sets flag bit 3: faces-traverse's coder may be 1),
//    uniform (the file sets flag bit 6: its ranks is read, and may be 1)}
//   {kind: "restore", name, faces: FILE (int32 M*n), K, M, n,
//    residuals: FILE (int32, or float64 with "wide": true, K*cols column-major), predict: [cols],
//    push: [cols] (optional: predictor 2's push per column, format 1.6; absent: 2)}

import { createHash } from 'node:crypto';
import { readFileSync } from 'node:fs';
import { dirname, join } from 'node:path';
import { TkcError } from '../../tuckercodec/web/tkc/errors.js';
import { unpack } from '../../tuckercodec/web/tkc/msgpack.js';
import { meshTopology, restoreMeshColumn } from '../../tuckercodec/web/tkc/topology.js';
import { decodeTraverse } from '../../tuckercodec/web/tkc/traversal.js';

const args = process.argv.slice(2);
const manifestPath = args[0];
const repeatAt = args.indexOf('--repeat');
const repeat = repeatAt >= 0 ? Number(args[repeatAt + 1]) : 1;
const root = dirname(manifestPath);
const manifest = JSON.parse(readFileSync(manifestPath, 'utf8'));

const bytes = (name) => new Uint8Array(readFileSync(join(root, name)));
const typed = (name, Type) => {
  const raw = bytes(name);
  return new Type(raw.buffer, raw.byteOffset, raw.byteLength / Type.BYTES_PER_ELEMENT);
};
const sha256 = (array) => createHash('sha256').update(new Uint8Array(array.buffer, array.byteOffset, array.byteLength)).digest('hex');

function runTraverse(spec) {
  const entry = unpack(bytes(spec.entry));
  const payload = bytes(spec.payload);
  let faces;
  let best = Infinity;
  let held = 0;
  for (let r = 0; r < repeat; r++) {
    const before = process.memoryUsage().arrayBuffers;
    const started = performance.now();
    faces = decodeTraverse(entry, payload, spec.K, spec.M, spec.n, undefined, spec.adaptive === true, spec.uniform === true);
    best = Math.min(best, performance.now() - started);
    // what the walk held at its end is still counted: nothing allocates between its return and this
    if (r === 0) held = process.memoryUsage().arrayBuffers - before;
  }
  return { accepted: true, sha256: sha256(faces), ms: best, array_buffer_bytes: held };
}

function runRestore(spec) {
  const faces = typed(spec.faces, Int32Array);
  const residuals = typed(spec.residuals, spec.wide ? Float64Array : Int32Array);
  const { K, M, n, predict } = spec;
  const out = new Float64Array(K * predict.length);
  let best = { ms: Infinity };
  let topo;
  for (let r = 0; r < repeat; r++) {
    const t0 = performance.now();
    topo = meshTopology(faces, M, n, K);
    const t1 = performance.now();
    let firstMean = null; // the first predictor-2 column also builds the mean's plan
    for (let c = 0; c < predict.length; c++) {
      const s = performance.now();
      const q = predict[c] === 0 ? Float64Array.from(residuals.subarray(c * K, (c + 1) * K))
        : restoreMeshColumn(residuals, c * K, predict[c], topo, `column ${c}`, spec.push ? spec.push[c] : undefined);
      if (predict[c] === 2 && firstMean === null) firstMean = performance.now() - s;
      out.set(q, c * K);
    }
    const t2 = performance.now();
    if (t2 - t0 < best.ms) best = { ms: t2 - t0, topology_ms: t1 - t0, columns_ms: t2 - t1, first_mean_ms: firstMean };
  }
  return {
    accepted: true, sha256: sha256(out), ...best, max_depth: topo.maxDepth,
    big_sources: topo.plan !== null && topo.plan.sources >= 2 ** 17, // push 2 sums in BigInt
  };
}

const results = [];
for (const spec of manifest.cases) {
  let result;
  try {
    result = spec.kind === 'traverse' ? runTraverse(spec) : runRestore(spec);
  } catch (error) {
    result = error instanceof TkcError
      ? { accepted: false, rule: error.rule, kind: error.kind, message: error.message }
      : { crash: String(error && error.stack ? error.stack : error) };
  }
  results.push({ name: spec.name, ...result });
}
process.stdout.write(JSON.stringify(results));
