//! §6.8 codec `faces-traverse`: connectivity coded by walking across the faces' edges
//! (`tuckercodec/format/traversal.py` is the reference; read its module docstring first).
//!
//! [`decode`] rebuilds the faces from the four integer streams (ops, degrees, vertices,
//! references), with the checks and the error details of the Python walk (`_walk`, and
//! `_walk_triangles` which gives the same faces and errors for triangles); it is also the entry
//! point for fuzzing, as it takes any values and never panics. [`encode`] computes the streams
//! of a face table, the values of Python's `_Walk`, for both corner orders. [`ranks`] and
//! [`vertices`] turn the NEW vertices into their ranks among the unseen ones and back (`coder`
//! 1, format 1.6): the walk itself reads and writes gaps whichever coder the file uses.

mod boundary;
mod decode;
mod encode;
mod hash;
mod ranks;

pub use decode::{decode, Streams};
pub use encode::{encode, Walked};
pub use ranks::{ranks, vertices};

/// The rule a broken walk breaks (spec §11).
pub const RULE: &str = "R39-traversal";
/// Gate kinds and tip operations (§6.8; `GATE_*` and `TIP_*` in traversal.py).
pub const GATE_NONE: i64 = 0;
pub const TIP_NEW: i64 = 0;
pub const TIP_PREV: i64 = 1;
pub const TIP_NEXT: i64 = 2;
pub const TIP_FAR: i64 = 3;
/// `corner_order`: the rotation counts from the walk's first corner, or from the smallest vertex.
pub const ROTATE_FROM_GATE: i64 = 0;
pub const ROTATE_FROM_SMALLEST: i64 = 1;
/// The most values the four streams may hold together (2**30): the walk numbers its edges by
/// u32 (a face's corners are at most 3 per op). A section's limits keep real files far below;
/// the callers run the Python reference beyond it.
pub const MAX_VALUES: usize = 1 << 30;
/// The four streams' names, in the payload's order (error messages name them).
pub const STREAM_NAMES: [&str; 4] = ["ops", "degrees", "vertices", "references"];

/// The key of the directed edge x -> y between two vertex ids below 2**32.
#[inline]
fn edge(x: u32, y: u32) -> u64 {
    (u64::from(x) << 32) | u64::from(y)
}

/// The ends (x, y) of the edge `key`.
#[inline]
fn ends(key: u64) -> (u32, u32) {
    ((key >> 32) as u32, key as u32)
}

/// The position of the first smallest value of `cycle` (Python's `cycle.index(min(cycle))`).
fn first_smallest<T: Ord + Copy>(cycle: &[T]) -> usize {
    let mut best = 0;
    for (j, value) in cycle.iter().enumerate() {
        if *value < cycle[best] {
            best = j;
        }
    }
    best
}

#[cfg(test)]
mod tests;
