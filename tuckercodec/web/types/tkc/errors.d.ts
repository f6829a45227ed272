/** The error classes of §11; `TkcError.kind` is one of them. */
export declare const KINDS: readonly string[];
/** A file that breaks a rule of spec/FORMAT.md §11. */
export declare class TkcError extends Error {
    kind: string;
    rule: string;
    /**
     * @param {string} kind one of KINDS
     * @param {string} rule the §11 identifier, e.g. "R19-section-crc"
     * @param {string} message what is wrong and where (field, section, offset)
     */
    constructor(kind: string, rule: string, message: string);
}
/**
 * A FormatError (the class of most rules).
 * @param {string} rule
 * @param {string} message
 */
export declare function formatError(rule: string, message: string): TkcError;
/**
 * A LimitError: the file declares more than this decoder's limits allow (§7).
 * @param {string} rule
 * @param {string} message
 */
export declare function limitError(rule: string, message: string): TkcError;
