// `npm test` (node --test): the nearest codebook entry j of spec/FORMAT.md §6.9 (format 1.8's
// codebooks) as residual.js's MiddleIndex finds it, against a BigInt transcription of the spec's
// words, on codebooks that reach what the index's parts could get wrong: the whole int64 range
// (the widest span of midpoints, 2^64 − 2, cut by shifts above 32), entries crowded into a few
// narrow ranges far apart (one part holding hundreds of midpoints, most parts none), spans on
// either side of 2^32 (shifts near 32), spans narrower than the midpoints are many (shift 0),
// codebooks of one and two entries, and neighbours one apart; asked at every entry, at every
// midpoint and one either side (the ties), past both ends, at both ends of int64, at distances
// from the first midpoint whose low halves are all zeros or all ones, and at random.
// Whole files with codebooks are tests/test_js_codebooks.py's.

import assert from 'node:assert/strict';
import { test } from 'node:test';
import { MiddleIndex } from '../../tuckercodec/web/tkc/residual.js';

const MIN = -(2n ** 63n);
const MAX = 2n ** 63n - 1n;

/** j of §6.9, word for word: the largest j with C[j] <= b, or 0 if none; j + 1 where j + 1 < n,
 * C[j] <= b and C[j + 1] − b < b − C[j] (a tie keeps j). */
function nearestBySpec(book, b) {
  let j = -1;
  for (let m = 0; m < book.length && book[m] <= b; m++) j = m;
  if (j < 0) return 0;
  return j + 1 < book.length && book[j + 1] - b < b - book[j] ? j + 1 : j;
}

/** A seeded generator of 64-bit values (splitmix64). */
function random(seed) {
  let state = BigInt(seed);
  return () => {
    state = BigInt.asUintN(64, state + 0x9e3779b97f4a7c15n);
    let z = state;
    z = BigInt.asUintN(64, (z ^ (z >> 30n)) * 0xbf58476d1ce4e5b9n);
    z = BigInt.asUintN(64, (z ^ (z >> 27n)) * 0x94d049bb133111ebn);
    return BigInt.asIntN(64, z ^ (z >> 31n));
  };
}

/** The values worth asking of a codebook: the ends of int64, each entry and midpoint and their
 * neighbours, and `extra` more near random entries. */
function questions(book, next, extra) {
  const values = [MIN, MAX, 0n, -1n, 1n];
  const near = (v) => [v - 1n, v, v + 1n].filter((w) => w >= MIN && w <= MAX);
  book.forEach((c, m) => {
    values.push(...near(c));
    if (m + 1 < book.length) values.push(...near((c + book[m + 1]) >> 1n));
  });
  if (book.length > 1) {
    // the distances from the first midpoint with the last one's high half and a low half of all
    // zeros or all ones: a borrow or a comparison of halves gone wrong shows there
    const first = (book[0] + book[1]) >> 1n;
    const span = ((book.at(-2) + book.at(-1)) >> 1n) - first;
    values.push(...[span | 0xffffffffn, span & ~0xffffffffn, (span & ~0xffffffffn) - 1n].map((d) => first + d).filter((v) => v <= MAX));
  }
  for (let i = 0; i < extra; i++) {
    const c = book[Number(BigInt.asUintN(32, next()) % BigInt(book.length))];
    const w = c + (next() % 64n);
    if (w >= MIN && w <= MAX) values.push(w);
  }
  return values;
}

/** Every value's j by the index, against the spec's. */
function check(name, entries, extra = 2000) {
  const book = [...new Set(entries)].sort((a, b) => (a < b ? -1 : a > b ? 1 : 0));
  const index = new MiddleIndex(new Int32Array(BigInt64Array.from(book).buffer));
  const next = random(book.length);
  for (const b of questions(book, next, extra)) {
    const j = index.countBelow(Number(b >> 32n), Number(BigInt.asUintN(32, b)));
    if (j !== nearestBySpec(book, b)) assert.fail(`${name}: b = ${b}: the index gives ${j}, §6.9 ${nearestBySpec(book, b)}`);
  }
  return index;
}

test('the index gives the spec\'s entry across the whole int64 range', () => {
  const next = random(7);
  const spread = Array.from({ length: 300 }, next);
  check('spread', [...spread, MIN + 5n, MAX - 5n, -1n, 0n, 1n]);
  const widest = check('widest', [MIN, MIN + 1n, -1n, 0n, MAX - 1n, MAX]);
  assert.equal(widest.shift, 61); // midpoints MIN .. MAX − 1: 64 bits, 5 midpoints, 8 parts
  check('ends', [MIN, MAX]);
});

test('clustered codebooks: one part holds many entries', () => {
  const crowded = Array.from({ length: 600 }, (_, n) => [-(2n ** 40n), 17n, 2n ** 50n][n % 3] + 3n * BigInt(n));
  const index = check('crowded', crowded);
  const widest = Math.max(...index.starts.slice(1).map((s, k) => s - index.starts[k]));
  assert.ok(widest >= 100, `the largest part holds ${widest} midpoints`);
  // a few entries near each end of int64 and a dense run in the middle
  const dense = Array.from({ length: 500 }, (_, n) => 1000n + BigInt(n));
  check('ends-and-dense', [MIN, MIN + 2n, MAX - 3n, MAX, ...dense]);
});

test('spans either side of 2^32, and narrower than the entries are many', () => {
  for (const bits of [20, 31, 32, 33, 34, 40, 52, 62]) {
    for (const count of [3, 255, 256, 257, 1000]) {
      const next = random(bits * 4096 + count);
      const base = BigInt.asIntN(64, next()) >> 2n;
      const entries = Array.from({ length: count }, () => base + BigInt.asUintN(bits, next()));
      check(`span 2^${bits}, ${count} entries`, entries, 300);
    }
  }
  const narrow = check('neighbours one apart', Array.from({ length: 100 }, (_, n) => BigInt(n - 50)));
  assert.equal(narrow.shift, 0);
});

test('codebooks of one and two entries', () => {
  for (const book of [[42n], [MIN], [MAX], [-5n, 5n], [-5n, -4n], [MIN, MAX], [0n, 2n ** 32n]]) {
    check(`[${book.join(', ')}]`, book);
  }
});
