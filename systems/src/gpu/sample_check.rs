//! Times sampling on the GPU per stage and checks its samples against the CPU's
//! ([`GpuSampleCheck`], what `strata bench --gpu` prints), in either order.
//!
//! Input: an open device, a sampler, a count, a seed and an order ([`GpuOrder`]).
//! Output: the adapter's name, the bytes of the GPU's cell table against the CPU's
//! preprocessed data, the median wall times (waiting for the device) of the
//! per-request table on the CPU, the sites pass and (stratified) the sites pass with
//! the expansion into records, and how the GPU's sites differ from the CPU's
//! ([`Sampler::sample_sites_into`], or [`Sampler::progressive_sites_into`] from rank
//! 0). Cost: `repeat + 1` GPU requests (the first untimed), `repeat` CPU requests and
//! one read-back.

use std::time::Instant;

use strata_engine::sample::{SampleSite, Sampler};

use super::buffers::GpuSampleBuffer;
use super::context::{GpuContext, GpuError};
use super::sample::GpuSampler;
use strata_engine::sample::flat::progressive_scramble;

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

/// The largest position deviation accepted in the progressive order, over the
/// bounding-box diagonal. Its boundary leaves are descended twelve levels in `f32`
/// rather than over the CPU's exact tree: in a leaf that a parameterization sliver
/// crosses (on the bunny a uv triangle 1e-4 of its leaf wide holding three quarters
/// of the leaf's measure, its density 1600 times its neighbour's), `f32` corners
/// resolve the sliver's share to about 5e-4, so an early choice of sub-cell can differ
/// from the CPU's: 2 samples of 10^5 on the bunny at 1.2e-3 of the diagonal.
pub const PROGRESSIVE_POSITION_TOLERANCE: f64 = 2e-3;

/// Samples accepted with another face or segment than the CPU's, per sample. Such a
/// sample lies on an edge the two faces share, up to `f32` round-off (its position is
/// checked like every other's): on a grid-like plane, sub-cell centres that fall
/// exactly on a diagonal edge (0.1% of 10^5 samples of `plane-gaussian.ron`).
pub const DIFFERING_TOLERANCE: f64 = 1e-2;

/// The order of a checked request.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum GpuOrder {
    /// [`GpuSampler::sample_sites`] against [`Sampler::sample_sites_into`].
    Stratified,
    /// [`GpuSampler::sample_progressive_sites`] from rank 0 against
    /// [`Sampler::progressive_sites_into`].
    Progressive,
}

impl std::fmt::Display for GpuOrder {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            GpuOrder::Stratified => "stratified",
            GpuOrder::Progressive => "progressive",
        })
    }
}

/// One request timed and checked on the GPU ([module docs](self)).
#[derive(Clone, Debug, serde::Serialize)]
pub struct GpuSampleCheck {
    /// The order sampled.
    pub order: GpuOrder,
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
    /// Median wall time of the sites pass and the expansion into records, seconds
    /// (stratified; `None` for the progressive order, whose records the level-of-detail
    /// pool's expansion makes).
    pub samples_s: Option<f64>,
    /// Median GPU times from timestamp queries of the sites pass (values, leaf search
    /// and points, fused in one pass) and of the expansion into records, seconds;
    /// `None` where the adapter has no timestamp queries (then only the wall times
    /// above, submit and wait, are measured).
    pub pass_s: Option<[f64; 2]>,
    /// Median CPU time of the same request's sites on the CPU, seconds.
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

impl GpuSampleCheck {
    /// Times `repeat` GPU requests of `n` stratified samples for `seed` and compares
    /// the last one's sites with the CPU's.
    pub fn run(
        ctx: &GpuContext,
        sampler: &Sampler,
        n: usize,
        seed: u64,
        repeat: usize,
    ) -> Result<Self, GpuError> {
        Self::run_order(ctx, sampler, (n, seed, GpuOrder::Stratified), repeat)
    }

    /// Times `repeat` GPU requests of `n` samples for `seed` in `order` and compares
    /// the last one's sites with the CPU's.
    pub fn run_order(
        ctx: &GpuContext,
        sampler: &Sampler,
        (n, seed, order): (usize, u64, GpuOrder),
        repeat: usize,
    ) -> Result<Self, GpuError> {
        if order == GpuOrder::Progressive {
            return Self::run_progressive(ctx, sampler, n, seed, repeat);
        }
        let (device, queue) = (&ctx.device, &ctx.queue);
        let mut gpu = GpuSampler::new(device, sampler)?;
        gpu.set_timing(true);
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
        let mut check = Self {
            request_s: median(request),
            sites_s: median(sites),
            samples_s: Some(median(samples)),
            pass_s: (!gpu_sites.is_empty()).then(|| [median(gpu_sites), median(gpu_records)]),
            cpu_sites_s: median(cpu_sites),
            ..Self::unmeasured(GpuOrder::Stratified, ctx, sampler, n, &gpu)
        };
        check.compare(sampler, &got, &cpu);
        Ok(check)
    }

    /// [`run_order`](Self::run_order) for the progressive order.
    fn run_progressive(
        ctx: &GpuContext,
        sampler: &Sampler,
        n: usize,
        seed: u64,
        repeat: usize,
    ) -> Result<Self, GpuError> {
        let (device, queue) = (&ctx.device, &ctx.queue);
        let mut gpu = GpuSampler::new(device, sampler)?;
        gpu.set_timing(true);
        let (mut request, mut sites, mut passes, mut cpu_sites) =
            (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        let mut cpu = vec![SampleSite::default(); n];
        gpu.sample_progressive_sites(device, queue, 0, n, seed)?;
        ctx.wait_idle("sampling progressively on the GPU")?;
        for _ in 0..repeat.max(1) {
            let t = Instant::now();
            std::hint::black_box(progressive_scramble(std::hint::black_box(seed)));
            request.push(t.elapsed().as_secs_f64());
            let t = Instant::now();
            gpu.sample_progressive_sites(device, queue, 0, n, seed)?;
            ctx.wait_idle("sampling progressively on the GPU")?;
            sites.push(t.elapsed().as_secs_f64());
            if let Some(pass) = gpu.sites_pass_time(device, queue)? {
                passes.push(pass);
            }
            let t = Instant::now();
            sampler.progressive_sites_into(seed, 0, &mut cpu);
            cpu_sites.push(t.elapsed().as_secs_f64());
        }
        let got = gpu.read_sites(device, queue)?;
        let mut check = Self {
            request_s: median(request),
            sites_s: median(sites),
            samples_s: None,
            pass_s: (!passes.is_empty()).then(|| [median(passes), 0.0]),
            cpu_sites_s: median(cpu_sites),
            ..Self::unmeasured(GpuOrder::Progressive, ctx, sampler, n, &gpu)
        };
        check.compare(sampler, &got, &cpu);
        Ok(check)
    }

    /// Counts how the GPU's sites `got` differ from the CPU's `cpu`.
    /// What a check knows before it times or compares anything: the order, the
    /// adapter, the count and the sizes, with every time and difference zero.
    fn unmeasured(
        order: GpuOrder,
        ctx: &GpuContext,
        sampler: &Sampler,
        n: usize,
        gpu: &GpuSampler,
    ) -> Self {
        Self {
            order,
            adapter: ctx.adapter_summary(),
            count: n,
            faces: sampler.mesh().face_count(),
            table_bytes: gpu.table_bytes(),
            cpu_bytes: sampler.heap_bytes(),
            request_s: 0.0,
            sites_s: 0.0,
            samples_s: None,
            pass_s: None,
            cpu_sites_s: 0.0,
            faces_differ: 0,
            segments_differ: 0,
            deviation: 0.0,
            beyond: 0,
        }
    }

    fn compare(&mut self, sampler: &Sampler, got: &[SampleSite], cpu: &[SampleSite]) {
        let (lo, hi) = sampler.mesh().bounds();
        let diagonal = (hi - lo).length().max(f64::MIN_POSITIVE);
        let check = self;
        for (g, c) in got.iter().zip(cpu) {
            check.faces_differ += usize::from(g.face != c.face);
            check.segments_differ += usize::from(g.segment != c.segment);
            let d = (g
                .position_on(sampler.mesh())
                .zip(c.position_on(sampler.mesh())))
            .map_or(f64::INFINITY, |(p, q)| p.distance(q) / diagonal);
            check.deviation = check.deviation.max(d);
            check.beyond += usize::from(d > POSITION_TOLERANCE);
        }
    }

    /// Whether the GPU's samples are the CPU's within [`POSITION_TOLERANCE`] (but for
    /// [`SLIVER_TOLERANCE`] of them, within [`SLIVER_POSITION_TOLERANCE`]) and
    /// [`DIFFERING_TOLERANCE`].
    pub fn passes(&self) -> bool {
        let limit = (DIFFERING_TOLERANCE * self.count as f64).floor() as usize;
        let slivers = (SLIVER_TOLERANCE * self.count as f64).floor() as usize;
        let position = match self.order {
            GpuOrder::Stratified => SLIVER_POSITION_TOLERANCE,
            GpuOrder::Progressive => PROGRESSIVE_POSITION_TOLERANCE,
        };
        self.deviation <= position
            && self.beyond <= slivers
            && self.faces_differ <= limit
            && self.segments_differ <= limit
    }
}

impl std::fmt::Display for GpuSampleCheck {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let per_face = |b: f64| b / self.faces.max(1) as f64;
        writeln!(f, "GPU sampling, {} order, on {}", self.order, self.adapter)?;
        writeln!(
            f,
            "cell table {:.1} MiB ({:.0} bytes per face) against the CPU's preprocessed {:.1} MiB ({:.0} bytes per face)",
            self.table_bytes as f64 / (1024.0 * 1024.0),
            per_face(self.table_bytes as f64),
            self.cpu_bytes as f64 / (1024.0 * 1024.0),
            per_face(self.cpu_bytes as f64),
        )?;
        match self.samples_s {
            Some(samples_s) => writeln!(
                f,
                "{} samples, medians: counts (request table, CPU) {:.3} ms, sites pass {:.3} ms, sites and records {:.3} ms (wall: submit and wait for the device); CPU sites {:.3} ms",
                self.count,
                self.request_s * 1e3,
                self.sites_s * 1e3,
                samples_s * 1e3,
                self.cpu_sites_s * 1e3,
            )?,
            None => writeln!(
                f,
                "{} samples, medians: scramble (request, CPU) {:.4} ms, sites pass {:.3} ms (wall: submit and wait for the device); CPU sites {:.3} ms",
                self.count,
                self.request_s * 1e3,
                self.sites_s * 1e3,
                self.cpu_sites_s * 1e3,
            )?,
        }
        match self.pass_s {
            Some([sites, _]) if self.order == GpuOrder::Progressive => writeln!(
                f,
                "GPU time (timestamp queries): values, search and point (one pass) {:.3} ms",
                sites * 1e3
            )?,
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
