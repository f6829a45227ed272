//! A fast hasher for the walk's edge keys (u64), so that no hashing crate is needed: std's
//! SipHash costs several times more. Each table draws its own odd multiplier from std's random
//! keys, so a file cannot be crafted offline to put its edges in one bucket (a slow decode).

use std::collections::hash_map::RandomState;
use std::collections::HashMap;
use std::hash::{BuildHasher, Hasher};

/// Multiplies the key by the table's odd multiplier and folds the high half into the low one,
/// so the bucket (low bits) and hashbrown's tag (high bits) both depend on every bit of the key.
#[derive(Clone, Copy)]
pub struct EdgeHasher {
    state: u64,
    multiplier: u64,
}

impl Hasher for EdgeHasher {
    #[inline]
    fn finish(&self) -> u64 {
        let h = self.state.wrapping_mul(self.multiplier);
        h ^ (h >> 32)
    }

    #[inline]
    fn write(&mut self, bytes: &[u8]) {
        for byte in bytes {
            self.state =
                (self.state.rotate_left(8) ^ u64::from(*byte)).wrapping_mul(0x100_0000_01B3);
        }
    }

    #[inline]
    fn write_u64(&mut self, value: u64) {
        self.state = self.state.rotate_left(23) ^ value;
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

/// Makes the [`EdgeHasher`]s of one table, all with the multiplier drawn for it.
#[derive(Clone, Copy)]
pub struct EdgeHashing {
    multiplier: u64,
}

impl Default for EdgeHashing {
    fn default() -> Self {
        let random = RandomState::new().hash_one(0x9E37_79B9_7F4A_7C15_u64);
        // odd, and with high bits set, as a multiplicative hash wants
        EdgeHashing {
            multiplier: random | 0x8000_0000_0000_0001,
        }
    }
}

impl BuildHasher for EdgeHashing {
    type Hasher = EdgeHasher;

    #[inline]
    fn build_hasher(&self) -> EdgeHasher {
        EdgeHasher {
            state: 0,
            multiplier: self.multiplier,
        }
    }
}

/// A HashMap with [`EdgeHasher`].
pub type FastMap<K, V> = HashMap<K, V, EdgeHashing>;
