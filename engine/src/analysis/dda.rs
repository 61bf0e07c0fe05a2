//! Differential domain analysis (Wei and Wang, "Differential domain analysis for
//! non-uniform sampling", SIGGRAPH 2011; paper section 7.5): the spectrum of a sampling
//! computed from the differences between nearby samples, each measured in the local
//! metric of the sampling, so that adaptive, anisotropic and surface samplings can be
//! compared with the uniform isotropic case.
//!
//! Input: [`Sample`]s (ours or a baseline's; planar or on a mesh). Each sample carries
//! its local frame and expected spacings (`major_axis`, `normal`, `spacing`), which
//! define the metric: the difference `d = x_j - x_i` becomes
//! `d' = (d . m1_i / s1_i, d . m2_i / s2_i)` with `m2 = normal x m1`, i.e. `d` projected
//! into the tangent plane of sample `i` and measured in units of the expected spacing
//! there. A uniform isotropic sampling of unit-area density N then has
//! `d' = sqrt(N) d`, so frequencies are normalised (the nominal frequency is 1).
//!
//! Output: a [`DdaSpectrum`] on a centred grid of normalised frequencies,
//! `P(f) = (1 / N) sum_i sum_j k(|d'_ij|) cos(2 pi f . d'_ij)` (the pair `j = i`
//! included), and its [`RadialProfile`]. With `k = 1` and all pairs this is exactly the
//! periodogram of [`super::spectrum`]; the Gaussian kernel
//! `k(r) = exp(-r^2 / (2 sigma^2))` keeps the analysis local, which smooths the spectrum
//! at frequencies below about `1 / (2 pi sigma)` (where it adds a peak of height about
//! `2 pi sigma^2`) and leaves it unchanged above.
//!
//! **Epsilon.** The paper sets "epsilon = 10 (or 12) and a Gaussian kernel" after Wei
//! and Wang without defining it; we read epsilon as the kernel's support radius in
//! expected spacings: pairs with `|d'| < epsilon` count, with `sigma = epsilon / 3`.
//!
//! On surfaces, neighbours are found in space (not along the surface): pairs whose
//! normals differ by more than [`DdaOptions::min_normal_cos`] are skipped, so that
//! the far side of a thin part does not count; within the kernel's support the
//! projection into the tangent plane is the usual first-order approximation of the
//! surface's exponential map.
//!
//! **Method and cost.** Neighbours are found with a uniform grid in world space; the
//! weighted differences are accumulated into a histogram of bin size
//! `1 / bins_per_spacing` (nearest bin: at normalised frequency f the binning damps the
//! spectrum by `sinc(f / bins_per_spacing)`, under 2% at f = 2.5 with the default 20),
//! and the histogram is Fourier transformed separably. Cost: O(N epsilon^2) for the
//! pairs plus O(B^2 F) for the transform (B = 2 epsilon bins_per_spacing bins per
//! axis, F frequencies per axis). Parallel over fixed chunks of samples whose
//! histograms are summed in order, so results do not depend on the thread count.
//! Measured on 2 cores: 10,000 samples, epsilon 12, about 0.3 s.

use std::collections::HashMap;

use glam::{DVec2, DVec3, Vec3};
use rayon::prelude::*;

use super::spectrum::{RadialProfile, radial_profile};
use crate::sample::Sample;

/// Samples per parallel chunk (fixed for determinism).
const CHUNK: usize = 512;

/// Settings of [`dda`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(default, deny_unknown_fields))]
pub struct DdaOptions {
    /// Kernel support radius in expected spacings (the paper's epsilon, see the module
    /// docs); the Gaussian's sigma is a third of it. Range > 0; default 10.
    pub epsilon: f64,
    /// Largest normalised frequency per axis. Range > 0; default 2.5.
    pub max_frequency: f64,
    /// Frequency grid step (normalised). Range > 0; default 0.05.
    pub frequency_step: f64,
    /// Histogram bins per expected spacing. Range >= 4; default 20.
    pub bins_per_spacing: usize,
    /// Pairs whose normals make a cosine below this are skipped: on a surface, a
    /// neighbour in space across a thin part (the other side of a tube or a sheet) is
    /// not a neighbour on the surface. Range [-1, 1]; default 0.5 (60 degrees); planar
    /// samplings are unaffected.
    pub min_normal_cos: f64,
}

impl Default for DdaOptions {
    fn default() -> Self {
        Self {
            epsilon: 10.0,
            max_frequency: 2.5,
            frequency_step: 0.05,
            bins_per_spacing: 20,
            min_normal_cos: 0.5,
        }
    }
}

/// Errors of [`dda`].
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum DdaError {
    /// No samples at all.
    #[error("differential domain analysis needs at least one sample")]
    Empty,
    /// An option is out of range.
    #[error("DDA option {name} = {value} is out of range")]
    InvalidOption {
        /// The option.
        name: &'static str,
        /// Its value.
        value: f64,
    },
    /// A sample has a non-finite position or a non-positive spacing.
    #[error("sample {index} of set {set} has a non-finite position or a non-positive spacing")]
    BadSample {
        /// Which set.
        set: usize,
        /// Which sample.
        index: usize,
    },
}

impl DdaOptions {
    /// Checks the ranges.
    ///
    /// # Errors
    /// [`DdaError::InvalidOption`] for the first option out of range.
    pub fn validate(&self) -> Result<(), DdaError> {
        let positive = |name, v: f64| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(DdaError::InvalidOption { name, value: v })
            }
        };
        positive("epsilon", self.epsilon)?;
        positive("max_frequency", self.max_frequency)?;
        positive("frequency_step", self.frequency_step)?;
        if !(-1.0..=1.0).contains(&self.min_normal_cos) {
            return Err(DdaError::InvalidOption {
                name: "min_normal_cos",
                value: self.min_normal_cos,
            });
        }
        if self.bins_per_spacing < 4 {
            return Err(DdaError::InvalidOption {
                name: "bins_per_spacing",
                value: self.bins_per_spacing as f64,
            });
        }
        Ok(())
    }
}

/// A differential-domain spectrum on the normalised frequencies
/// `(a, b) * frequency_step`, `|a|, |b| <= half_size`.
#[derive(Clone, Debug, PartialEq)]
pub struct DdaSpectrum {
    /// Largest grid index per axis, `K`.
    pub half_size: usize,
    /// Frequency step (normalised).
    pub frequency_step: f64,
    /// Realizations averaged.
    pub realizations: usize,
    /// Row-major `(2K+1)^2` values, as [`super::spectrum::Spectrum::power`].
    pub power: Vec<f64>,
}

impl DdaSpectrum {
    /// Side of the grid, `2K + 1`.
    pub fn side(&self) -> usize {
        2 * self.half_size + 1
    }

    /// RAPSD and anisotropy per annulus (radius in grid steps, reported as normalised
    /// frequency).
    pub fn radial(&self) -> RadialProfile {
        radial_profile(&self.power, self.half_size, self.frequency_step)
    }
}

/// The mean differential-domain spectrum of one or more sample sets.
///
/// # Errors
/// [`DdaError::Empty`] if there are no samples, [`DdaError::InvalidOption`],
/// [`DdaError::BadSample`].
///
/// # Example
/// ```
/// use strata_engine::analysis::{baseline, dda};
///
/// let sets: Vec<_> = (0..2)
///     .map(|s| baseline::planar_samples(&baseline::uniform_random(500, s), 1.0))
///     .collect();
/// let spectrum = dda::dda(&sets, &dda::DdaOptions::default())?;
/// let radial = spectrum.radial();
/// // White noise stays flat at 1 beyond the kernel's low-frequency bump.
/// let high = radial.rapsd.iter().zip(&radial.frequency)
///     .filter(|(_, f)| **f > 0.5).map(|(p, _)| *p).sum::<f64>()
///     / radial.frequency.iter().filter(|f| **f > 0.5).count() as f64;
/// assert!((high - 1.0).abs() < 0.15);
/// # Ok::<(), strata_engine::analysis::dda::DdaError>(())
/// ```
pub fn dda(sets: &[Vec<Sample>], options: &DdaOptions) -> Result<DdaSpectrum, DdaError> {
    options.validate()?;
    let total: usize = sets.iter().map(Vec::len).sum();
    if total == 0 {
        return Err(DdaError::Empty);
    }
    for (set, samples) in sets.iter().enumerate() {
        if let Some(index) = samples.iter().position(|s| {
            let ok = |v: f32| v.is_finite() && v > 0.0;
            !(Vec3::from(s.position).is_finite() && ok(s.spacing[0]) && ok(s.spacing[1]))
        }) {
            return Err(DdaError::BadSample { set, index });
        }
    }
    let bins_half = (options.epsilon * options.bins_per_spacing as f64).ceil() as usize;
    let side_bins = 2 * bins_half + 1;
    let mut histogram = vec![0.0; side_bins * side_bins];
    for samples in sets {
        let h = differences(samples, options, bins_half);
        histogram.iter_mut().zip(&h).for_each(|(a, b)| *a += b);
    }
    let k = (options.max_frequency / options.frequency_step)
        .round()
        .max(1.0) as usize;
    let power = transform(
        &histogram,
        bins_half,
        1.0 / options.bins_per_spacing as f64,
        k,
        options.frequency_step,
    );
    Ok(DdaSpectrum {
        half_size: k,
        frequency_step: options.frequency_step,
        realizations: sets.len(),
        power: power.into_iter().map(|p| p / total as f64).collect(),
    })
}

/// The kernel-weighted histogram of local differences of one set.
fn differences(samples: &[Sample], options: &DdaOptions, bins_half: usize) -> Vec<f64> {
    let side = 2 * bins_half + 1;
    let eps = options.epsilon;
    let sigma2 = (eps / 3.0).powi(2);
    let bins = options.bins_per_spacing as f64;
    let normals: Vec<DVec3> = samples
        .iter()
        .map(|s| Vec3::from(s.normal).as_dvec3())
        .collect();
    let pos: Vec<DVec3> = samples
        .iter()
        .map(|s| Vec3::from(s.position).as_dvec3())
        .collect();
    // World reach of each sample: epsilon times its larger spacing.
    let reach: Vec<f64> = samples
        .iter()
        .map(|s| eps * s.spacing[0].max(s.spacing[1]) as f64)
        .collect();
    let mut sorted = reach.clone();
    sorted.sort_by(f64::total_cmp);
    let cell = sorted[sorted.len() / 2].max(f64::MIN_POSITIVE);
    let key = |p: DVec3| -> (i64, i64, i64) {
        let q = (p / cell).floor();
        (q.x as i64, q.y as i64, q.z as i64)
    };
    let mut grid: HashMap<(i64, i64, i64), Vec<u32>> = HashMap::new();
    for (i, p) in pos.iter().enumerate() {
        grid.entry(key(*p)).or_default().push(i as u32);
    }
    let partials: Vec<Vec<f64>> = (0..samples.len())
        .collect::<Vec<_>>()
        .par_chunks(CHUNK)
        .map(|chunk| {
            let mut h = vec![0.0; side * side];
            for &i in chunk {
                let s = &samples[i];
                let n = normals[i];
                let m1 = Vec3::from(s.major_axis).as_dvec3();
                let m2 = n.cross(m1).try_normalize().unwrap_or(DVec3::Y);
                let inv = DVec2::new(1.0 / s.spacing[0] as f64, 1.0 / s.spacing[1] as f64);
                let (cx, cy, cz) = key(pos[i]);
                let r = (reach[i] / cell).ceil() as i64;
                for gz in cz - r..=cz + r {
                    for gy in cy - r..=cy + r {
                        for gx in cx - r..=cx + r {
                            let Some(list) = grid.get(&(gx, gy, gz)) else {
                                continue;
                            };
                            for &j in list {
                                if normals[j as usize].dot(n) < options.min_normal_cos {
                                    continue;
                                }
                                let d = pos[j as usize] - pos[i];
                                let q = DVec2::new(d.dot(m1), d.dot(m2)) * inv;
                                let r2 = q.length_squared();
                                if r2 >= eps * eps {
                                    continue;
                                }
                                let w = (-r2 / (2.0 * sigma2)).exp();
                                let bx = (q.x * bins).round() as i64 + bins_half as i64;
                                let by = (q.y * bins).round() as i64 + bins_half as i64;
                                if (0..side as i64).contains(&bx) && (0..side as i64).contains(&by)
                                {
                                    h[by as usize * side + bx as usize] += w;
                                }
                            }
                        }
                    }
                }
            }
            h
        })
        .collect();
    let mut h = vec![0.0; side * side];
    for p in partials {
        h.iter_mut().zip(&p).for_each(|(a, b)| *a += b);
    }
    h
}

/// `sum_bins H(b) cos(2 pi f . c_b)` on the frequency grid, separably: first along x
/// per histogram row, then along y.
fn transform(hist: &[f64], bins_half: usize, bin: f64, k: usize, step: f64) -> Vec<f64> {
    let side_b = 2 * bins_half + 1;
    let side_f = 2 * k + 1;
    let two_pi = 2.0 * std::f64::consts::PI;
    // phase[fi][bi] = (cos, sin) of 2 pi f_fi c_bi.
    let phases: Vec<Vec<(f64, f64)>> = (0..side_f)
        .map(|fi| {
            let f = (fi as f64 - k as f64) * step;
            (0..side_b)
                .map(|bi| {
                    let c = (bi as f64 - bins_half as f64) * bin;
                    let (s, co) = (two_pi * f * c).sin_cos();
                    (co, s)
                })
                .collect()
        })
        .collect();
    // Row transforms: (C, S)[row][fx].
    let rows: Vec<Vec<(f64, f64)>> = hist
        .par_chunks(side_b)
        .map(|row| {
            if row.iter().all(|&v| v == 0.0) {
                return vec![(0.0, 0.0); side_f];
            }
            phases
                .iter()
                .map(|ph| {
                    row.iter()
                        .zip(ph)
                        .fold((0.0, 0.0), |(c, s), (&h, &(co, si))| {
                            (c + h * co, s + h * si)
                        })
                })
                .collect()
        })
        .collect();
    (0..side_f * side_f)
        .into_par_iter()
        .map(|idx| {
            let (fy, fx) = (idx / side_f, idx % side_f);
            rows.iter()
                .zip(&phases[fy])
                .map(|(row, &(co, si))| {
                    let (c, s) = row[fx];
                    c * co - s * si
                })
                .sum()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::baseline;
    use crate::analysis::spectrum::periodogram;

    fn mean_over(r: &RadialProfile, from: f64, to: f64) -> f64 {
        let v: Vec<f64> = r
            .frequency
            .iter()
            .zip(&r.rapsd)
            .filter(|(f, _)| **f >= from && **f < to)
            .map(|(_, p)| *p)
            .collect();
        v.iter().sum::<f64>() / v.len() as f64
    }

    /// DDA of a uniform jittered set matches its plain periodogram above the kernel's
    /// low-frequency bump.
    #[test]
    fn uniform_jittered_dda_matches_the_periodogram() {
        let n = 1024;
        let points: Vec<Vec<DVec2>> = (0..6).map(|s| baseline::jittered_grid(n, s)).collect();
        let plain = periodogram(&points, 2.5).expect("periodogram").radial();
        let samples: Vec<Vec<Sample>> = points
            .iter()
            .map(|p| baseline::planar_samples(p, 1.0))
            .collect();
        let options = DdaOptions {
            frequency_step: 1.0 / 32.0,
            ..Default::default()
        };
        let d = dda(&samples, &options).expect("dda").radial();
        for (from, to) in [(0.3, 0.7), (0.7, 1.1), (1.1, 1.5), (1.5, 2.5)] {
            let (a, b) = (mean_over(&plain, from, to), mean_over(&d, from, to));
            assert!(
                (a - b).abs() < 0.06 + 0.1 * a,
                "band {from}..{to}: periodogram {a}, DDA {b}"
            );
        }
    }

    /// Stretching a set and telling DDA the stretched spacings gives back the spectrum
    /// of the unstretched set (the metric is undone).
    #[test]
    fn anisotropic_metric_is_undone() {
        let n = 900;
        let iso: Vec<Vec<Sample>> = (0..3)
            .map(|s| baseline::planar_samples(&baseline::jittered_grid(n, s), 1.0))
            .collect();
        let stretched: Vec<Vec<Sample>> = iso
            .iter()
            .map(|set| {
                set.iter()
                    .map(|s| {
                        let mut t = *s;
                        t.position[0] *= 4.0;
                        t.spacing[0] *= 4.0;
                        t
                    })
                    .collect()
            })
            .collect();
        let o = DdaOptions::default();
        let a = dda(&iso, &o).expect("dda");
        let b = dda(&stretched, &o).expect("dda");
        for (x, y) in a.power.iter().zip(&b.power) {
            assert!((x - y).abs() < 1e-6 * (1.0 + x.abs()), "{x} vs {y}");
        }
    }

    #[test]
    fn deterministic_and_checked() {
        let set = baseline::planar_samples(&baseline::uniform_random(700, 2), 1.0);
        let o = DdaOptions::default();
        let one = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .expect("pool")
            .install(|| dda(std::slice::from_ref(&set), &o).expect("dda"));
        assert_eq!(one, dda(std::slice::from_ref(&set), &o).expect("dda"));
        assert_eq!(dda(&[], &o), Err(DdaError::Empty));
        let mut bad = set;
        bad[3].spacing[1] = 0.0;
        assert!(matches!(
            dda(&[bad], &o),
            Err(DdaError::BadSample { set: 0, index: 3 })
        ));
        let o = DdaOptions {
            epsilon: -1.0,
            ..Default::default()
        };
        assert!(o.validate().is_err());
    }
}
