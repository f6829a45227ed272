// §8's per-frame product U1 · W (K × i by i × 3) in WebAssembly SIMD: two vertices at a time,
// each f64x2 lane one vertex, so three vector multiply-adds do the work of six scalar ones
// (samba's frame: 0.3 ms against 1.5 ms for the JavaScript loop in node).
//
// The module is assembled here from named opcodes, so there is no toolchain and no build step:
// one function, frame(u1, w, out, pairs, columns, skip), over one memory the caller fills. Each
// lane computes x = u·W[0, x], then x += u·W[a, x] for a = 1, 2, ... (the order of §8.1) with
// the JavaScript loop's binary64 multiply and add (WebAssembly never fuses them): both paths
// give the same bits, and an engine without WebAssembly SIMD uses the JavaScript loop
// (reconstruct.js).

const I32 = 0x7f;
const V128 = 0x7b;
const op = {
  block: 0x02, loop: 0x03, end: 0x0b, br: 0x0c, brIf: 0x0d, void: 0x40,
  get: 0x20, set: 0x21, i32Const: 0x41, i32Add: 0x6a, i32GeU: 0x4f, f64Store: 0x39,
};
/** @typedef {{product(W: Float64Array, i: number): Float64Array}} SimdBasis */

/** @type {(code: number) => number[]} */
const simd = (code) => [0xfd, ...uleb(code)];
/** @type {(offset: number) => number[]} */
const v128Load = (offset) => [...simd(0x00), 4, ...uleb(offset)]; // align 2^4
const f64x2Add = simd(0xf0);
const f64x2Mul = simd(0xf2);
/** @type {(lane: number) => number[]} */
const extract = (lane) => [...simd(0x21), lane];

/**
 * @param {number} value
 * @returns {number[]}
 */
function uleb(value) {
  const out = [];
  do {
    let byte = value & 0x7f;
    value >>>= 7;
    if (value) byte |= 0x80;
    out.push(byte);
  } while (value);
  return out;
}
/** @type {(id: number, bytes: number[]) => number[]} */
const section = (id, bytes) => [id, ...uleb(bytes.length), ...bytes];
/** @type {(items: (number | number[])[]) => number[]} */
const vector = (items) => [...uleb(items.length), ...items.flat()];
/** @type {(text: string) => number[]} */
const name = (text) => [...uleb(text.length), ...Array.from(text, (c) => c.charCodeAt(0))];

// parameters and locals
const [U1, W, OUT, PAIRS, COLUMNS, SKIP] = [0, 1, 2, 3, 4, 5];
const [P, A, PU, PW, PO] = [6, 7, 8, 9, 10];
const [X, Y, Z, U] = [11, 12, 13, 14];
/** @type {(i: number) => number[]} */
const get = (i) => [op.get, i];
/** @type {(i: number) => number[]} */
const set = (i) => [op.set, i];
/** @type {(local: number, n: number) => number[]} */
const addConst = (local, n) => [...get(local), op.i32Const, ...uleb(n), op.i32Add, ...set(local)];
// accumulator += u · W-pair at byte offset `offset` of PW
/** @type {(acc: number, offset: number) => number[]} */
const multiplyAdd = (acc, offset) => [...get(acc), ...get(U), ...get(PW), ...v128Load(offset), ...f64x2Mul, ...f64x2Add, ...set(acc)];
// accumulator = u · W-pair at byte offset `offset` of PW
/** @type {(acc: number, offset: number) => number[]} */
const product = (acc, offset) => [...get(U), ...get(PW), ...v128Load(offset), ...f64x2Mul, ...set(acc)];
/** @type {(acc: number, lane: number, offset: number) => number[]} */
const store = (acc, lane, offset) => [...get(PO), ...get(acc), ...extract(lane), op.f64Store, 3, ...uleb(offset)];

const body = [
  ...get(U1), ...set(PU), ...get(OUT), ...set(PO), op.i32Const, 0, ...set(P),
  op.block, op.void, op.loop, op.void,
  ...get(P), ...get(PAIRS), op.i32GeU, op.brIf, 1,
  // column 0 starts each sum (§8.1: S = U1[v, 0]·W[0, x], then + U1[v, a]·W[a, x] for a = 1...)
  ...get(W), ...set(PW), ...get(PU), ...v128Load(0), ...set(U),
  ...product(X, 0), ...product(Y, 16), ...product(Z, 32),
  ...addConst(PU, 16), ...addConst(PW, 48), op.i32Const, 1, ...set(A),
  op.block, op.void, op.loop, op.void,
  ...get(A), ...get(COLUMNS), op.i32GeU, op.brIf, 1,
  ...get(PU), ...v128Load(0), ...set(U),
  ...multiplyAdd(X, 0), ...multiplyAdd(Y, 16), ...multiplyAdd(Z, 32),
  ...addConst(PU, 16), ...addConst(PW, 48), ...addConst(A, 1),
  op.br, 0, op.end, op.end,
  // a shared basis may hold more columns than the segment uses: step over the rest
  ...get(PU), ...get(SKIP), op.i32Add, ...set(PU),
  ...store(X, 0, 0), ...store(Y, 0, 8), ...store(Z, 0, 16),
  ...store(X, 1, 24), ...store(Y, 1, 32), ...store(Z, 1, 40),
  ...addConst(PO, 48), ...addConst(P, 1),
  op.br, 0, op.end, op.end,
  op.end,
];
const locals = vector([[5, I32], [4, V128]]);
const code = [...locals, ...body];

const BYTES = new Uint8Array([
  0x00, 0x61, 0x73, 0x6d, 0x01, 0x00, 0x00, 0x00,
  ...section(1, vector([[0x60, ...vector([I32, I32, I32, I32, I32, I32]), 0]])), // type: (i32 x6) -> ()
  ...section(2, vector([[...name('m'), ...name('memory'), 0x02, 0x00, 0x01]])), // import memory, min 1 page
  ...section(3, vector([0])), // one function of type 0
  ...section(7, vector([[...name('frame'), 0x00, 0]])), // export it
  ...section(10, vector([[...uleb(code.length), ...code]])),
]);

/** True where this engine runs WebAssembly SIMD (every current browser and node 16+). */
export const SIMD_AVAILABLE = typeof WebAssembly === 'object' && WebAssembly.validate(BYTES);

const PAGE = 65536;
// wasm32 memory is at most 4 GiB; engines may refuse less (then the JavaScript loop)
const MAX_PAGES = 65536;

/**
 * U1 (K × columns, row-major) laid out for the SIMD loop, vertex pairs interleaved:
 * (u[2p, a], u[2p+1, a]) for every column. Returns null where the module cannot run or its
 * memory cannot be had (the caller then uses the JavaScript loop).
 * @param {Float64Array} u1
 * @param {number} K
 * @param {number} columns
 * @returns {SimdBasis | null}
 */
export function simdBasis(u1, K, columns) {
  if (!SIMD_AVAILABLE) return null;
  const pairs = Math.ceil(K / 2);
  const u1Bytes = pairs * columns * 16;
  const wBytes = columns * 48;
  const outBytes = pairs * 48;
  const pages = Math.ceil((u1Bytes + wBytes + outBytes) / PAGE);
  if (pages > MAX_PAGES) return null;
  let memory;
  let frame;
  try {
    memory = new WebAssembly.Memory({ initial: pages });
    const exports = new WebAssembly.Instance(new WebAssembly.Module(BYTES), { m: { memory } }).exports;
    frame = /** @type {(...args: number[]) => void} */ (exports.frame);
  } catch (error) {
    // no memory for it (RangeError), or a page whose Content-Security-Policy does not allow
    // 'wasm-unsafe-eval' (CompileError): the JavaScript loop does the same, slower
    if (error instanceof RangeError || error instanceof WebAssembly.CompileError) return null;
    throw error;
  }
  const heap = new Float64Array(memory.buffer);
  for (let p = 0; p < pairs; p++) {
    const second = 2 * p + 1 < K;
    for (let a = 0; a < columns; a++) {
      const at = 2 * (p * columns + a);
      heap[at] = u1[2 * p * columns + a];
      heap[at + 1] = second ? u1[(2 * p + 1) * columns + a] : 0;
    }
  }
  const wAt = u1Bytes / 8;
  const outAt = (u1Bytes + wBytes) / 8;
  return {
    /**
     * U1[:, :i] · W (W: i × 3, row-major), as a K*3 view of the module's memory, valid until
     * the next call.
     * @param {Float64Array} W
     * @param {number} i
     */
    product(W, i) {
      for (let a = 0; a < i; a++) {
        for (let x = 0; x < 3; x++) {
          heap[wAt + 6 * a + 2 * x] = W[3 * a + x];
          heap[wAt + 6 * a + 2 * x + 1] = W[3 * a + x];
        }
      }
      frame(0, u1Bytes, u1Bytes + wBytes, pairs, i, 16 * (columns - i));
      return heap.subarray(outAt, outAt + 3 * K);
    },
  };
}
