//! A point budget for level of detail (issue 19): the base count under which a view
//! shows about a given number of samples.
//!
//! With base count `N`, rank `k` is visible when `k < N lod(p_k)`
//! ([`lod`](super::lod)). The sequence spreads every run of ranks over the surface by
//! one measure `rho` (the curves' measure, stratified at every prefix), so the visible
//! count is, up to that stratification's error, `N E_rho[lod]`: linear in `N`. The
//! mean multiplier is estimated on the first [`PROBES`] ranks of the sequence (one in
//! each `1 / PROBES` of the measure), whose positions and normals are kept, so that a
//! view costs one multiplier per probe: 75-85 us for the 4096 on the test machine, with
//! the probes out of cache as they are between frames (the `lod` bench); the last
//! view's estimate is kept, so a still camera costs nothing. The base count that
//! shows `S` samples is then `S / E_rho[lod]`.
//!
//! A renderer with a point budget (as point-cloud renderers bound the points they draw)
//! sets the base count of every frame this way, so that the shown count stays at its
//! budget while the camera moves: a dolly in then refines near the camera and thins
//! elsewhere instead of showing ever more samples. On the bunny's `lod` bench paths
//! the estimate is within 1% of the count (bench/README.md).

use glam::DVec3;

use super::faces::position_normal;
use super::lod::{LodError, ViewLod, check_deformation};
use super::{SampleSite, Sampler};
use crate::mesh::TriMesh;

/// Probes of the mean multiplier: the first this many ranks of the sequence. On the
/// bunny's `lod` bench paths, 4096 estimate the shown count within 1% (1024: within
/// 4.5%, 16384: within 0.3%).
pub const PROBES: usize = 4096;

/// The estimator of a point budget: see the module docs.
#[derive(Clone, Debug)]
pub struct ShownEstimate {
    /// The probes' sites (ranks `0..PROBES`).
    sites: Vec<SampleSite>,
    /// Their positions and unit normals on the current geometry.
    points: Vec<(DVec3, DVec3)>,
    /// The last view [`base_for`](Self::base_for) estimated, and its mean multiplier: a
    /// camera that has not moved costs nothing.
    last: Option<(ViewLod, f64)>,
}

impl ShownEstimate {
    /// The estimator of `sampler`'s progressive sequence for `seed`, on the sampler's
    /// mesh. Cost: [`PROBES`] progressive sites.
    pub fn new(sampler: &Sampler, seed: u64) -> Self {
        let mut sites = vec![SampleSite::default(); PROBES];
        sampler.progressive_sites_into(seed, 0, &mut sites);
        let points = Self::place(&sites, sampler.mesh());
        Self {
            sites,
            points,
            last: None,
        }
    }

    fn place(sites: &[SampleSite], mesh: &TriMesh) -> Vec<(DVec3, DVec3)> {
        sites
            .iter()
            .map(|s| position_normal(mesh, s.face, s.barycentric().map(f64::from)))
            .collect()
    }

    /// Moves the probes onto `mesh`, a deformation of the sampler's mesh (the same
    /// vertices and triangles): an error, and nothing changed, when it has others.
    pub fn set_geometry(&mut self, sampler: &Sampler, mesh: &TriMesh) -> Result<(), LodError> {
        check_deformation(sampler.mesh(), mesh)?;
        self.move_to(mesh);
        Ok(())
    }

    /// [`set_geometry`](Self::set_geometry) for a caller that checked `mesh` already.
    pub(crate) fn move_to(&mut self, mesh: &TriMesh) {
        self.points = Self::place(&self.sites, mesh);
        self.last = None;
    }

    /// The mean of `view`'s multiplier over the probes: `E_rho[lod]`.
    pub fn mean_multiplier(&self, view: &ViewLod) -> f64 {
        // One thread, in order: the same sum whatever the thread count, and faster than
        // waking rayon's workers for 4096 multipliers (85 us here against 120 us).
        let sum: f64 = self
            .points
            .iter()
            .map(|&(p, n)| view.multiplier(p, n))
            .sum();
        sum / self.points.len() as f64
    }

    /// About how many samples `view` shows with base count `base`.
    pub fn shown(&self, view: &ViewLod, base: f64) -> f64 {
        base * self.mean_multiplier(view)
    }

    /// The base count under which `view` shows about `shown` samples, at most 2^32 (the
    /// sequence's length); `None` when the view shows nothing at any base count (no
    /// probe in view). The mean multiplier of the last view asked is kept: the same
    /// view again costs nothing.
    pub fn base_for(&mut self, view: &ViewLod, shown: f64) -> Option<f64> {
        let mean = match self.last {
            Some((last, mean)) if last == *view => mean,
            _ => {
                let mean = self.mean_multiplier(view);
                self.last = Some((*view, mean));
                mean
            }
        };
        (mean > 0.0).then(|| (shown / mean).min(4_294_967_296.0))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sample::lod::fade;
    use crate::surface::tests::torus_sampler;

    fn view(eye: DVec3, target: DVec3) -> ViewLod {
        let fov = 50f64.to_radians();
        let proj = glam::dcamera::rh::proj::directx::perspective(fov, 1.5, 0.01, 100.0);
        let look = glam::dcamera::rh::view::look_at_mat4(eye, target, DVec3::Y);
        ViewLod {
            clip_from_world: proj * look,
            eye,
            focal_pixels: 500.0 / (2.0 * (fov / 2.0).tan()),
            reference: 5000.0,
            max: 4.0,
            cull_back_faces: true,
        }
    }

    /// The ranks below `end` visible under `v` with base `base`, by a scan.
    fn count(s: &Sampler, seed: u64, end: u32, v: &ViewLod, base: f64) -> usize {
        let mut sites = vec![SampleSite::default(); end as usize];
        s.progressive_sites_into(seed, 0, &mut sites);
        (0..end)
            .zip(&sites)
            .filter(|&(k, site)| {
                let (p, n) =
                    position_normal(s.mesh(), site.face, site.barycentric().map(f64::from));
                fade(k, base, v.multiplier(p, n)) > 0.0
            })
            .count()
    }

    #[test]
    fn the_estimate_is_close_to_the_visible_count() {
        let s = torus_sampler();
        let mut estimate = ShownEstimate::new(&s, 7);
        // Far and near, from above and from the side, part of the torus out of view.
        for (eye, target) in [
            (DVec3::new(0.0, 3.0, 3.0), DVec3::ZERO),
            (DVec3::new(2.5, 0.5, 0.0), DVec3::ZERO),
            (DVec3::new(1.6, 0.6, 0.6), DVec3::new(1.0, 0.0, 0.0)),
        ] {
            let v = view(eye, target);
            let mean = estimate.mean_multiplier(&v);
            // A base under which at most max * base ranks can show: the scan covers them.
            let base = 20_000.0;
            let exact = count(&s, 7, (base * v.max) as u32 + 1, &v, base) as f64;
            let guess = estimate.shown(&v, base);
            assert!(exact > 1000.0, "{eye}: {exact} shown");
            assert!(
                (guess / exact - 1.0).abs() < 0.03,
                "{eye}: estimate {guess} against {exact} (mean multiplier {mean})"
            );
            let b = estimate.base_for(&v, exact).expect("in view");
            assert!((b / base - 1.0).abs() < 0.03, "{eye}: base {b}");
            // A smaller budget, a proportionally smaller base.
            let half = estimate.base_for(&v, exact / 2.0).expect("in view");
            assert!((half / b - 0.5).abs() < 1e-12);
        }
    }

    #[test]
    fn a_view_of_nothing_has_no_base() {
        let s = torus_sampler();
        let mut estimate = ShownEstimate::new(&s, 7);
        let away = view(DVec3::new(0.0, 0.0, 3.0), DVec3::new(0.0, 0.0, 6.0));
        assert_eq!(estimate.mean_multiplier(&away), 0.0);
        assert_eq!(estimate.base_for(&away, 1e6), None);
        // A tiny multiplier: the base is capped at the sequence's length.
        let far = ViewLod {
            reference: 1e300,
            ..view(DVec3::new(0.0, 3.0, 3.0), DVec3::ZERO)
        };
        assert_eq!(estimate.base_for(&far, 1e6), Some(4_294_967_296.0));
    }

    #[test]
    fn deformed_probes_follow_the_mesh() {
        let s = torus_sampler();
        let mut estimate = ShownEstimate::new(&s, 7);
        let v = view(DVec3::new(0.0, 3.0, 3.0), DVec3::ZERO);
        let before = estimate.mean_multiplier(&v);
        let base = estimate.base_for(&v, 1e4).expect("in view");
        // The torus moved away from the camera: it shows less.
        let rest = s.mesh();
        let shifted: Vec<DVec3> = rest
            .positions()
            .iter()
            .map(|&p| p - DVec3::new(0.0, 1.0, 1.0))
            .collect();
        let moved = TriMesh::new(shifted, rest.triangles().to_vec()).expect("mesh");
        estimate.set_geometry(&s, &moved).expect("same topology");
        let after = estimate.mean_multiplier(&v);
        assert!(after < 0.8 * before, "{after} against {before}");
        // The kept estimate of the view is dropped with the old geometry.
        let moved_base = estimate.base_for(&v, 1e4).expect("in view");
        assert!((moved_base * after / (base * before) - 1.0).abs() < 1e-12);
        let other = TriMesh::new(vec![DVec3::ZERO, DVec3::X, DVec3::Y], vec![[0, 1, 2]])
            .expect("a triangle");
        assert!(matches!(
            estimate.set_geometry(&s, &other),
            Err(LodError::Mismatch { .. })
        ));
        assert_eq!(estimate.mean_multiplier(&v), after);
    }
}
