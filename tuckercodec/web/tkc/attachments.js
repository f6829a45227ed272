// Format 1.5: what a file carries beside positions and faces, as ancillary sections that a
// decoder of 1.0 to 1.4 skips: ORDER (the faces' given order, §6.10), ATTR.n (static attributes,
// §6.11), FSET (face sets, §6.12) and FLD.n with its factors FLD.n.U1, .U3, .CORE and .MEAN
// (animated fields, §6.13). This module finds them in the section table and checks the table's
// rules for them (§5 step 19's first part); the codecs are in face_order.js, attributes.js,
// face_sets.js and fields.js.

import { TkcError, formatError } from './errors.js';

const NUMBER = '(0|[1-9][0-9]*)';
const ATTRIBUTE_ID = new RegExp(`^ATTR\\.${NUMBER}$`);
const FIELD_ID = new RegExp(`^FLD\\.${NUMBER}$`);
const FIELD_FACTOR_ID = new RegExp(`^FLD\\.${NUMBER}\\.(U1|U3|CORE|MEAN)$`);

/**
 * @typedef {import('./container.js').Section} Section
 * @typedef {{order: Section | null, attributes: Section[], faceSets: Section | null,
 *   fields: Section[], factors: Map<string, Section>}} Attached
 */

/**
 * The codec of a section of format 1.5 with this id, or null: not one of them.
 * @param {string} id
 * @returns {string | null}
 */
export function attachmentCodec(id) {
  if (id === 'ORDER') return 'face-order';
  if (id === 'FSET') return 'face-sets';
  if (ATTRIBUTE_ID.test(id)) return 'attribute';
  if (FIELD_ID.test(id)) return 'field';
  if (FIELD_FACTOR_ID.test(id)) return 'qmat';
  return null;
}

/**
 * §5 step 19, first part: each section of 1.5 is ancillary (R27) with its codec (R25); the
 * ATTR.n and FLD.n are numbered 0, 1, 2... without a gap (R43-attribute, R45-field), and every
 * factor section belongs to a field that has one (R45-field).
 * @param {Section[]} sections the section table
 * @returns {Attached}
 */
export function findAttachments(sections) {
  /** @type {Map<string, Section>} */
  const found = new Map();
  for (const section of sections) {
    const codec = attachmentCodec(section.id);
    if (codec === null) continue;
    if (section.critical) {
      throw formatError('R27-criticality', `section '${section.id}' has critical = true; §6.6 says false`);
    }
    if (section.codec !== codec) {
      throw new TkcError('UnsupportedVersionError', 'R25-unknown-codec', `section '${section.id}' has codec '${section.codec}'; this decoder reads '${codec}'`);
    }
    found.set(section.id, section);
  }
  const attributes = numbered(found, ATTRIBUTE_ID, 'ATTR', 'R43-attribute');
  const fields = numbered(found, FIELD_ID, 'FLD', 'R45-field');
  /** @type {Map<string, Section>} */
  const factors = new Map();
  for (const [id, section] of found) {
    const match = FIELD_FACTOR_ID.exec(id);
    if (match === null) continue;
    if (Number(match[1]) >= fields.length) {
      throw formatError('R45-field', `section '${id}' is a factor of field ${match[1]}, which has no section FLD.${match[1]}`);
    }
    factors.set(id, section);
  }
  return { order: found.get('ORDER') ?? null, attributes, faceSets: found.get('FSET') ?? null, fields, factors };
}

/**
 * The sections STEM.0, STEM.1... in order, refused with `rule` when their numbers have a gap.
 * @param {Map<string, Section>} found
 * @param {RegExp} pattern
 * @param {string} stem
 * @param {string} rule
 */
function numbered(found, pattern, stem, rule) {
  /** @type {Map<number, Section>} */
  const byNumber = new Map();
  for (const [id, section] of found) {
    const match = pattern.exec(id);
    // a number beyond 2^53 is not exact as a Number, but it is a gap whatever its value
    if (match !== null) byNumber.set(Number(match[1]), section);
  }
  const out = [];
  for (let n = 0; n < byNumber.size; n++) {
    const section = byNumber.get(n);
    if (section === undefined) {
      throw formatError(rule, `sections ${stem}.n are numbered 0, 1, 2... without a gap: ${stem}.${n} is missing`);
    }
    out.push(section);
  }
  return out;
}
