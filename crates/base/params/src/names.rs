//! The hash maps keyed by parameter name, with a fast hasher.
//!
//! A model's build looks names up thousands of times (every symbol of every expression,
//! every unit and domain), and with the standard library's SipHash the hashing alone was
//! about 3 % of a whole `pendkit modes quad`. SipHash resists collision attacks from
//! untrusted keys; the names here come from the user's own model and case files, which
//! can slow their own run down at most, so the simpler FxHash (the hasher of `rustc`)
//! serves. No map here is iterated, so the hasher changes no output.

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

/// A map keyed by parameter name (any key, hashed with [`FxHasher`]).
pub(crate) type NameMap<K, V> = HashMap<K, V, BuildHasherDefault<FxHasher>>;

/// FxHash: each 8-byte word is folded in by a rotation, an xor and one multiplication.
#[derive(Default, Clone, Copy)]
pub(crate) struct FxHasher {
    hash: u64,
}

/// The multiplier of FxHash (from Firefox and `rustc`).
const SEED: u64 = 0x51_7c_c1_b7_27_22_0a_95;

impl FxHasher {
    fn add(&mut self, word: u64) {
        self.hash = (self.hash.rotate_left(5) ^ word).wrapping_mul(SEED);
    }
}

impl Hasher for FxHasher {
    fn write(&mut self, bytes: &[u8]) {
        let mut words = bytes.chunks_exact(8);
        for word in &mut words {
            let mut b = [0u8; 8];
            b.copy_from_slice(word);
            self.add(u64::from_le_bytes(b));
        }
        let rest = words.remainder();
        if !rest.is_empty() {
            let mut b = [0u8; 8];
            b[..rest.len()].copy_from_slice(rest);
            self.add(u64::from_le_bytes(b));
        }
        // the length, so that trailing zero bytes are not lost in the padding above
        self.add(bytes.len() as u64);
    }

    fn write_u8(&mut self, i: u8) {
        self.add(u64::from(i));
    }

    fn write_usize(&mut self, i: usize) {
        self.add(i as u64);
    }

    fn finish(&self) -> u64 {
        self.hash
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::hash::BuildHasher;

    /// Names that differ only in their last bytes, or in length, hash apart.
    #[test]
    fn close_names_hash_apart() {
        let build = BuildHasherDefault::<FxHasher>::default();
        let names = [
            "m",
            "m1",
            "m2",
            "m12345678",
            "m12345679",
            "steel_C",
            "steel_C\0",
        ];
        let hashes: Vec<u64> = names.iter().map(|n| build.hash_one(n)).collect();
        for (i, a) in hashes.iter().enumerate() {
            for b in &hashes[i + 1..] {
                assert_ne!(a, b);
            }
        }
    }
}
