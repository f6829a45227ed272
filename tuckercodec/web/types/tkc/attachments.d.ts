export type Section = import('./container.js').Section;
export type Attached = {
    order: Section | null;
    attributes: Section[];
    faceSets: Section | null;
    fields: Section[];
    factors: Map<string, Section>;
};
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
export declare function attachmentCodec(id: string): string | null;
/**
 * §5 step 19, first part: each section of 1.5 is ancillary (R27) with its codec (R25); the
 * ATTR.n and FLD.n are numbered 0, 1, 2... without a gap (R43-attribute, R45-field), and every
 * factor section belongs to a field that has one (R45-field).
 * @param {Section[]} sections the section table
 * @returns {Attached}
 */
export declare function findAttachments(sections: Section[]): Attached;
