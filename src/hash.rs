//! 64-bit FNV-1a: a hash that stays the same across Rust releases and machines, for file
//! names, checksums and the fingerprints of render parts (not for security: where it
//! matters, what was hashed is compared in full).

/// The FNV-1a hash of `bytes`.
pub(crate) fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3)
    })
}
