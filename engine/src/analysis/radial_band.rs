//! A radial profile over a band of frequencies, compared with a reference profile:
//! how section 7.5 of the paper (Quinn et al., "Generalized Anisotropic Stratified
//! Surface Sampling") judges whether a density-controlled, anisotropic or surface
//! sampling's differential domain spectrum is consistent with the uniform one.
//!
//! Input: two [`RadialProfile`]s (from [`spectrum`](super::spectrum) or
//! [`dda`](super::dda)) on the same frequencies, and the band. Output: a
//! [`BandSummary`] of plain numbers. Cost: O(annuli).

use super::spectrum::RadialProfile;

/// One annulus of a profile: `(frequency, rapsd, anisotropy_db)`.
pub type Annulus = (f64, f64, f64);

/// The annuli of `profile` with `from <= frequency <= to`, in order.
pub fn band(profile: &RadialProfile, from: f64, to: f64) -> Vec<Annulus> {
    profile
        .frequency
        .iter()
        .zip(&profile.rapsd)
        .zip(&profile.anisotropy_db)
        .filter(|((f, _), _)| **f >= from && **f <= to)
        .map(|((f, p), a)| (*f, *p, *a))
        .collect()
}

/// A profile's band statistics against a reference (see [`BandSummary::measure`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BandSummary {
    /// Root mean square difference of the RAPSD from the reference's over the band
    /// (power; white noise is 1).
    pub rms_vs_reference: f64,
    /// Mean anisotropy over the band (dB).
    pub mean_anisotropy_db: f64,
    /// Mean RAPSD over `from <= frequency < low_below` (0 if no annulus is there).
    pub low: f64,
    /// Largest RAPSD in the band (the first, if tied; `-inf` for an empty band).
    pub peak: f64,
    /// Frequency of [`peak`](Self::peak) (0 for an empty band).
    pub peak_frequency: f64,
}

impl BandSummary {
    /// Statistics of `profile` over `from <= frequency <= to` against `reference`
    /// (annuli paired in order, so both should come from the same frequencies; the
    /// RMS divides by the profile's annuli in the band), and its mean RAPSD over the
    /// low end `from <= frequency < low_below`. Section 7.5 uses the band 0.2 to 2.5
    /// (beyond the kernel's low-frequency bump) and `low_below` 0.5. An empty band gives
    /// NaN for the RMS and the anisotropy.
    ///
    /// # Example
    /// ```
    /// use strata_engine::analysis::radial_band::BandSummary;
    /// use strata_engine::analysis::spectrum::RadialProfile;
    /// let flat = RadialProfile {
    ///     frequency: vec![0.1, 0.3, 1.0, 3.0],
    ///     rapsd: vec![1.0; 4],
    ///     anisotropy_db: vec![-10.0; 4],
    /// };
    /// let s = BandSummary::measure(&flat, &flat, 0.2, 2.5, 0.5);
    /// assert_eq!((s.rms_vs_reference, s.mean_anisotropy_db, s.low), (0.0, -10.0, 1.0));
    /// ```
    pub fn measure(
        profile: &RadialProfile,
        reference: &RadialProfile,
        from: f64,
        to: f64,
        low_below: f64,
    ) -> Self {
        let b = band(profile, from, to);
        let ref_band = band(reference, from, to);
        let rms_vs_reference = (b
            .iter()
            .zip(&ref_band)
            .map(|(x, y)| (x.1 - y.1).powi(2))
            .sum::<f64>()
            / b.len() as f64)
            .sqrt();
        let mean_anisotropy_db = b.iter().map(|x| x.2).sum::<f64>() / b.len() as f64;
        let in_low = |f: &f64| *f >= from && *f < low_below;
        let low = profile
            .frequency
            .iter()
            .zip(&profile.rapsd)
            .filter(|(f, _)| in_low(f))
            .map(|(_, p)| *p)
            .sum::<f64>()
            / profile
                .frequency
                .iter()
                .filter(|f| in_low(f))
                .count()
                .max(1) as f64;
        let mut best = (0.0, f64::NEG_INFINITY);
        for x in &b {
            if x.1 > best.1 {
                best = (x.0, x.1);
            }
        }
        Self {
            rms_vs_reference,
            mean_anisotropy_db,
            low,
            peak: best.1,
            peak_frequency: best.0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn profile(rapsd: &[f64], anisotropy_db: &[f64]) -> RadialProfile {
        RadialProfile {
            frequency: vec![0.1, 0.2, 0.4, 1.0, 2.5, 3.0],
            rapsd: rapsd.to_vec(),
            anisotropy_db: anisotropy_db.to_vec(),
        }
    }

    #[test]
    fn band_keeps_closed_range_in_order() {
        let p = profile(&[9.0, 1.0, 2.0, 3.0, 4.0, 9.0], &[0.0; 6]);
        let b = band(&p, 0.2, 2.5);
        let f: Vec<f64> = b.iter().map(|a| a.0).collect();
        assert_eq!(f, vec![0.2, 0.4, 1.0, 2.5]);
        assert_eq!(b[2], (1.0, 3.0, 0.0));
        assert!(band(&p, 5.0, 6.0).is_empty());
    }

    #[test]
    fn known_answers() {
        // In the band 0.2..=2.5: rapsd 1, 0.5, 2, 1 against 1, 1, 1, 1.
        let p = profile(
            &[9.0, 1.0, 0.5, 2.0, 1.0, 9.0],
            &[50.0, -4.0, -8.0, -6.0, -2.0, 50.0],
        );
        let r = profile(&[0.0, 1.0, 1.0, 1.0, 1.0, 0.0], &[0.0; 6]);
        let s = BandSummary::measure(&p, &r, 0.2, 2.5, 0.5);
        // (0 + 0.25 + 1 + 0) / 4 = 0.3125.
        assert!((s.rms_vs_reference - 0.3125f64.sqrt()).abs() < 1e-15);
        assert_eq!(s.mean_anisotropy_db, -5.0);
        // f = 0.2 and 0.4 are in [0.2, 0.5): (1 + 0.5) / 2; f = 0.1 is not.
        assert_eq!(s.low, 0.75);
        // The peak is searched in the band only (9 at f = 3 is outside).
        assert_eq!((s.peak, s.peak_frequency), (2.0, 1.0));
    }

    #[test]
    fn first_of_tied_peaks_and_empty_low() {
        let p = profile(&[0.0, 3.0, 1.0, 3.0, 1.0, 0.0], &[0.0; 6]);
        let s = BandSummary::measure(&p, &p, 0.2, 2.5, 0.2);
        assert_eq!((s.peak, s.peak_frequency), (3.0, 0.2));
        assert_eq!(s.rms_vs_reference, 0.0);
        assert_eq!(s.low, 0.0);
    }

    #[test]
    fn empty_band() {
        let p = profile(&[1.0; 6], &[0.0; 6]);
        let s = BandSummary::measure(&p, &p, 10.0, 20.0, 15.0);
        assert!(s.rms_vs_reference.is_nan() && s.mean_anisotropy_db.is_nan());
        assert_eq!((s.peak, s.peak_frequency), (f64::NEG_INFINITY, 0.0));
    }
}
