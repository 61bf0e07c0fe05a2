//! The CPU's feature level, for hot loops compiled a second time with
//! `#[target_feature]`: one list of features per [`Level`], checked at run time as a
//! whole, so a clone never runs on a CPU that lacks one of the features it enables.
//!
//! Input: nothing (the running CPU). Output: a [`Level`]. Cost: one cached load per
//! feature (the standard library detects them once per process and keeps the result).
//!
//! The idiom, for a body `f_body` marked `#[inline(always)]` (so that each caller's
//! features apply to all of it) and a clone compiled for a level:
//!
//! ```ignore
//! fn f(&self, x: &mut [f64]) {
//!     #[cfg(target_arch = "x86_64")]
//!     if Level::detected() >= Level::Avx2 {
//!         // SAFETY: the CPU has every feature of `Level::Avx2`, which is what
//!         // `f_avx2` enables.
//!         #[allow(unsafe_code)]
//!         unsafe {
//!             self.f_avx2(x);
//!         }
//!         return;
//!     }
//!     self.f_body(x);
//! }
//!
//! #[cfg(target_arch = "x86_64")]
//! #[target_feature(enable = "avx,avx2")] // exactly `Level::Avx2.features()`
//! fn f_avx2(&self, x: &mut [f64]) {
//!     self.f_body(x);
//! }
//! ```
//!
//! A clone's `enable` string must be one level's [`features`](Level::features), joined
//! with commas; a test of this module reads every source file of the crate and fails on
//! any other. Clones keep the portable body's bits as long as no feature changes
//! rounding: FMA is enabled for [`Level::V3`], and code compiled for it must not call
//! `mul_add` (Rust never fuses a multiply and an add by itself).
//!
//! Hand-written rather than the `multiversion` crate: the clones here are methods (one
//! generic over the record type) whose bodies follow the inlining contract of
//! `curve/mod.rs`, the dispatch is the few lines above, and this module adds no
//! dependency; what it adds over `is_x86_feature_detected!` calls at each site is one
//! list per level that the check and the clones share.

/// A set of optional x86-64 features that hot loops are compiled for. Ordered: each
/// level holds every feature of the levels below it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub(crate) enum Level {
    /// No optional feature (or not x86-64): run the portable body.
    Portable,
    /// AVX and AVX2: 256-bit vectors, nothing fused.
    Avx2,
    /// The x86-64-v3 features the sampler's loop uses: AVX2, FMA, BMI1, BMI2, LZCNT and
    /// POPCNT (three-operand encodings and bit instructions).
    V3,
}

impl Level {
    /// The features a clone for this level enables, in the order of its `enable` list.
    pub(crate) const fn features(self) -> &'static [&'static str] {
        match self {
            Level::Portable => &[],
            Level::Avx2 => &["avx", "avx2"],
            Level::V3 => &["avx", "avx2", "fma", "bmi1", "bmi2", "lzcnt", "popcnt"],
        }
    }

    /// The highest level whose every feature the running CPU has.
    pub(crate) fn detected() -> Level {
        [Level::V3, Level::Avx2]
            .into_iter()
            .find(|level| level.features().iter().all(|f| has(f)))
            .unwrap_or(Level::Portable)
    }
}

/// Whether the running CPU has feature `name` (a name of [`Level::features`]; any other
/// name is `false`, so a misspelt feature never enables a clone).
fn has(name: &str) -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::is_x86_feature_detected as detected;
        match name {
            "avx" => detected!("avx"),
            "avx2" => detected!("avx2"),
            "fma" => detected!("fma"),
            "bmi1" => detected!("bmi1"),
            "bmi2" => detected!("bmi2"),
            "lzcnt" => detected!("lzcnt"),
            "popcnt" => detected!("popcnt"),
            _ => false,
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        let _ = name;
        false
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn levels_nest_and_every_feature_is_checked() {
        assert!(Level::Portable < Level::Avx2 && Level::Avx2 < Level::V3);
        for pair in [Level::Portable, Level::Avx2, Level::V3].windows(2) {
            let (low, high) = (pair[0].features(), pair[1].features());
            assert!(low.iter().all(|f| high.contains(f)), "{pair:?}");
        }
        assert!(!has("avx512f"), "only the features of a level are known");
        let level = Level::detected();
        assert!(level.features().iter().all(|f| has(f)));
        // On x86-64 every feature name is one `has` knows: a CPU with all of them
        // detects as V3 (the check itself cannot be run without such a CPU).
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
        {
            assert!(level >= Level::Avx2);
        }
    }

    /// Every `target_feature` attribute of the crate enables exactly one level's
    /// features, so the run-time check of that level covers all of them.
    #[test]
    fn every_clone_enables_exactly_a_level_s_features() {
        let known: Vec<String> = [Level::Avx2, Level::V3]
            .iter()
            .map(|l| l.features().join(","))
            .collect();
        let src = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
        let mut stack = vec![src];
        let (mut seen, mut wrong) = (0, Vec::new());
        while let Some(dir) = stack.pop() {
            for entry in std::fs::read_dir(&dir).expect("readable source folder") {
                let path = entry.expect("directory entry").path();
                if path.is_dir() {
                    stack.push(path);
                    continue;
                }
                let text = std::fs::read_to_string(&path).unwrap_or_default();
                let pattern = concat!("#[target_", "feature(enable = \"");
                for (i, _) in text.match_indices(pattern) {
                    let rest = &text[i + pattern.len()..];
                    let features = &rest[..rest.find('"').unwrap_or(0)];
                    seen += 1;
                    if !known.iter().any(|k| k == features) {
                        wrong.push(format!("{}: {features}", path.display()));
                    }
                }
            }
        }
        assert!(seen > 0, "the scan found no clone");
        assert!(
            wrong.is_empty(),
            "clones enabling features that no level checks: {wrong:?}"
        );
    }
}
