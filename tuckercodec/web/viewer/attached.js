// What the viewer shows of a file's format 1.5 sections: a checker texture to see its UVs, and
// the list of its attributes, face sets and fields with the bytes each takes in the file.

/**
 * @typedef {typeof import('three')} Three
 * @typedef {import('../tkc/decoder.js').TkcFile} TkcFile
 */

/**
 * A checker of 8 × 8 squares whose colour runs from blue (u = 0) to red (u = 1) and dark to
 * light (v = 0 to 1), so that a UV's direction shows as well as its stretch.
 * @param {Three} THREE
 */
export function checkerTexture(THREE) {
  const size = 256;
  const pixels = new Uint8Array(size * size * 4);
  for (let y = 0; y < size; y++) {
    for (let x = 0; x < size; x++) {
      const dark = ((x >> 5) + (y >> 5)) % 2 === 0;
      const light = dark ? 0.45 : 1;
      const at = 4 * (y * size + x);
      pixels[at] = Math.round(255 * light * (x / size));
      pixels[at + 1] = Math.round(255 * light * (0.3 + 0.7 * (y / size)));
      pixels[at + 2] = Math.round(255 * light * (1 - x / size));
      pixels[at + 3] = 255;
    }
  }
  const texture = new THREE.DataTexture(pixels, size, size);
  texture.wrapS = texture.wrapT = THREE.RepeatWrapping;
  texture.magFilter = THREE.NearestFilter;
  texture.colorSpace = THREE.SRGBColorSpace;
  texture.needsUpdate = true;
  return texture;
}

/**
 * The bytes of the section `id` in the file, or 0.
 * @param {TkcFile} file
 * @param {string} id
 */
function sectionBytes(file, id) {
  const section = file.container.sections.find((s) => s.id === id);
  return section ? section.length : 0;
}

/** @param {number} bytes */
function bytesText(bytes) {
  return `${bytes.toLocaleString('en')} bytes`;
}

/**
 * One row per attribute, face set and field: [term, description], empty for a file without.
 * @param {TkcFile} file
 * @returns {[string, string][]}
 */
export function attachedRows(file) {
  /** @type {[string, string][]} */
  const rows = file.attributes.map((a, n) => [
    a.name,
    `${a.role} per ${a.domain}: ${a.rows.toLocaleString('en')} × ${a.components} ${a.type}` +
      `${a.indices === null ? '' : ', indexed'}; ${bytesText(sectionBytes(file, `ATTR.${n}`))}`,
  ]);
  const setBytes = sectionBytes(file, 'FSET');
  for (const s of file.faceSets) {
    rows.push([s.name, `face set${s.family ? ` (${s.family})` : ''}: ${s.faces.length.toLocaleString('en')} faces`]);
  }
  if (setBytes) rows.push(['face sets', `${bytesText(setBytes)} in all`]);
  file.attached.fields.forEach((section, n) => {
    const name = section.entry.get('name');
    let bytes = section.length;
    for (const [id, factor] of file.attached.factors) if (id.startsWith(`FLD.${n}.`)) bytes += factor.length;
    rows.push([typeof name === 'string' ? name : `FLD.${n}`, `animated field; ${bytesText(bytes)}`]);
  });
  const order = sectionBytes(file, 'ORDER');
  if (order) rows.push(['face order', `kept as given; ${bytesText(order)}`]);
  return rows;
}
