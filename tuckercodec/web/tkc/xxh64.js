// XXH64 with seed 0, for the optional content checksum of a Zstandard frame (RFC 8878 §3.1.1:
// the low 32 bits of XXH64 of the content). BigInt arithmetic: simple and exact; the reference
// encoder writes no checksum, so this runs only on frames made elsewhere.

const MASK = (1n << 64n) - 1n;
const P1 = 11400714785074694791n;
const P2 = 14029467366897019727n;
const P3 = 1609587929392839161n;
const P4 = 9650029242287828579n;
const P5 = 2870177450012600261n;

/** @type {(x: bigint, r: bigint) => bigint} */
const rotl = (x, r) => ((x << r) | (x >> (64n - r))) & MASK;
/** @type {(acc: bigint, lane: bigint) => bigint} */
const round = (acc, lane) => (rotl((acc + lane * P2) & MASK, 31n) * P1) & MASK;
/** @type {(acc: bigint, value: bigint) => bigint} */
const merge = (acc, value) => (((acc ^ round(0n, value)) * P1) & MASK) + P4 & MASK;

/**
 * The low 32 bits of XXH64(bytes, seed 0), as an unsigned number.
 * @param {Uint8Array} bytes
 */
export function xxh64Low32(bytes) {
  const view = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
  const n = bytes.length;
  let i = 0;
  let h;
  if (n >= 32) {
    let v1 = (P1 + P2) & MASK;
    let v2 = P2;
    let v3 = 0n;
    let v4 = (0n - P1) & MASK;
    for (; i + 32 <= n; i += 32) {
      v1 = round(v1, view.getBigUint64(i, true));
      v2 = round(v2, view.getBigUint64(i + 8, true));
      v3 = round(v3, view.getBigUint64(i + 16, true));
      v4 = round(v4, view.getBigUint64(i + 24, true));
    }
    h = (rotl(v1, 1n) + rotl(v2, 7n) + rotl(v3, 12n) + rotl(v4, 18n)) & MASK;
    h = merge(h, v1);
    h = merge(h, v2);
    h = merge(h, v3);
    h = merge(h, v4);
  } else {
    h = P5;
  }
  h = (h + BigInt(n)) & MASK;
  for (; i + 8 <= n; i += 8) {
    h ^= round(0n, view.getBigUint64(i, true));
    h = (rotl(h, 27n) * P1 + P4) & MASK;
  }
  if (i + 4 <= n) {
    h ^= (BigInt(view.getUint32(i, true)) * P1) & MASK;
    h = (rotl(h, 23n) * P2 + P3) & MASK;
    i += 4;
  }
  for (; i < n; i++) {
    h ^= (BigInt(bytes[i]) * P5) & MASK;
    h = (rotl(h, 11n) * P1) & MASK;
  }
  h ^= h >> 33n;
  h = (h * P2) & MASK;
  h ^= h >> 29n;
  h = (h * P3) & MASK;
  h ^= h >> 32n;
  return Number(h & 0xffffffffn);
}
