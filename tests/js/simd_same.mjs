// node simd_same.mjs FILE...: decodes every frame of each .tkc twice, with WebAssembly SIMD and
// with the JavaScript loop (openTkc's simd: false), and prints, as a JSON array, whether SIMD
// ran and how many values differ (reconstruct.js promises the same bits). The first entry is a
// synthetic basis of an odd K whose product uses fewer columns than it holds, against the plain
// sum. Run by tests/test_js_decoder.py.

import { readFileSync } from 'node:fs';
import { openTkc } from '../../tuckercodec/web/tkc/decoder.js';
import { SIMD_AVAILABLE, simdBasis } from '../../tuckercodec/web/tkc/simd.js';

function synthetic() {
  const K = 7;
  const columns = 5;
  const i = 3;
  let seed = 1;
  const random = () => ((seed = (seed * 16807) % 2147483647) / 2147483647) - 0.5;
  const u1 = Float64Array.from({ length: K * columns }, random);
  const W = Float64Array.from({ length: 3 * i }, random);
  const product = simdBasis(u1, K, columns).product(W, i);
  let differ = 0;
  for (let v = 0; v < K; v++) {
    for (let x = 0; x < 3; x++) {
      let sum = u1[v * columns] * W[x]; // §8.1: the first product starts the sum
      for (let a = 1; a < i; a++) sum += u1[v * columns + a] * W[3 * a + x];
      differ += !Object.is(sum, product[3 * v + x]);
    }
  }
  return { simd: SIMD_AVAILABLE, values: 3 * K, differ };
}

const results = [synthetic()].concat(process.argv.slice(2).map((path) => {
  const bytes = new Uint8Array(readFileSync(path));
  const fast = openTkc(bytes);
  const plain = openTkc(bytes, { simd: false });
  let differ = 0;
  for (let t = 0; t < fast.frames; t++) {
    const a = fast.frame(t);
    const b = plain.frame(t);
    for (let j = 0; j < a.length; j++) differ += !Object.is(a[j], b[j]);
  }
  return { simd: SIMD_AVAILABLE, values: fast.frames * 3 * fast.vertices, differ };
}));
process.stdout.write(JSON.stringify(results));
