//! A fast hasher for the walk's edge keys (u64), so that no hashing crate is needed: std's
//! SipHash costs several times more, and the keys come from the walk, not from a file's bytes
//! chosen to collide (a crafted file can at worst make its own decode slower).

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

/// Multiplies the key by a large odd constant and folds the high half into the low one, so the
/// bucket (low bits) and hashbrown's tag (high bits) both depend on every bit of the key.
#[derive(Default, Clone, Copy)]
pub struct EdgeHasher(u64);

impl Hasher for EdgeHasher {
    #[inline]
    fn finish(&self) -> u64 {
        let h = self.0.wrapping_mul(0x9E37_79B9_7F4A_7C15);
        h ^ (h >> 32)
    }

    #[inline]
    fn write(&mut self, bytes: &[u8]) {
        for byte in bytes {
            self.0 = (self.0.rotate_left(8) ^ u64::from(*byte)).wrapping_mul(0x100_0000_01B3);
        }
    }

    #[inline]
    fn write_u64(&mut self, value: u64) {
        self.0 = self.0.rotate_left(23) ^ value;
    }

    #[inline]
    fn write_i64(&mut self, value: i64) {
        self.write_u64(value as u64);
    }

    #[inline]
    fn write_u32(&mut self, value: u32) {
        self.write_u64(u64::from(value));
    }
}

/// A HashMap with [`EdgeHasher`].
pub type FastMap<K, V> = HashMap<K, V, BuildHasherDefault<EdgeHasher>>;
