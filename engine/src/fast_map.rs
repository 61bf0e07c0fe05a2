//! The hash map of the engine's integer-keyed maps on hot paths (see [`FastMap`]).
//!
//! Input: small fixed-size integer keys (position bits, vertex triples and pairs, face
//! indices). Output: a `HashMap` hashing them with `rustc-hash`'s multiply-add hasher.
//! Cost: a multiply and an add per 8-byte word, against std's SipHash, whose guard
//! against hash flooding cannot change what these maps return, only how fast (it cost
//! more than the lookups in mesh construction, a parameterization's validity test and
//! segment merging).

/// A `HashMap` with `rustc-hash`'s hasher. Only for maps whose results do not depend
/// on their iteration order.
pub(crate) type FastMap<K, V> = rustc_hash::FxHashMap<K, V>;

/// An empty [`FastMap`] with room for `capacity` entries.
pub(crate) fn fast_map<K, V>(capacity: usize) -> FastMap<K, V> {
    FastMap::with_capacity_and_hasher(capacity, rustc_hash::FxBuildHasher)
}
