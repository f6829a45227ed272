// The script of tests/js/conformance.html (a file: the server's policy refuses inline scripts).
import { observeVector } from './conformance_observe.mjs';

async function fetchBytes(url) {
  const response = await fetch(url);
  if (!response.ok) throw new Error(`${url}: HTTP ${response.status}`);
  return new Uint8Array(await response.arrayBuffer());
}

window.observeVectors = async (vectors) => {
  const results = {};
  for (const [name, tkc, npy] of vectors) {
    results[name] = await observeVector(await fetchBytes(tkc), npy ? await fetchBytes(npy) : null);
  }
  document.getElementById('status').textContent = `observed ${vectors.length} vectors`;
  return results;
};
