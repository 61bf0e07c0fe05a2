//! Stable keys of settings, for caches that must know whether a result is still valid
//! (the ECS keeps a segment's parameterization while its content key is unchanged).
//!
//! A key is built field by field from the settings a stage reads, with the crate's
//! fixed mixing function ([`crate::rng::keyed_hash`]): the same settings give the same
//! key in every run, build and Rust version. `Debug` text would change with a derive
//! or a formatting change, and `DefaultHasher`'s algorithm is unspecified. Each key
//! destructures its structs without `..`, so a new setting does not compile until it
//! is either hashed or named as not read.

use crate::param::ParamOptions;
use crate::rng::{keyed_hash, stream_key};
use crate::segment::SegmentOptions;

use super::{AngleCriterion, SurfaceOptions};

/// Folds 64-bit words into a key, in order.
///
/// ```
/// use strata_engine::surface::KeyBuilder;
/// let a = KeyBuilder::new(1).word(2).float(0.5).finish();
/// assert_eq!(a, KeyBuilder::new(1).word(2).float(0.5).finish());
/// assert_ne!(a, KeyBuilder::new(1).float(0.5).word(2).finish());
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct KeyBuilder {
    state: u64,
    words: u64,
}

impl KeyBuilder {
    /// Starts a key in `domain` (keys of different domains differ for the same words).
    pub fn new(domain: u64) -> Self {
        Self {
            state: stream_key(domain, 0x6b65_7973),
            words: 0,
        }
    }

    /// Adds a word.
    #[must_use]
    pub fn word(self, w: u64) -> Self {
        Self {
            state: keyed_hash(self.state ^ w, self.words),
            words: self.words + 1,
        }
    }

    /// Adds a number by its bits, with `-0.0` as `0.0` (equal settings, equal keys).
    #[must_use]
    pub fn float(self, x: f64) -> Self {
        self.word(if x == 0.0 { 0 } else { x.to_bits() })
    }

    /// The key: the words and their count.
    pub fn finish(self) -> u64 {
        keyed_hash(self.state, self.words)
    }
}

/// Domain of [`SurfaceOptions::parameterization_key`].
const PARAMETERIZATION: u64 = 1;

impl SurfaceOptions {
    /// A stable key of the settings that a segment's parameterization with splitting
    /// ([`parameterize_segment_with_splitting`](super::parameterize_segment_with_splitting)
    /// and its [`SplitContext`](super::SplitContext)) reads: the parameterization
    /// settings, `min_segment_faces`, `angle_criterion`, `merge_pieces` and the walk's `sigma`. Settings
    /// it does not read (seeding, cells, isotropic charts) do not change the key.
    ///
    /// ```
    /// use strata_engine::surface::SurfaceOptions;
    /// let a = SurfaceOptions::default();
    /// let mut b = a;
    /// b.segment.seed += 1; // seeding only
    /// assert_eq!(a.parameterization_key(), b.parameterization_key());
    /// b.param.gamma *= 0.5;
    /// assert_ne!(a.parameterization_key(), b.parameterization_key());
    /// ```
    pub fn parameterization_key(&self) -> u64 {
        let Self {
            segment,
            param,
            curve: _,
            min_segment_faces,
            angle_criterion,
            isotropy_threshold: _,
            chart_angle: _,
            merge_pieces,
        } = self;
        let SegmentOptions {
            beta: _,
            sigma,
            seed: _,
        } = segment;
        let ParamOptions {
            gamma,
            isotropy_threshold,
            max_stretch,
        } = param;
        let criterion = match angle_criterion {
            AngleCriterion::Mean => 0,
            AngleCriterion::Max => 1,
        };
        KeyBuilder::new(PARAMETERIZATION)
            .float(*gamma)
            .float(*isotropy_threshold)
            .float(*max_stretch)
            .word(*min_segment_faces as u64)
            .word(criterion)
            .word(u64::from(*merge_pieces))
            .float(*sigma)
            .finish()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_setting_read_changes_the_key_and_no_other_does() {
        let base = SurfaceOptions::default();
        let key = base.parameterization_key();
        let read: [fn(&mut SurfaceOptions); 7] = [
            |o| o.merge_pieces = !o.merge_pieces,
            |o| o.param.gamma *= 0.5,
            |o| o.param.isotropy_threshold += 0.01,
            |o| o.param.max_stretch += 0.1,
            |o| o.min_segment_faces += 1,
            |o| o.angle_criterion = AngleCriterion::Max,
            |o| o.segment.sigma *= 2.0,
        ];
        let mut keys = vec![key];
        for change in read {
            let mut o = base;
            change(&mut o);
            keys.push(o.parameterization_key());
        }
        let mut distinct = keys.clone();
        distinct.sort_unstable();
        distinct.dedup();
        assert_eq!(distinct.len(), keys.len(), "{keys:x?}");
        let unread: [fn(&mut SurfaceOptions); 5] = [
            |o| o.segment.beta *= 0.5,
            |o| o.segment.seed += 1,
            |o| o.curve.max_cell_share *= 0.5,
            |o| o.isotropy_threshold += 0.1,
            |o| o.chart_angle *= 0.5,
        ];
        for change in unread {
            let mut o = base;
            change(&mut o);
            assert_ne!(o, base);
            assert_eq!(o.parameterization_key(), key);
        }
    }

    #[test]
    fn keys_are_stable_across_builds() {
        // A fixed value: a change to the mixing or to the words hashed shows here (and
        // would invalidate keys that a host stored).
        let key = KeyBuilder::new(7).word(1).float(0.25).finish();
        assert_eq!(key, 0x408b_0000_72ba_2d7e, "{key:#x}");
        assert_eq!(
            KeyBuilder::new(7).float(0.0).finish(),
            KeyBuilder::new(7).float(-0.0).finish()
        );
        assert_ne!(
            KeyBuilder::new(7).word(1).finish(),
            KeyBuilder::new(8).word(1).finish()
        );
        // Word count is part of the key: a trailing zero word is not nothing.
        assert_ne!(
            KeyBuilder::new(7).finish(),
            KeyBuilder::new(7).word(0).finish()
        );
    }
}
