//! Counter-based random numbers.
//!
//! strata's samples must be identical for the same seed whatever the thread count, so
//! random values are a pure function of `(seed, stream, counter)` rather than the state
//! of a generator shared between threads: any chunk of work can compute its own values
//! without knowing how the work was split. The mixer is SplitMix64's finaliser
//! (Steele, Lea and Flood 2014), which passes BigCrush as a counter-based generator;
//! it is a few lines, so no crate is pulled in for it.

/// SplitMix64's 64-bit finaliser: a bijective mix with full avalanche.
#[inline]
pub fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

const GOLDEN: u64 = 0x9e37_79b9_7f4a_7c15;

/// A random `u64` for `(seed, stream, counter)`.
#[inline]
pub fn hash3(seed: u64, stream: u64, counter: u64) -> u64 {
    keyed_hash(stream_key(seed, stream), counter)
}

/// The part of [`hash3`] that depends only on `(seed, stream)`: a loop over counters
/// of one stream computes it once and calls [`keyed_hash`].
#[inline]
pub fn stream_key(seed: u64, stream: u64) -> u64 {
    mix64(seed ^ stream.wrapping_mul(GOLDEN))
}

/// `hash3(seed, stream, counter)` from `key = stream_key(seed, stream)`.
#[inline]
pub fn keyed_hash(key: u64, counter: u64) -> u64 {
    mix64(key.wrapping_add(counter.wrapping_mul(GOLDEN)))
}

/// Converts 53 random bits to a uniform `f64` in `[0, 1)`.
#[inline]
pub fn unit_f64(bits: u64) -> f64 {
    (bits >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

/// A uniform value in `[0, 1)` for `(seed, stream, counter)`.
#[inline]
pub fn uniform(seed: u64, stream: u64, counter: u64) -> f64 {
    unit_f64(hash3(seed, stream, counter))
}

/// A small sequential generator over the same mixer, for code that draws values one
/// after another (baselines, seed placement). Deterministic for a seed and stream.
#[derive(Clone, Debug)]
pub struct Rng {
    seed: u64,
    stream: u64,
    counter: u64,
}

impl Rng {
    /// A generator for `seed` and `stream` (use distinct streams for independent uses).
    pub fn new(seed: u64, stream: u64) -> Self {
        Self {
            seed,
            stream,
            counter: 0,
        }
    }

    /// Next random `u64`.
    #[inline]
    pub fn next_u64(&mut self) -> u64 {
        let v = hash3(self.seed, self.stream, self.counter);
        self.counter += 1;
        v
    }

    /// Next uniform value in `[0, 1)`.
    #[inline]
    pub fn next_f64(&mut self) -> f64 {
        unit_f64(self.next_u64())
    }

    /// A uniform integer in `0..n` (`n > 0`), by Lemire's multiply-shift (bias below 2^-32
    /// for n below 2^32).
    #[inline]
    pub fn below(&mut self, n: u64) -> u64 {
        ((self.next_u64() as u128 * n as u128) >> 64) as u64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniform_is_in_range_and_balanced() {
        let n = 100_000;
        let mut sum = 0.0;
        let mut below_quarter = 0;
        for i in 0..n {
            let u = uniform(7, 1, i);
            assert!((0.0..1.0).contains(&u));
            sum += u;
            below_quarter += (u < 0.25) as u32;
        }
        let mean = sum / n as f64;
        assert!((mean - 0.5).abs() < 0.005, "mean {mean}");
        assert!((below_quarter as f64 / n as f64 - 0.25).abs() < 0.005);
    }

    #[test]
    fn streams_and_seeds_differ() {
        assert_ne!(hash3(1, 0, 0), hash3(2, 0, 0));
        assert_ne!(hash3(1, 0, 0), hash3(1, 1, 0));
        assert_ne!(hash3(1, 0, 0), hash3(1, 0, 1));
        assert_eq!(hash3(1, 2, 3), hash3(1, 2, 3));
    }

    #[test]
    fn below_covers_range() {
        let mut r = Rng::new(3, 0);
        let mut hits = [0u32; 7];
        for _ in 0..70_000 {
            hits[r.below(7) as usize] += 1;
        }
        assert!(
            hits.iter().all(|&h| (9_000..11_000).contains(&h)),
            "{hits:?}"
        );
    }
}
