//! The loops of tuckercodec that Python cannot run fast, in memory-safe Rust.
//!
//! Every function here reads values that came from a file, so each count, index and length is
//! checked before it is used, and a bad value is an [`error::Broken`] naming the same rule and
//! saying the same thing as the Python reference (`tuckercodec/format/`), never a panic.
#![forbid(unsafe_code)]

pub mod adaptive;
pub mod codebooks;
pub mod encoder;
pub mod error;
pub mod fuzzing;
pub mod prediction;
pub mod residual;
pub mod streams;
#[cfg(test)]
mod test_random;
pub mod text;
pub mod traversal;
