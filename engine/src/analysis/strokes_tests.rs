use std::f64::consts::{FRAC_PI_2, SQRT_2};

use super::*;
use crate::rng::Rng;

/// `nx x ny` axis-aligned strokes tiling the unit square, along x or along y.
fn tiling(nx: usize, ny: usize, along_y: bool) -> Vec<Stroke> {
    let (w, h) = (1.0 / nx as f64, 1.0 / ny as f64);
    let mut out = Vec::new();
    for j in 0..ny {
        for i in 0..nx {
            let centre = [(i as f64 + 0.5) * w, (j as f64 + 0.5) * h];
            let s = if along_y {
                Stroke::with_angle(centre, FRAC_PI_2, h, w)
            } else {
                Stroke::new(centre, [1.0, 0.0], w, h)
            };
            out.push(s.expect("valid stroke"));
        }
    }
    out
}

/// Counts by testing every pixel against every stroke.
fn brute_counts(strokes: &[Stroke], n: usize) -> Vec<u32> {
    let mut counts = vec![0u32; n * n];
    for j in 0..n {
        for i in 0..n {
            let p = [(i as f64 + 0.5) / n as f64, (j as f64 + 0.5) / n as f64];
            counts[j * n + i] = strokes.iter().filter(|s| s.contains(p)).count() as u32;
        }
    }
    counts
}

/// Largest squared pixel distance from an uncovered pixel to the nearest covered one,
/// by trying every pair.
fn brute_hole_squared(counts: &[u32], n: usize) -> f64 {
    let at = |k: usize| ((k % n) as f64, (k / n) as f64);
    let covered: Vec<(f64, f64)> = (0..n * n).filter(|&k| counts[k] > 0).map(at).collect();
    (0..n * n)
        .filter(|&k| counts[k] == 0)
        .map(|k| {
            let (x, y) = at(k);
            covered
                .iter()
                .map(|(a, b)| (x - a).powi(2) + (y - b).powi(2))
                .fold(f64::INFINITY, f64::min)
        })
        .fold(0.0, f64::max)
}

fn random_strokes(count: usize, seed: u64) -> Vec<Stroke> {
    let mut r = Rng::new(seed, 0);
    (0..count)
        .map(|_| {
            // Centres slightly beyond the square too, so clipping is exercised.
            let centre = [1.2 * r.next_f64() - 0.1, 1.2 * r.next_f64() - 0.1];
            // Every fourth stroke axis-aligned (zero direction components).
            let angle = if r.below(4) == 0 {
                FRAC_PI_2 * r.below(4) as f64
            } else {
                std::f64::consts::TAU * r.next_f64()
            };
            let length = 0.02 + 0.3 * r.next_f64();
            Stroke::with_angle(centre, angle, length, length / 8.0).expect("valid stroke")
        })
        .collect()
}

#[test]
fn tiled_grid_covers_exactly_once_with_no_hole() {
    for along_y in [false, true] {
        // 4 x 32 strokes of 1/4 x 1/32 (8:1); edges fall between pixel centres.
        let strokes = if along_y {
            tiling(32, 4, true)
        } else {
            tiling(4, 32, false)
        };
        let raster = rasterise(&strokes, 256).expect("raster");
        assert!(raster.counts.iter().all(|&c| c == 1), "along_y {along_y}");
        let c = raster.coverage();
        assert_eq!(c.covered_fraction, 1.0);
        assert_eq!(c.mean_overlap, 1.0);
        assert_eq!(c.largest_hole, 0.0);
    }
}

#[test]
fn two_coincident_strokes_overlap_exactly_twice() {
    let s = Stroke::with_angle([0.4, 0.55], 0.7, 0.3, 0.04).expect("valid stroke");
    let one = rasterise(&[s], 512).expect("raster");
    let two = rasterise(&[s, s], 512).expect("raster");
    let c1 = one.coverage();
    let c2 = two.coverage();
    assert_eq!(c2.mean_overlap, 2.0);
    assert_eq!(c1.mean_overlap, 1.0);
    assert_eq!(c2.covered_fraction, c1.covered_fraction);
    assert!(c1.covered_fraction > 0.0);
    assert!(two.counts.iter().all(|&c| c == 0 || c == 2));
}

#[test]
fn empty_set_covers_nothing_and_its_hole_is_unbounded() {
    let c = coverage(&[], 64).expect("coverage");
    assert_eq!(c.covered_fraction, 0.0);
    assert_eq!(c.mean_overlap, 0.0);
    assert_eq!(c.largest_hole, f64::INFINITY);
}

#[test]
fn one_covered_pixel_gives_the_distance_to_the_far_corner() {
    // Pixel (32, 32) of 64 alone: the farthest pixel is (0, 0), 32 sqrt(2) pixels away,
    // so the hole is sqrt(2) / 2 exactly (the border does not count as covered).
    let n = 64;
    let centre = [32.5 / n as f64, 32.5 / n as f64];
    let tiny = 0.5 / n as f64;
    let s = Stroke::new(centre, [1.0, 1.0], tiny, tiny).expect("valid stroke");
    let raster = rasterise(&[s], n).expect("raster");
    assert_eq!(raster.counts.iter().filter(|&&c| c > 0).count(), 1);
    assert_eq!(raster.counts[32 * n + 32], 1);
    let c = raster.coverage();
    assert_eq!(c.covered_fraction, 1.0 / (n * n) as f64);
    assert!(
        (c.largest_hole - SQRT_2 / 2.0).abs() < 1e-15,
        "{}",
        c.largest_hole
    );
}

#[test]
fn a_covered_column_leaves_a_hole_as_wide_as_the_rest() {
    // Column 0 covered on a 40-pixel raster: the farthest pixels are in column 39.
    let n = 40;
    let s =
        Stroke::new([0.5 / n as f64, 0.5], [0.0, 1.0], 1.0, 0.5 / n as f64).expect("valid stroke");
    let c = coverage(&[s], n).expect("coverage");
    assert_eq!(c.covered_fraction, 1.0 / n as f64);
    assert!((c.largest_hole - 39.0 / n as f64).abs() < 1e-15);
}

#[test]
fn rasterise_matches_a_test_of_every_pixel() {
    for seed in 1..=4 {
        let strokes = random_strokes(40, seed);
        for n in [37, 64] {
            let fast = rasterise(&strokes, n).expect("raster");
            assert_eq!(fast.counts, brute_counts(&strokes, n), "seed {seed}, n {n}");
        }
    }
}

#[test]
fn largest_hole_matches_brute_force() {
    for seed in 1..=6 {
        let n = 48;
        // Few strokes (some holes are large) and more (small holes).
        let strokes = random_strokes(3 + 6 * seed as usize, seed);
        let raster = rasterise(&strokes, n).expect("raster");
        let expected = brute_hole_squared(&raster.counts, n).sqrt() / n as f64;
        let got = raster.coverage().largest_hole;
        assert!(
            (got - expected).abs() < 1e-15,
            "seed {seed}: {got} vs {expected}"
        );
        assert!(got > 0.0);
    }
}

#[test]
fn rotated_stroke_area_is_length_times_width_within_raster_error() {
    let n = 1024;
    for angle_deg in [0.0, 17.0, 30.0, 45.0, 71.0, 90.0] {
        let s = Stroke::with_angle([0.5, 0.5], f64::to_radians(angle_deg), 0.4, 0.05)
            .expect("valid stroke");
        let c = coverage(&[s], n).expect("coverage");
        // A pixel whose centre and square are on different sides of an edge lies within
        // half a pixel diagonal of it: the error is at most that band's area.
        let bound = 2.0 * (s.length + s.width) * SQRT_2 / n as f64;
        assert!(
            (c.covered_fraction - s.area()).abs() < bound,
            "{angle_deg} deg: {} vs {}",
            c.covered_fraction,
            s.area()
        );
        assert_eq!(c.mean_overlap, 1.0);
    }
}

#[test]
fn size_variation_is_deterministic_and_in_range() {
    let style = StrokeStyle {
        length: 0.08,
        width: 0.01,
        variation: 0.25,
    };
    let mut r = Rng::new(9, 1);
    let positions: Vec<[f64; 2]> = (0..500).map(|_| [r.next_f64(), r.next_f64()]).collect();
    let directions = vec![[0.0, 2.0]; positions.len()];
    let a = strokes_from_samples(&positions, &directions, &style, 3).expect("strokes");
    let b = strokes_from_samples(&positions, &directions, &style, 3).expect("strokes");
    let other = strokes_from_samples(&positions, &directions, &style, 4).expect("strokes");
    assert_eq!(a, b);
    assert_ne!(a, other);
    // A sample's size depends on its index only, not on the other samples.
    let prefix =
        strokes_from_samples(&positions[..10], &directions[..10], &style, 3).expect("strokes");
    assert_eq!(prefix[..], a[..10]);
    let factors: Vec<f64> = a.iter().map(|s| s.length / style.length).collect();
    assert!(factors.iter().all(|f| (0.75..=1.25).contains(f)));
    assert!(factors.iter().any(|&f| f < 0.8) && factors.iter().any(|&f| f > 1.2));
    let mean = factors.iter().sum::<f64>() / factors.len() as f64;
    assert!((mean - 1.0).abs() < 0.02, "mean factor {mean}");
    for s in &a {
        assert!((s.length / s.width - 8.0).abs() < 1e-12);
        assert_eq!(s.direction, [0.0, 1.0]);
    }
    let fixed = StrokeStyle {
        variation: 0.0,
        ..style
    };
    let same = strokes_from_samples(&positions, &directions, &fixed, 3).expect("strokes");
    assert!(same.iter().all(|s| s.length == 0.08 && s.width == 0.01));
}

#[test]
fn invalid_input_is_a_typed_error() {
    let ok = Stroke::new([0.5, 0.5], [1.0, 0.0], 0.1, 0.01).expect("valid stroke");
    assert_eq!(
        Stroke::new([0.5, 0.5], [0.0, 0.0], 0.1, 0.01),
        Err(StrokeError::BadDirection { index: 0 })
    );
    assert!(matches!(
        Stroke::new([0.5, 0.5], [1.0, 0.0], -0.1, 0.01),
        Err(StrokeError::BadSize { .. })
    ));
    let nan = Stroke {
        centre: [f64::NAN, 0.5],
        ..ok
    };
    assert_eq!(
        rasterise(&[ok, nan], 8),
        Err(StrokeError::NonFiniteCentre { index: 1 })
    );
    let thin = Stroke { width: 0.0, ..ok };
    assert!(matches!(
        rasterise(&[thin], 8),
        Err(StrokeError::BadSize { index: 0, .. })
    ));
    let skew = Stroke {
        direction: [1.0, 1.0],
        ..ok
    };
    assert_eq!(
        coverage(&[skew], 8),
        Err(StrokeError::BadDirection { index: 0 })
    );
    assert_eq!(rasterise(&[ok], 0), Err(StrokeError::BadRaster { size: 0 }));
    assert_eq!(
        rasterise(&[ok], MAX_RASTER + 1),
        Err(StrokeError::BadRaster {
            size: MAX_RASTER + 1
        })
    );
    let style = StrokeStyle {
        length: 0.1,
        width: 0.01,
        variation: 1.0,
    };
    assert!(matches!(
        strokes_from_samples(&[[0.5, 0.5]], &[[1.0, 0.0]], &style, 1),
        Err(StrokeError::BadStyle {
            name: "variation",
            ..
        })
    ));
    let style = StrokeStyle {
        variation: 0.1,
        ..style
    };
    assert_eq!(
        strokes_from_samples(&[[0.5, 0.5]], &[], &style, 1),
        Err(StrokeError::LengthMismatch {
            positions: 1,
            directions: 0
        })
    );
    assert_eq!(
        strokes_from_samples(
            &[[0.5, 0.5], [0.2, 0.2]],
            &[[1.0, 0.0], [0.0, 0.0]],
            &style,
            1
        ),
        Err(StrokeError::BadDirection { index: 1 })
    );
    assert_eq!(
        strokes_from_samples(&[[0.5, f64::INFINITY]], &[[1.0, 0.0]], &style, 1),
        Err(StrokeError::NonFiniteCentre { index: 0 })
    );
}
