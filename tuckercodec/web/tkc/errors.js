// The decoder's one error class (spec/FORMAT.md §1 "Conformance", §11).
//
// Every failure of a file carries the identifier of the §11 rule it breaks (`rule`) and the
// class the reference decoder raises for it (`kind`), so that callers and the conformance tests
// compare failures by rule, not by wording. The message ends with the rule, as the reference's
// does: "... [R09-trailing-bytes]".

/** The error classes of §11; `TkcError.kind` is one of them. */
export const KINDS = Object.freeze([
  'FormatError',
  'TruncatedFileError',
  'ChecksumError',
  'UnsupportedVersionError',
  'LimitError',
]);

/** A file that breaks a rule of spec/FORMAT.md §11. */
export class TkcError extends Error {
  /**
   * @param {string} kind one of KINDS
   * @param {string} rule the §11 identifier, e.g. "R19-section-crc"
   * @param {string} message what is wrong and where (field, section, offset)
   */
  constructor(kind, rule, message) {
    super(`${message} [${rule}]`);
    this.name = 'TkcError';
    this.kind = kind;
    this.rule = rule;
  }
}

/**
 * A FormatError (the class of most rules).
 * @param {string} rule
 * @param {string} message
 */
export function formatError(rule, message) {
  return new TkcError('FormatError', rule, message);
}

/**
 * A LimitError: the file declares more than this decoder's limits allow (§7).
 * @param {string} rule
 * @param {string} message
 */
export function limitError(rule, message) {
  return new TkcError('LimitError', rule, message);
}
