//! GPU-resident progressive pools and the level-of-detail visible set (issue 19).
//!
//! [`GpuLodPool`] keeps a copy of an engine [`LodPool`] on the GPU: its sites and ranks
//! (20 bytes per entry) and their expanded samples in the renderer's sample buffer.
//! After [`LodPool::update`] only the entries it appended are uploaded and expanded
//! ([`GpuLodPool::sync`]); a pool rebuilt for a far view re-sends its extension. With
//! [`GpuLodPool::sync_placed`] only the new entries' ranks are uploaded (4 bytes each)
//! and [`GpuSampler`]'s progressive pass places them on the GPU; the engine pool is
//! then built with [`Placement::Elsewhere`], so that it lists ranks and places
//! nothing on the CPU either. The
//! splat pipelines then cull and fade by rank against the frame's camera
//! ([`SplatLod`], in the vertex shader), so a frame whose view
//! needs no new ranks uploads nothing but its uniforms. A deforming mesh keeps its
//! samples: [`SiteExpander::set_geometry`] and [`GpuLodPool::reexpand`] move them onto
//! the new surface without resampling.
//!
//! [`LodFades`] reads back the fade weight of every sample as the splat pipelines
//! compute it (the same WGSL function): the GPU's visible set, for tests against
//! [`LodPool::fades_into`] and for counting what a frame shows.

use strata_engine::mesh::TriMesh;
use strata_engine::sample::lod::Placement;
use strata_engine::sample::{Budget, FrameUpdate, LodPool, PoolChange, SampleSite, Sampler};

use super::buffers::{GpuSampleBuffer, next_capacity, read_buffer};
use super::camera::OrbitCamera;
use super::context::{GpuError, scoped};
use super::expand::{Bound, SiteExpander};
use super::pipeline::{ComputePipelineDesc, buffer_entry, pipeline_layout, shader_module};
use super::sample::{GpuSampler, Ranks};
use super::shaders;
use super::splat::{SplatLod, SplatStyle, frame_uniforms};

const SITE_BYTES: u64 = std::mem::size_of::<SampleSite>() as u64;

/// Where the sites of a pool's new entries come from.
#[derive(Clone, Copy)]
enum SiteSource<'a> {
    /// Uploaded from the pool (placed by the CPU); expanded with the expander.
    Upload(&'a SiteExpander),
    /// Placed by the sampler's progressive pass.
    Gpu(&'a GpuSampler),
}

/// The GPU copy of an engine [`LodPool`]: see the module docs.
#[derive(Debug)]
pub struct GpuLodPool {
    sites: wgpu::Buffer,
    ranks: wgpu::Buffer,
    capacity: usize,
    len: usize,
    base: f64,
    /// The progressive pass's bind group and the buffers it binds.
    placing: Bound<4>,
    /// The expansion's bind group and the buffers it binds.
    expanding: Bound<5>,
    /// Whether the last submission was checked in error scopes and no bind group was
    /// made since: a sync binding the same buffers is submitted without scopes (popping
    /// them allocates); an error then (out of memory) reaches the device's
    /// uncaptured-error handler.
    checked: bool,
}

impl GpuLodPool {
    /// An empty copy; samples are expanded with the spacings of `base` samples over
    /// the surface (the pool's base count, at multiplier 1).
    pub fn new(device: &wgpu::Device, base: f64) -> Result<Self, GpuError> {
        let capacity = 1024;
        let (sites, ranks) = Self::allocate(device, capacity)?;
        Ok(Self {
            sites,
            ranks,
            capacity,
            len: 0,
            base,
            placing: None,
            expanding: None,
            checked: false,
        })
    }

    fn allocate(
        device: &wgpu::Device,
        capacity: usize,
    ) -> Result<(wgpu::Buffer, wgpu::Buffer), GpuError> {
        let limits = device.limits();
        let limit = limits
            .max_buffer_size
            .min(limits.max_storage_buffer_binding_size);
        let bytes = capacity as u64 * SITE_BYTES;
        if bytes > limit {
            return Err(GpuError::Limit {
                what: "progressive pool sites (bytes)",
                requested: bytes,
                limit,
            });
        }
        scoped(device, "allocating the progressive pool", || {
            let buffer = |label, size| {
                device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some(label),
                    size,
                    usage: wgpu::BufferUsages::STORAGE
                        | wgpu::BufferUsages::COPY_DST
                        | wgpu::BufferUsages::COPY_SRC,
                    mapped_at_creation: false,
                })
            };
            (
                buffer("strata pool sites", bytes),
                buffer("strata pool ranks", capacity as u64 * 4),
            )
        })
    }

    /// Entries held on the GPU.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether no entry is held.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Brings the GPU copy up to `pool` after `change` (what the last
    /// [`LodPool::update`] returned; anything for a first call) and expands the
    /// entries that changed into `samples` with `expander` (built for the pool's
    /// sampler). Returns the bytes uploaded: 20 per new entry. Records and submits;
    /// never waits on the GPU. An error, and nothing sent, for a pool whose entries
    /// are not placed on the CPU ([`Placement::Elsewhere`]: use
    /// [`sync_placed`](Self::sync_placed)).
    pub fn sync(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        pool: &LodPool,
        change: &PoolChange,
        expander: &SiteExpander,
        samples: &mut GpuSampleBuffer,
    ) -> Result<u64, GpuError> {
        if pool.placement() != Placement::Cpu {
            return Err(GpuError::Mismatch {
                what: "a level-of-detail pool synced with its sites",
                detail: "its entries are placed elsewhere (sync_placed places them)".into(),
            });
        }
        self.sync_with(
            device,
            queue,
            (pool, change),
            SiteSource::Upload(expander),
            samples,
        )
    }

    /// [`sync`](Self::sync) with the new entries placed on the GPU: only their ranks
    /// are uploaded (4 bytes per new entry), and `sampler`'s progressive pass (built
    /// for the pool's sampler) places them in the GPU copy's sites buffer, the sites
    /// a CPU-placed pool holds up to `f32` round-off (the tolerances of
    /// [`GpuSampler::sample_progressive_sites`]); its expander makes the records.
    /// Reads only the pool's ranks and seed: build it with [`Placement::Elsewhere`]
    /// ([`LodPool::new_with`]) so that its updates place nothing on the CPU.
    /// Returns the bytes uploaded. Records and submits; never waits on the GPU.
    pub fn sync_placed(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        (pool, change): (&LodPool, &PoolChange),
        sampler: &GpuSampler,
        samples: &mut GpuSampleBuffer,
    ) -> Result<u64, GpuError> {
        self.sync_with(
            device,
            queue,
            (pool, change),
            SiteSource::Gpu(sampler),
            samples,
        )
    }

    /// Copies the sites held on the GPU back (waits for the device; for tests).
    pub fn read_sites(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> Result<Vec<SampleSite>, GpuError> {
        let bytes = read_buffer(device, queue, &self.sites, self.len as u64 * SITE_BYTES)?;
        Ok(bytemuck::pod_collect_to_vec(&bytes))
    }

    fn sync_with(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        (pool, change): (&LodPool, &PoolChange),
        placement: SiteSource<'_>,
        samples: &mut GpuSampleBuffer,
    ) -> Result<u64, GpuError> {
        let n = pool.len();
        let from = match change {
            _ if self.len == 0 => 0,
            PoolChange::Unchanged => n.min(self.len),
            PoolChange::Appended(r) => r.start.min(self.len),
            PoolChange::Rebuilt => (pool.prefix() as usize).min(self.len),
        };
        if from == n && n == self.len && samples.len() == n {
            // Nothing new: no upload, no pass, no submit.
            return Ok(0);
        }
        let count = u32::try_from(n).map_err(|_| GpuError::Limit {
            what: "progressive pool entries",
            requested: n as u64,
            limit: u64::from(u32::MAX),
        })?;
        let mut encoder = device.create_command_encoder(&Default::default());
        if n > self.capacity {
            // Grow on the GPU: the entries held are copied, not sent again.
            let capacity = next_capacity(self.capacity, n);
            let (sites, ranks) = Self::allocate(device, capacity)?;
            let kept = self.len.min(from) as u64;
            encoder.copy_buffer_to_buffer(&self.sites, 0, &sites, 0, kept * SITE_BYTES);
            encoder.copy_buffer_to_buffer(&self.ranks, 0, &ranks, 0, kept * 4);
            (self.sites, self.ranks, self.capacity) = (sites, ranks, capacity);
        }
        queue.write_buffer(
            &self.ranks,
            from as u64 * 4,
            bytemuck::cast_slice(&pool.ranks()[from..]),
        );
        let (expander, site_bytes, placed) = match placement {
            SiteSource::Upload(expander) => {
                let new = &pool.sites()[from..];
                queue.write_buffer(
                    &self.sites,
                    from as u64 * SITE_BYTES,
                    bytemuck::cast_slice(new),
                );
                (expander, SITE_BYTES, false)
            }
            SiteSource::Gpu(sampler) => {
                let ranks = Ranks::Listed(&self.ranks, from as u32);
                let made = sampler.encode_progressive(
                    device,
                    queue,
                    &mut encoder,
                    (ranks, count - from as u32, pool.seed()),
                    (&self.sites, from as u32),
                    (None, &mut self.placing),
                )?;
                (sampler.expander(), 0, made)
            }
        };
        let reallocations = samples.reallocations();
        samples.resize(device, n)?;
        // A reallocated sample buffer lost its contents: expand every entry.
        let first = if samples.reallocations() != reallocations {
            0
        } else {
            from as u32
        };
        let expanded = expander.expand_ranked(
            device,
            queue,
            &mut encoder,
            (&self.sites, &self.ranks, samples.buffer()),
            first..count,
            self.base,
            &mut self.expanding,
        )?;
        if self.checked && !placed && !expanded {
            queue.submit([encoder.finish()]);
        } else {
            self.checked = false;
            scoped(device, "expanding the progressive pool", || {
                queue.submit([encoder.finish()]);
            })?;
            self.checked = true;
        }
        self.len = n;
        Ok((n - from) as u64 * (site_bytes + 4))
    }

    /// Expands every entry again (after [`SiteExpander::set_geometry`] deformed the
    /// mesh): no upload, no resampling.
    pub fn reexpand(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        expander: &SiteExpander,
        samples: &GpuSampleBuffer,
    ) -> Result<(), GpuError> {
        scoped(device, "expanding the progressive pool", || {
            let mut encoder = device.create_command_encoder(&Default::default());
            expander.expand_ranked(
                device,
                queue,
                &mut encoder,
                (&self.sites, &self.ranks, samples.buffer()),
                0..self.len as u32,
                self.base,
                &mut None,
            )?;
            queue.submit([encoder.finish()]);
            Ok(())
        })?
    }
}

/// Rows of the fade pass's 2-D dispatch, in invocations (the shader's constant).
const FADE_ROW: u32 = 64 * 1024;

/// The fade-weight pass (`cs_lod_fades` in `shaders/splat.wgsl`): see the module docs.
#[derive(Debug)]
pub struct LodFades {
    pipeline: wgpu::ComputePipeline,
    frame_layout: wgpu::BindGroupLayout,
    layout: wgpu::BindGroupLayout,
}

impl LodFades {
    /// Builds the pass.
    pub fn new(device: &wgpu::Device) -> Result<Self, GpuError> {
        scoped(device, "building the fade pass", || {
            let module = shader_module(device, "strata lod fades", shaders::SPLAT);
            let entry = |binding, ty| buffer_entry(binding, wgpu::ShaderStages::COMPUTE, ty, None);
            let frame_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("strata lod frame"),
                entries: &[entry(0, wgpu::BufferBindingType::Uniform)],
            });
            let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("strata lod fades"),
                entries: &[
                    entry(0, wgpu::BufferBindingType::Storage { read_only: true }),
                    entry(1, wgpu::BufferBindingType::Storage { read_only: false }),
                ],
            });
            let pipeline_layout = pipeline_layout(
                device,
                "strata lod fades",
                &[Some(&frame_layout), Some(&layout)],
            );
            let pipeline = ComputePipelineDesc {
                label: "strata lod fades",
                entry: "cs_lod_fades",
            }
            .create(device, &pipeline_layout, &module);
            Self {
                pipeline,
                frame_layout,
                layout,
            }
        })
    }

    /// The fade weight of each of `samples` for `camera` and `style` (whose `lod`
    /// is used; 1 everywhere without one) on a target of `size` pixels, read back.
    /// Waits for the device: for tests and statistics, not for the frame loop.
    pub fn fades(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        samples: &GpuSampleBuffer,
        camera: &OrbitCamera,
        style: &SplatStyle,
        size: (u32, u32),
    ) -> Result<Vec<f32>, GpuError> {
        let n = samples.len() as u64;
        if n == 0 {
            return Ok(Vec::new());
        }
        let uniforms = frame_uniforms(camera, style, size, 0.0);
        let out = scoped(device, "computing fade weights", || {
            let frame = wgpu::util::DeviceExt::create_buffer_init(
                device,
                &wgpu::util::BufferInitDescriptor {
                    label: Some("strata lod frame"),
                    contents: bytemuck::bytes_of(&uniforms),
                    usage: wgpu::BufferUsages::UNIFORM,
                },
            );
            let out = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("strata lod fades"),
                size: n * 4,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            });
            let frame_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("strata lod frame"),
                layout: &self.frame_layout,
                entries: &[wgpu::BindGroupEntry {
                    binding: 0,
                    resource: frame.as_entire_binding(),
                }],
            });
            let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("strata lod fades"),
                layout: &self.layout,
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                            buffer: samples.buffer(),
                            offset: 0,
                            size: wgpu::BufferSize::new(n * 64),
                        }),
                    },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: out.as_entire_binding(),
                    },
                ],
            });
            let mut encoder = device.create_command_encoder(&Default::default());
            {
                let mut pass = encoder.begin_compute_pass(&Default::default());
                pass.set_pipeline(&self.pipeline);
                pass.set_bind_group(0, &frame_group, &[]);
                pass.set_bind_group(1, &group, &[]);
                let rows = (n as u32).div_ceil(FADE_ROW);
                let columns = (n as u32).min(FADE_ROW).div_ceil(64);
                pass.dispatch_workgroups(columns, rows, 1);
            }
            queue.submit([encoder.finish()]);
            out
        })?;
        let bytes = read_buffer(device, queue, &out, n * 4)?;
        Ok(bytemuck::pod_collect_to_vec(&bytes))
    }
}

/// What one [`LodScene::frame`] did.
#[derive(Clone, Debug, PartialEq)]
pub struct LodFrame {
    /// The engine pool's change.
    pub change: PoolChange,
    /// Bytes sent to the GPU for the pool (uniforms not counted).
    pub uploaded: u64,
    /// Entries in the pool (the instances drawn; the shader culls the rest).
    pub entries: usize,
    /// CPU time of the pool update (new ranks and their sites, and the point budget's
    /// base count).
    pub update: std::time::Duration,
}

/// A sampler drawn with level of detail: an engine [`LodPool`], its GPU copy and the
/// expansion pass, brought up to each frame's camera by [`frame`](Self::frame) before
/// the splat renderer draws with [`style`](Self::style).
#[derive(Debug)]
pub struct LodScene {
    pool: LodPool,
    gpu: GpuLodPool,
    expander: SiteExpander,
    lod: SplatLod,
    /// A point budget: the samples each frame shows, about.
    shown: Option<u32>,
}

impl LodScene {
    /// A pool of `sampler`'s progressive sequence for `seed` holding ranks
    /// `0..lod.base` and up to `budget` more where views ask for them; the samples are
    /// expanded for `lod.base` (its [`expanded`](SplatLod::expanded) is set to it).
    pub fn new(
        device: &wgpu::Device,
        sampler: &Sampler,
        seed: u64,
        lod: SplatLod,
        budget: usize,
    ) -> Result<Self, GpuError> {
        Ok(Self {
            pool: LodPool::new(sampler, seed, lod.base as u32, budget),
            gpu: GpuLodPool::new(device, f64::from(lod.base))?,
            expander: SiteExpander::new(device, sampler)?,
            lod: SplatLod {
                expanded: lod.base,
                ..lod
            },
            shown: None,
        })
    }

    /// The same scene with a point budget: every [`frame`](Self::frame) thresholds
    /// with the base count under which its camera shows about `shown` samples
    /// ([`Budget::Shown`]); the base count given to [`new`](Self::new) stays the pool's
    /// prefix and the base count of a view of nothing.
    pub fn with_shown(mut self, shown: u32) -> Self {
        self.shown = Some(shown);
        self
    }

    /// The engine pool.
    pub fn pool(&self) -> &LodPool {
        &self.pool
    }

    /// The level of detail.
    pub fn lod(&self) -> SplatLod {
        self.lod
    }

    /// The expansion pass (for [`SiteExpander::set_geometry`] on a deforming mesh,
    /// then [`reexpand`](Self::reexpand)).
    pub fn expander(&self) -> &SiteExpander {
        &self.expander
    }

    /// `style` drawing with this level of detail.
    pub fn style(&self, style: &SplatStyle) -> SplatStyle {
        SplatStyle {
            lod: Some(self.lod),
            ..*style
        }
    }

    /// Draws the ranks `camera` on a target of `size` pixels needs and sends the new
    /// entries into `samples` (the renderer's sample buffer).
    pub fn frame(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        sampler: &Sampler,
        samples: &mut GpuSampleBuffer,
        camera: &OrbitCamera,
        size: (u32, u32),
    ) -> Result<LodFrame, GpuError> {
        let view = self.lod.view(camera, size);
        let clock = std::time::Instant::now();
        let budget = Budget::new(f64::from(self.lod.expanded), self.shown);
        let FrameUpdate { change, base } =
            self.pool
                .update(sampler, &view, budget)
                .map_err(|e| GpuError::Mismatch {
                    what: "the sampler of a level-of-detail frame",
                    detail: e.to_string(),
                })?;
        self.lod.base = base as f32;
        let update = clock.elapsed();
        let uploaded =
            self.gpu
                .sync(device, queue, &self.pool, &change, &self.expander, samples)?;
        Ok(LodFrame {
            change,
            uploaded,
            entries: self.pool.len(),
            update,
        })
    }

    /// Moves the samples onto `mesh`, a deformation of the sampler's mesh (the same
    /// vertices and triangles, moved): the pool's bounds, the expansion pass's vertex
    /// table and every entry on the GPU follow it; nothing is resampled or sent but
    /// the vertices.
    pub fn deform(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        sampler: &Sampler,
        mesh: &TriMesh,
        samples: &GpuSampleBuffer,
    ) -> Result<(), GpuError> {
        self.pool
            .set_geometry(sampler, mesh)
            .map_err(|e| GpuError::Mismatch {
                what: "deformed mesh",
                detail: e.to_string(),
            })?;
        self.expander.set_geometry(queue, mesh)?;
        self.reexpand(device, queue, samples)
    }

    /// Expands every entry again from the expander's current mesh.
    pub fn reexpand(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        samples: &GpuSampleBuffer,
    ) -> Result<(), GpuError> {
        self.gpu.reexpand(device, queue, &self.expander, samples)
    }
}

/// The pool with GPU placement against the CPU pool, on whatever adapter wgpu opens
/// (the software adapter in CI); skipped without one unless `STRATA_REQUIRE_GPU=1`.
#[cfg(test)]
mod gpu_tests {
    use std::io::Write;
    use std::path::Path;

    use glam::Vec3;
    use strata_engine::sample::lod::Placement;
    use strata_engine::sample::{Budget, LodPool, PoolChange, SampleSite};

    use super::GpuLodPool;
    use crate::config::SceneConfig;
    use crate::gpu::{GpuContext, GpuSampleBuffer, GpuSampler, OrbitCamera, SplatLod};
    use crate::scene::Scene;

    const BASE: f64 = 20_000.0;

    /// A pool that lists ranks only, synced with GPU placement, holds the sites of a
    /// pool placed on the CPU (the sampler check's tolerances: at most 1 in 10^4
    /// beyond 1e-5 of the diagonal, none beyond 1e-4, at most 1 in 10^3 in another
    /// face) along a dolly in and an orbit on the default scene and on the same shape
    /// with coarse cells (boundary leaves at level 3, placed over the progressive
    /// trees), uploading 4 bytes per new entry, and the expanded records follow the
    /// sites. Synced with its sites instead, it is refused.
    #[test]
    fn placed_pool_holds_the_cpu_pools_sites() {
        let Some(ctx) = GpuContext::headless_or_skip("placed_pool_holds_the_cpu_pools_sites")
        else {
            return;
        };
        let shape = "mesh: Shape(Genus2(size: 2.0, resolution: 3)), \
             field: Constant(direction: (1.0, 0.3, 0.2), anisotropy: 3.0, density: 1.0)";
        placed_pool_follows(&ctx, &format!("({shape})"), "default");
        placed_pool_follows(
            &ctx,
            &format!("({shape}, curve: (max_cell_share: 0.02, boundary_level: 3))"),
            "coarse",
        );
    }

    /// `placed_pool_holds_the_cpu_pools_sites` on the scene `ron` (`name` in messages).
    fn placed_pool_follows(ctx: &GpuContext, ron: &str, name: &str) {
        let (device, queue) = (&ctx.device, &ctx.queue);
        let config = SceneConfig::from_ron(ron, Path::new("test.ron")).expect("parses");
        let scene = Scene::build(&config).expect("builds");
        let s = &scene.sampler;
        let gpu = GpuSampler::new(device, s).expect("GPU sampler");
        let mut pool = LodPool::new(s, 5, BASE as u32, 2_000_000);
        let mut listed = LodPool::new_with(s, 5, (BASE as u32, 2_000_000), Placement::Elsewhere);
        let mut gpu_pool = GpuLodPool::new(device, BASE).expect("pool");
        let mut samples = GpuSampleBuffer::new(device).expect("buffer");
        let expander = gpu.expander();
        let refused = gpu_pool.sync(
            device,
            queue,
            &listed,
            &PoolChange::Rebuilt,
            expander,
            &mut samples,
        );
        let e = refused.expect_err("sites placed elsewhere");
        assert!(e.to_string().contains("placed elsewhere"), "{e}");
        assert!(gpu_pool.is_empty() && samples.is_empty());
        let lod = SplatLod {
            base: BASE as f32,
            expanded: BASE as f32,
            reference: 4000.0,
            max: 8.0,
            cull_back_faces: true,
        };
        let (lo, hi) = s.mesh().bounds();
        let diagonal = (hi - lo).length();
        let (mut appended, mut reused) = (0, 0);
        let path = [(6.0, 0.3), (4.5, 0.3), (3.5, 0.3), (3.5, 0.6), (3.5, 0.9)];
        for (frame, &(distance, yaw)) in path.iter().enumerate() {
            let camera = OrbitCamera {
                target: Vec3::ZERO,
                distance,
                yaw,
                pitch: 0.5,
                fov_y: 40f32.to_radians(),
                radius: 2.0,
            };
            let view = lod.view(&camera, (320, 240));
            let update = pool
                .update(s, &view, Budget::Base(BASE))
                .expect("the pool's sampler");
            let change = listed.update(s, &view, Budget::Base(BASE)).expect("same");
            assert_eq!(change, update, "{name}, frame {frame}");
            assert_eq!(listed.ranks(), pool.ranks(), "{name}, frame {frame}");
            let change = change.change;
            let held = gpu_pool.len();
            let kept = gpu_pool.placing.as_ref().map(|(_, group)| group.clone());
            let bytes = gpu_pool
                .sync_placed(device, queue, (&listed, &change), &gpu, &mut samples)
                .expect("sync");
            // The kept bind groups bind the pool's buffers as they are now.
            let (bound, group) = gpu_pool.placing.as_ref().expect("placed");
            assert!(bound[2] == gpu_pool.ranks && bound[3] == gpu_pool.sites);
            let (bound, _) = gpu_pool.expanding.as_ref().expect("expanded");
            assert!(bound[1] == gpu_pool.sites && bound[3] == *samples.buffer());
            assert!(gpu_pool.checked, "{name}, frame {frame}");
            reused += usize::from(kept.as_ref() == Some(group));
            let sent = if frame == 0 {
                pool.len()
            } else {
                pool.len() - held
            };
            assert_eq!(bytes, sent as u64 * 4, "{name}, frame {frame}: ranks only");
            if frame > 0 && matches!(change, PoolChange::Appended(_)) {
                appended += sent;
            }
            let sites = gpu_pool.read_sites(device, queue).expect("read back");
            assert_eq!(sites.len(), pool.len());
            let (mut faces, mut beyond, mut worst) = (0, 0, 0.0f64);
            for (g, c) in sites.iter().zip(pool.sites()) {
                faces += usize::from(g.face != c.face || g.segment != c.segment);
                let at = |x: &SampleSite| x.position_on(s.mesh()).expect("a face of the mesh");
                let d = at(g).distance(at(c)) / diagonal;
                worst = worst.max(d);
                beyond += usize::from(d > 1e-5);
            }
            let n = sites.len();
            let _ = writeln!(
                std::io::stderr(),
                "{name}, frame {frame}: {n} entries, {faces} in another face, largest deviation {worst:.2e} ({beyond} beyond 1e-5)"
            );
            assert!(faces * 1000 <= n, "{name}, frame {frame}: {faces} of {n}");
            assert!(
                beyond * 10_000 <= n && worst <= 1e-4,
                "{name}, frame {frame}"
            );
            let records = samples.read_back(device, queue).expect("records");
            assert_eq!(records.len(), n);
            for (k, (r, site)) in records.iter().zip(&sites).enumerate().step_by(97) {
                assert_eq!((r.face, r.segment), (site.face, site.segment), "record {k}");
                let p = site.position_on(s.mesh()).expect("a face").as_vec3();
                let dist = Vec3::from(r.position).distance(p);
                assert!(dist <= 1e-5 * diagonal as f32, "record {k}: {dist}");
            }
        }
        assert!(
            appended > 1000,
            "{name}: the path appended {appended} entries"
        );
        // Some frame placed its entries with the bind group of the frame before.
        assert!(reused > 0, "{name}: every frame made its bind groups");
    }
}
