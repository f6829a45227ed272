// Reconstruction (spec/FORMAT.md §8): positions[f, v, x] =
//   Σ_a Σ_c Σ_b U1[v, a] · CORE[a, c, b] · U2[x, c] · U3[f, b] + CENT[f, x],
// grouped as the reference groups it: B[a, x, b] = Σ_c CORE[a, c, b] · U2[x, c] once per
// segment, then per frame W[a, x] = Σ_b B[a, x, b] · U3[f, b] and U1 · W + CENT[f]. All binary64.
//
// B and W are summed in the order §8.1 writes (each sum starting from its first product, not
// from 0, which could only change the sign of a zero): a file with corrections (flag bit 2) is
// reconstructed by reconstructExact, §8.1's integer product, and the same bits in every decoder
// are what its corrections (§6.9) need.

import { formatError } from './errors.js';

/**
 * A decoded segment's factors, as reconstructFrame reads them (decoder.js makes them), and its
 * corrections (§6.9; null without flag bit 2) with their section's payload and, once decoded,
 * (1.8) its codebooks.
 * @typedef {{u1: Float64Array, columns: number, i: number, k: number, B: Float64Array,
 *   u3: Float64Array, core: Float64Array, cent: Float64Array, u2: Float64Array,
 *   simd?: import('./simd.js').SimdBasis | null,
 *   residual: import('./residual.js').Residual | null,
 *   residualPayload: Uint8Array | null, exact: Exact | null,
 *   codebooks?: import('./residual.js').Codebooks}} Factors
 */

/**
 * What §8.1 takes of U1 in a file with corrections: its restored integers q1 (K × columns,
 * row-major, as binary64), its steps (the f32 widened), and R, the largest Σ_a |q1[v, a]| over
 * the segment's i columns (exact below 2^53; a larger R fails every weight but 0 all the same).
 * @typedef {{q1: Float64Array, steps1: Float64Array, rowSum: number}} Exact
 */

/**
 * The per-segment product B (i × 3 × k, C order) of the core and U2.
 * @param {Float64Array} core
 * @param {Float64Array} u2
 * @param {number} i
 * @param {number} k
 */
export function coreTimesU2(core, u2, i, k) {
  const B = new Float64Array(i * 3 * k);
  for (let a = 0; a < i; a++) {
    for (let x = 0; x < 3; x++) {
      for (let b = 0; b < k; b++) {
        // (CORE[a, 0, b]·U2[x, 0] + CORE[a, 1, b]·U2[x, 1]) + CORE[a, 2, b]·U2[x, 2]
        const sum = core[(a * 3) * k + b] * u2[3 * x] + core[(a * 3 + 1) * k + b] * u2[3 * x + 1];
        B[(a * 3 + x) * k + b] = sum + core[(a * 3 + 2) * k + b] * u2[3 * x + 2];
      }
    }
  }
  return B;
}

/**
 * Frame t of a segment into `out` (K*3, any array type: Float64Array, or Float32Array for the
 * GPU, which rounds each binary64 position once). Every position must be finite (R36).
 * @template {Float64Array | Float32Array} T
 * @param {Factors} factors u1 is K × columns row-major (a shared basis may have more columns
 *   than the segment uses); simd, when not null, the same U1 laid out for WebAssembly SIMD
 *   (simd.js)
 * @param {number} t the frame within the segment
 * @param {T} out
 * @param {Float64Array} W scratch of i*3
 * @param {number} frameNumber the frame within the file, for messages
 * @returns {T}
 */
export function reconstructFrame(factors, t, out, W, frameNumber) {
  const { u1, columns, i, k, B, u3, cent, simd } = factors;
  for (let a = 0; a < i; a++) {
    for (let x = 0; x < 3; x++) {
      const row = (a * 3 + x) * k;
      let sum = B[row] * u3[t * k];
      for (let b = 1; b < k; b++) sum += B[row + b] * u3[t * k + b];
      W[a * 3 + x] = sum;
    }
  }
  const cx = cent[t * 3];
  const cy = cent[t * 3 + 1];
  const cz = cent[t * 3 + 2];
  const K = out.length / 3;
  let allFinite = true;
  if (simd) {
    // U1 · W in WebAssembly SIMD (simd.js): the same bits as the loop below, five times sooner
    const product = simd.product(W, i);
    for (let v = 0; v < 3 * K; v += 3) {
      const px = product[v] + cx;
      const py = product[v + 1] + cy;
      const pz = product[v + 2] + cz;
      if (px - px + (py - py) + (pz - pz) !== 0) allFinite = false;
      out[v] = px;
      out[v + 1] = py;
      out[v + 2] = pz;
    }
  } else {
    for (let v = 0; v < K; v++) {
      const base = v * columns;
      const first = u1[base];
      let px = first * W[0];
      let py = first * W[1];
      let pz = first * W[2];
      let a = 1;
      // four columns a step: a quarter of the loop's overhead, the same sum order
      for (; a + 3 < i; a += 4) {
        const w = 3 * a;
        const u0 = u1[base + a];
        const u1_ = u1[base + a + 1];
        const u2_ = u1[base + a + 2];
        const u3_ = u1[base + a + 3];
        px += u0 * W[w]; py += u0 * W[w + 1]; pz += u0 * W[w + 2];
        px += u1_ * W[w + 3]; py += u1_ * W[w + 4]; pz += u1_ * W[w + 5];
        px += u2_ * W[w + 6]; py += u2_ * W[w + 7]; pz += u2_ * W[w + 8];
        px += u3_ * W[w + 9]; py += u3_ * W[w + 10]; pz += u3_ * W[w + 11];
      }
      for (; a < i; a++) {
        const u = u1[base + a];
        px += u * W[3 * a];
        py += u * W[3 * a + 1];
        pz += u * W[3 * a + 2];
      }
      px += cx;
      py += cy;
      pz += cz;
      // x − x is 0 for every finite x and NaN for ±∞ and NaN: one test for the three values
      if (px - px + (py - py) + (pz - pz) !== 0) allFinite = false;
      out[3 * v] = px;
      out[3 * v + 1] = py;
      out[3 * v + 2] = pz;
    }
  }
  if (!allFinite) {
    for (let v = 0; v < K; v++) {
      for (let x = 0; x < 3; x++) {
        const p = reconstructAgain(factors, t, v, x, W);
        if (!Number.isFinite(p)) {
          throw formatError('R36-reconstruction-finite', `frame ${frameNumber}, vertex ${v}, axis ${'xyz'[x]}: the reconstruction is ${p}, not finite`);
        }
      }
    }
  }
  return out;
}

/**
 * @param {Factors} factors
 * @param {number} t
 * @param {number} v
 * @param {number} x
 * @param {Float64Array} W
 */
function reconstructAgain(factors, t, v, x, W) {
  const { u1, columns, i, cent } = factors;
  let p = u1[v * columns] * W[x];
  for (let a = 1; a < i; a++) p += u1[v * columns + a] * W[a * 3 + x];
  return p + cent[t * 3 + x];
}

/**
 * 2^n as binary64, from its bits (n in −1022..1023: a normal number, exact).
 * @param {number} n
 */
function powerOfTwo(n) {
  const view = new DataView(new ArrayBuffer(8));
  view.setUint32(4, (n + 1023) << 20, true);
  return view.getFloat64(0, true);
}

/**
 * Rounded to the nearest integer, ties to even (Math.round sends ties toward +∞).
 * @param {number} x
 */
function roundHalfEven(x) {
  const r = Math.round(x);
  return r - x === 0.5 && r % 2 !== 0 ? r - 1 : r;
}

/**
 * §8.1's integer weights of frame t of a segment: W[a, x] summed over b in order, then
 * w[a, x] = round((step1[a]·W[a, x])·2^−e), ties to even, into `w` (i·3). Returns the largest
 * |w|, or NaN when a weight is not finite.
 * @param {Factors} factors its `exact` set
 * @param {number} t
 * @param {Float64Array} w
 * @param {number} exponent e
 */
export function exactWeights(factors, t, w, exponent) {
  const { i, k, B, u3 } = factors;
  const steps = /** @type {Exact} */ (factors.exact).steps1;
  const down = powerOfTwo(-exponent);
  let largest = 0;
  for (let a = 0; a < i; a++) {
    for (let x = 0; x < 3; x++) {
      const row = (a * 3 + x) * k;
      let W = B[row] * u3[t * k];
      for (let b = 1; b < k; b++) W += B[row + b] * u3[t * k + b];
      const weight = roundHalfEven(steps[a] * W * down); // (step1·W)·2^−e: two roundings
      w[a * 3 + x] = weight;
      const size = Math.abs(weight);
      if (size - size !== 0) return NaN; // ±∞ or NaN: R41 (the others need not be made)
      if (size > largest) largest = size;
    }
  }
  return largest;
}

/**
 * Whether R·largest <= 2^53 (§8.1, R41): exact, with BigInt where the product nears 2^53.
 * @param {number} rowSum R
 * @param {number} largest the largest |w|, an integer or NaN
 */
export function weightsFit(rowSum, largest) {
  if (largest !== largest) return false;
  if (rowSum * largest < 2 ** 52) return true; // rounding is monotone: then the exact one is too
  return BigInt(rowSum) * BigInt(largest) <= 2n ** 53n; // both integers
}

/**
 * P of §8.1 for frame t of a segment, from its weights w (exactWeights, checked by
 * weightsFit): S = q1·w, an integer product exact in any order (so WebAssembly SIMD or the
 * JavaScript loop), then P = S·2^e + CENT[t], one multiplication and one addition.
 * @param {Factors} factors its `exact` set; simd, when not null, q1 laid out for SIMD
 * @param {number} t
 * @param {Float64Array} P K·3
 * @param {Float64Array} w
 * @param {number} exponent
 */
export function reconstructExact(factors, t, P, w, exponent) {
  const { columns, i, cent, simd } = factors;
  const q1 = /** @type {Exact} */ (factors.exact).q1;
  const up = powerOfTwo(exponent);
  const cx = cent[t * 3];
  const cy = cent[t * 3 + 1];
  const cz = cent[t * 3 + 2];
  const K = P.length / 3;
  if (simd) {
    const S = simd.product(w, i);
    for (let v = 0; v < 3 * K; v += 3) {
      P[v] = S[v] * up + cx;
      P[v + 1] = S[v + 1] * up + cy;
      P[v + 2] = S[v + 2] * up + cz;
    }
    return P;
  }
  for (let v = 0; v < K; v++) {
    const base = v * columns;
    let sx = 0;
    let sy = 0;
    let sz = 0;
    for (let a = 0; a < i; a++) {
      const q = q1[base + a];
      sx += q * w[3 * a];
      sy += q * w[3 * a + 1];
      sz += q * w[3 * a + 2];
    }
    P[3 * v] = sx * up + cx;
    P[3 * v + 1] = sy * up + cy;
    P[3 * v + 2] = sz * up + cz;
  }
  return P;
}
