// node --import ./three_from_vendor.mjs ...: resolves the bare specifier `three` to the copy the
// viewer vendors (tuckercodec/web/vendor/three), so that TKCLoader runs in node from a clone,
// without npm (a page does the same with an import map). Used by memory.mjs.

import { register } from 'node:module';

const THREE = new URL('../../tuckercodec/web/vendor/three/three.module.js', import.meta.url).href;

const HOOK = `export async function resolve(specifier, context, next) {
  return specifier === 'three' ? { url: ${JSON.stringify(THREE)}, shortCircuit: true } : next(specifier, context);
}`;
register(`data:text/javascript,${encodeURIComponent(HOOK)}`);
