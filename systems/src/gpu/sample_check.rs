//! Times sampling on the GPU per stage and checks its samples against the CPU's
//! ([`GpuSampleCheck`], what `strata bench --gpu` prints).
//!
//! Input: an open device, a sampler, a count and a seed. Output: the adapter's name,
//! the bytes of the GPU's cell table against the CPU's preprocessed data, the median
//! wall times (waiting for the device) of the per-request table on the CPU, the sites
//! pass and the sites pass with the expansion into records, and how the GPU's sites
//! differ from [`Sampler::sample_sites_into`]'s. Cost: `repeat + 1` GPU requests (the
//! first untimed), `repeat` CPU requests and one read-back.

use std::time::Instant;

use glam::DVec3;
use strata_engine::sample::{SampleSite, Sampler};

use super::buffers::GpuSampleBuffer;
use super::context::{GpuContext, GpuError};
use super::sample::GpuSampler;

/// The largest position deviation accepted, over the bounding-box diagonal.
pub const POSITION_TOLERANCE: f64 = 1e-5;

/// Samples accepted beyond [`POSITION_TOLERANCE`], per sample: points in triangles that
/// are slivers in the parameterization (a uv triangle a few 1e-7 wide), whose `f32`
/// coordinates resolve the triangle's width only to a few percent (one sample of 10^5
/// on the bunny, at 2.1e-5 of the diagonal).
pub const SLIVER_TOLERANCE: f64 = 1e-4;

/// The largest position deviation accepted for those samples, over the bounding-box
/// diagonal.
pub const SLIVER_POSITION_TOLERANCE: f64 = 1e-3;

/// Samples accepted with another face or segment than the CPU's, per sample. Such a
/// sample lies on an edge the two faces share, up to `f32` round-off (its position is
/// checked like every other's): on a grid-like plane, sub-cell centres that fall
/// exactly on a diagonal edge (0.1% of 10^5 samples of `plane-gaussian.ron`).
pub const DIFFERING_TOLERANCE: f64 = 1e-2;

/// One request timed and checked on the GPU ([module docs](self)).
#[derive(Clone, Debug, serde::Serialize)]
pub struct GpuSampleCheck {
    /// The adapter, as [`GpuContext::adapter_summary`] names it.
    pub adapter: String,
    /// Samples per request.
    pub count: usize,
    /// Faces of the mesh.
    pub faces: usize,
    /// Bytes of the GPU's cell table.
    pub table_bytes: u64,
    /// Bytes of the CPU's preprocessed data ([`Sampler::heap_bytes`]).
    pub cpu_bytes: usize,
    /// Median CPU time of the per-request table (allocation and levels), seconds.
    pub request_s: f64,
    /// Median wall time of the sites pass until the device is idle, seconds.
    pub sites_s: f64,
    /// Median wall time of the sites pass and the expansion into records, seconds.
    pub samples_s: f64,
    /// Median GPU times from timestamp queries of the sites pass (values, leaf search
    /// and points, fused in one pass) and of the expansion into records, seconds;
    /// `None` where the adapter has no timestamp queries (then only the wall times
    /// above, submit and wait, are measured).
    pub pass_s: Option<[f64; 2]>,
    /// Median CPU time of [`Sampler::sample_sites_into`] for the same request, seconds.
    pub cpu_sites_s: f64,
    /// Samples whose face differs from the CPU's.
    pub faces_differ: usize,
    /// Samples whose segment differs from the CPU's.
    pub segments_differ: usize,
    /// The largest distance between a GPU and a CPU site over the bounding-box
    /// diagonal.
    pub deviation: f64,
    /// Samples farther from the CPU's than [`POSITION_TOLERANCE`].
    pub beyond: usize,
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(0.0)
}

fn point(sampler: &Sampler, s: &SampleSite) -> DVec3 {
    let mesh = sampler.mesh();
    let tri = mesh.triangles()[s.face as usize];
    let b = s.barycentric().map(f64::from);
    (0..3).fold(DVec3::ZERO, |acc, k| {
        acc + mesh.positions()[tri[k] as usize] * b[k]
    })
}

impl GpuSampleCheck {
    /// Times `repeat` GPU requests of `n` samples for `seed` and compares the last
    /// one's sites with the CPU's.
    pub fn run(
        ctx: &GpuContext,
        sampler: &Sampler,
        n: usize,
        seed: u64,
        repeat: usize,
    ) -> Result<Self, GpuError> {
        let (device, queue) = (&ctx.device, &ctx.queue);
        let mut gpu = GpuSampler::new(device, sampler)?;
        let mut buffer = GpuSampleBuffer::new(device)?;
        let (mut request, mut sites, mut samples, mut cpu_sites) =
            (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        let (mut gpu_sites, mut gpu_records) = (Vec::new(), Vec::new());
        let mut cpu = vec![SampleSite::default(); n];
        // One request untimed: the first dispatch of a pipeline may compile it.
        gpu.sample(device, queue, n, seed, &mut buffer)?;
        ctx.wait_idle("sampling on the GPU")?;
        // The tables as deep as this count needs (the first request deepened them).
        let flat = gpu.flat().clone();
        for _ in 0..repeat.max(1) {
            let t = Instant::now();
            flat.request(sampler, n as u64, seed)?;
            request.push(t.elapsed().as_secs_f64());
            let t = Instant::now();
            gpu.sample_sites(device, queue, n, seed)?;
            ctx.wait_idle("sampling sites on the GPU")?;
            sites.push(t.elapsed().as_secs_f64());
            let t = Instant::now();
            gpu.sample(device, queue, n, seed, &mut buffer)?;
            ctx.wait_idle("sampling on the GPU")?;
            samples.push(t.elapsed().as_secs_f64());
            if let Some([a, b]) = gpu.pass_times(device, queue)? {
                gpu_sites.push(a);
                gpu_records.push(b);
            }
            let t = Instant::now();
            sampler.sample_sites_into(seed, &mut cpu);
            cpu_sites.push(t.elapsed().as_secs_f64());
        }
        let got = gpu.read_sites(device, queue)?;
        let (lo, hi) = sampler.mesh().bounds();
        let diagonal = (hi - lo).length().max(f64::MIN_POSITIVE);
        let mut check = Self {
            adapter: ctx.adapter_summary(),
            count: n,
            faces: sampler.mesh().face_count(),
            table_bytes: gpu.table_bytes(),
            cpu_bytes: sampler.heap_bytes(),
            request_s: median(request),
            sites_s: median(sites),
            samples_s: median(samples),
            pass_s: (!gpu_sites.is_empty()).then(|| [median(gpu_sites), median(gpu_records)]),
            cpu_sites_s: median(cpu_sites),
            faces_differ: 0,
            segments_differ: 0,
            deviation: 0.0,
            beyond: 0,
        };
        for (g, c) in got.iter().zip(&cpu) {
            check.faces_differ += usize::from(g.face != c.face);
            check.segments_differ += usize::from(g.segment != c.segment);
            let d = point(sampler, g).distance(point(sampler, c)) / diagonal;
            check.deviation = check.deviation.max(d);
            check.beyond += usize::from(d > POSITION_TOLERANCE);
        }
        Ok(check)
    }

    /// Whether the GPU's samples are the CPU's within [`POSITION_TOLERANCE`] (but for
    /// [`SLIVER_TOLERANCE`] of them, within [`SLIVER_POSITION_TOLERANCE`]) and
    /// [`DIFFERING_TOLERANCE`].
    pub fn passes(&self) -> bool {
        let limit = (DIFFERING_TOLERANCE * self.count as f64).floor() as usize;
        let slivers = (SLIVER_TOLERANCE * self.count as f64).floor() as usize;
        self.deviation <= SLIVER_POSITION_TOLERANCE
            && self.beyond <= slivers
            && self.faces_differ <= limit
            && self.segments_differ <= limit
    }
}

impl std::fmt::Display for GpuSampleCheck {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let per_face = |b: f64| b / self.faces.max(1) as f64;
        writeln!(f, "GPU sampling on {}", self.adapter)?;
        writeln!(
            f,
            "cell table {:.1} MiB ({:.0} bytes per face) against the CPU's preprocessed {:.1} MiB ({:.0} bytes per face)",
            self.table_bytes as f64 / (1024.0 * 1024.0),
            per_face(self.table_bytes as f64),
            self.cpu_bytes as f64 / (1024.0 * 1024.0),
            per_face(self.cpu_bytes as f64),
        )?;
        writeln!(
            f,
            "{} samples, medians: counts (request table, CPU) {:.3} ms, sites pass {:.3} ms, sites and records {:.3} ms (wall: submit and wait for the device); CPU sites {:.3} ms",
            self.count,
            self.request_s * 1e3,
            self.sites_s * 1e3,
            self.samples_s * 1e3,
            self.cpu_sites_s * 1e3,
        )?;
        match self.pass_s {
            Some([sites, records]) => writeln!(
                f,
                "GPU time (timestamp queries): values, search and point (one pass) {:.3} ms, record {:.3} ms",
                sites * 1e3,
                records * 1e3
            )?,
            None => writeln!(
                f,
                "GPU time: not measured (the adapter has no timestamp queries; the wall times above include submission and waiting)"
            )?,
        }
        write!(
            f,
            "against the CPU: {} faces and {} segments differ, largest deviation {:.2e} of the bounding-box diagonal, {} samples beyond {:.0e} ({})",
            self.faces_differ,
            self.segments_differ,
            self.deviation,
            self.beyond,
            POSITION_TOLERANCE,
            if self.passes() {
                "within tolerance"
            } else {
                "OUT OF TOLERANCE"
            }
        )
    }
}
