//! Growable GPU buffers refilled every frame through a ring of mapped staging chunks:
//! the buffer of [`Sample`]s the splats are drawn from ([`GpuSampleBuffer`]) and the sites
//! buffer of the expansion pass ([`super::expand`]), both a `StreamedBuffer`.
//!
//! Capacity policy: the buffer holds a power of two of samples, at least
//! [`MIN_CAPACITY`]. It grows to the next power of two at or above the request, and
//! shrinks (to the next power of two above the request) only when the request falls
//! below a quarter of the capacity, so a count oscillating around a power of two does
//! not reallocate every frame. Reallocating does not copy: every upload rewrites the
//! whole prefix in use.
//!
//! Uploads go through a `wgpu::util::StagingBelt`: a ring of `MAP_WRITE` chunks, each
//! re-mapped asynchronously once the GPU has consumed its copy. A frame takes a chunk
//! that is already mapped, or allocates a new one if all are still in flight, so the CPU
//! never waits for the GPU's previous frame; in steady state two or three chunks of the
//! buffer's size circulate. Cost per frame: one copy of `64 N` bytes into mapped memory
//! and one recorded buffer-to-buffer copy.

use strata_engine::sample::Sample;
use wgpu::util::StagingBelt;

use super::context::{GpuError, scoped};

/// The smallest capacity, in samples (64 KiB).
pub const MIN_CAPACITY: usize = 1024;

const SAMPLE_BYTES: u64 = std::mem::size_of::<Sample>() as u64;

/// The device buffer of samples that the splat pipeline reads at instance rate: the
/// render-side copy of the ECS's [`SampleBuffer`](crate::ecs::SampleBuffer).
#[derive(Debug)]
pub struct GpuSampleBuffer {
    inner: StreamedBuffer,
}

/// The capacity that [`GpuSampleBuffer`] chooses for `count` samples when it currently
/// holds `capacity` (see the module documentation).
pub fn next_capacity(capacity: usize, count: usize) -> usize {
    let fit = count.max(MIN_CAPACITY).next_power_of_two();
    if count > capacity || count < capacity / 4 {
        fit
    } else {
        capacity
    }
}

/// The most samples one buffer can hold on `device` (its `max_buffer_size`, with room
/// for the power-of-two capacity policy).
pub fn max_samples(device: &wgpu::Device) -> usize {
    let bytes = device.limits().max_buffer_size;
    let fit = usize::try_from(bytes / SAMPLE_BYTES).unwrap_or(usize::MAX);
    // Capacities are powers of two: the largest one that fits.
    if fit == 0 {
        0
    } else {
        1usize << (usize::BITS - 1 - fit.leading_zeros())
    }
}

/// What a [`StreamedBuffer`] is for (labels and error texts), the size of one item,
/// the largest size the device allows for its use, and its usages.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Streamed {
    /// wgpu label.
    pub label: &'static str,
    /// The limit's name in a [`GpuError::Limit`].
    pub what: &'static str,
    /// The operation in a [`GpuError::Device`] when allocating.
    pub operation: &'static str,
    /// Bytes per item.
    pub item_bytes: u64,
    /// The largest buffer size the device allows for this use, bytes.
    pub limit: u64,
    /// Usages (`COPY_DST` is added for the belt's copies).
    pub usage: wgpu::BufferUsages,
}

/// A device buffer of items rewritten every frame through its own staging belt, with
/// the capacity policy of the module documentation: the sample buffer and the sites
/// buffer of the expansion pass.
#[derive(Debug)]
pub(crate) struct StreamedBuffer {
    spec: Streamed,
    buffer: wgpu::Buffer,
    belt: StagingBelt,
    capacity: usize,
    len: usize,
    reallocations: usize,
}

impl StreamedBuffer {
    /// An empty buffer of [`MIN_CAPACITY`] items.
    pub(crate) fn new(device: &wgpu::Device, spec: Streamed) -> Result<Self, GpuError> {
        let (buffer, belt) = Self::allocate(device, &spec, MIN_CAPACITY)?;
        Ok(Self {
            spec,
            buffer,
            belt,
            capacity: MIN_CAPACITY,
            len: 0,
            reallocations: 0,
        })
    }

    /// A buffer of `capacity` items and a staging belt whose chunk holds a whole
    /// frame's upload (a new belt per capacity drops chunks too small for the new size;
    /// wgpu frees them once the GPU is done), or a typed error over the limit.
    fn allocate(
        device: &wgpu::Device,
        spec: &Streamed,
        capacity: usize,
    ) -> Result<(wgpu::Buffer, StagingBelt), GpuError> {
        let bytes = capacity as u64 * spec.item_bytes;
        if bytes > spec.limit {
            return Err(GpuError::Limit {
                what: spec.what,
                requested: bytes,
                limit: spec.limit,
            });
        }
        let buffer = scoped(device, spec.operation, || {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(spec.label),
                size: bytes,
                usage: spec.usage | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        })?;
        Ok((buffer, StagingBelt::new(device.clone(), bytes)))
    }

    /// Makes the buffer hold `len` items without writing them, reallocating first when
    /// the capacity policy says so (a reallocated buffer's contents are undefined).
    pub(crate) fn resize(&mut self, device: &wgpu::Device, len: usize) -> Result<(), GpuError> {
        let capacity = next_capacity(self.capacity, len);
        if capacity != self.capacity {
            let (buffer, belt) = Self::allocate(device, &self.spec, capacity)?;
            self.buffer = buffer;
            self.belt = belt;
            self.capacity = capacity;
            self.reallocations += 1;
        }
        self.len = len;
        Ok(())
    }

    /// Resizes to `items.len()` items and records their copy into `encoder`, after
    /// recycling staging chunks whose copies have finished (without blocking). `false`
    /// when there is nothing to copy. Call [`submit`](Self::submit) with the encoder.
    pub(crate) fn write<T: bytemuck::Pod>(
        &mut self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        items: &[T],
    ) -> Result<bool, GpuError> {
        debug_assert_eq!(std::mem::size_of::<T>() as u64, self.spec.item_bytes);
        self.resize(device, items.len())?;
        let Some(size) = wgpu::BufferSize::new(self.bytes()) else {
            return Ok(false);
        };
        device
            .poll(wgpu::PollType::Poll)
            .map_err(|source| GpuError::Poll {
                operation: "recycling staging memory",
                source,
            })?;
        let mut view = self.belt.write_buffer(encoder, &self.buffer, 0, size);
        view.copy_from_slice(bytemuck::cast_slice(items));
        Ok(true)
    }

    /// Submits `encoder` (holding this buffer's copy) and returns the staging chunks
    /// to the ring once the GPU has consumed them.
    pub(crate) fn submit(&mut self, queue: &wgpu::Queue, encoder: wgpu::CommandEncoder) {
        self.belt.finish();
        queue.submit([encoder.finish()]);
        self.belt.recall();
    }

    /// The device buffer (`capacity` items; the first `len` are current).
    pub(crate) fn buffer(&self) -> &wgpu::Buffer {
        &self.buffer
    }

    /// Bytes of the current items.
    pub(crate) fn bytes(&self) -> u64 {
        self.len as u64 * self.spec.item_bytes
    }
}

impl GpuSampleBuffer {
    /// An empty buffer of [`MIN_CAPACITY`] samples.
    pub fn new(device: &wgpu::Device) -> Result<Self, GpuError> {
        let spec = Streamed {
            label: "strata samples",
            what: "sample buffer size (bytes)",
            operation: "allocating the sample buffer",
            item_bytes: SAMPLE_BYTES,
            limit: device.limits().max_buffer_size,
            usage: wgpu::BufferUsages::VERTEX
                | wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_SRC,
        };
        Ok(Self {
            inner: StreamedBuffer::new(device, spec)?,
        })
    }

    /// Replaces the contents with `samples`, growing or shrinking the buffer first when
    /// the capacity policy says so. Records the copy into a new command buffer and
    /// submits it; draws submitted afterwards see the new samples.
    pub fn upload(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        samples: &[Sample],
    ) -> Result<(), GpuError> {
        scoped(device, "uploading samples", || {
            let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("strata sample upload"),
            });
            if self.inner.write(device, &mut encoder, samples)? {
                self.inner.submit(queue, encoder);
            }
            Ok(())
        })?
    }

    /// Makes the buffer hold `len` samples without writing them, growing or shrinking
    /// it first when the capacity policy says so (a reallocated buffer's contents are
    /// undefined): for a GPU pass that writes the samples itself, such as
    /// [`SiteExpander::expand`](super::expand::SiteExpander::expand).
    pub fn resize(&mut self, device: &wgpu::Device, len: usize) -> Result<(), GpuError> {
        self.inner.resize(device, len)
    }

    /// The device buffer (capacity samples; the first [`len`](Self::len) are current).
    pub fn buffer(&self) -> &wgpu::Buffer {
        self.inner.buffer()
    }

    /// Samples held: those of the last [`upload`](Self::upload) or
    /// [`resize`](Self::resize).
    pub fn len(&self) -> usize {
        self.inner.len
    }

    /// Whether the last upload was empty.
    pub fn is_empty(&self) -> bool {
        self.inner.len == 0
    }

    /// Samples the buffer can hold without reallocating.
    pub fn capacity(&self) -> usize {
        self.inner.capacity
    }

    /// How many times the buffer was reallocated (grown or shrunk) since creation.
    pub fn reallocations(&self) -> usize {
        self.inner.reallocations
    }

    /// Copies the current samples back from the GPU (waits for the device; for tests and
    /// debugging, not for the frame loop).
    pub fn read_back(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> Result<Vec<Sample>, GpuError> {
        let bytes = read_buffer(device, queue, self.inner.buffer(), self.inner.bytes())?;
        Ok(bytemuck::pod_collect_to_vec(&bytes))
    }
}

/// Copies the first `size` bytes of `buffer` (which needs `COPY_SRC`) into a mapped
/// readback buffer and returns them. Waits for the device.
pub(crate) fn read_buffer(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    buffer: &wgpu::Buffer,
    size: u64,
) -> Result<Vec<u8>, GpuError> {
    const OP: &str = "reading a buffer back";
    if size == 0 {
        return Ok(Vec::new());
    }
    let readback = scoped(device, OP, || {
        let readback = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("strata readback"),
            size,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut encoder = device.create_command_encoder(&Default::default());
        encoder.copy_buffer_to_buffer(buffer, 0, &readback, 0, size);
        queue.submit([encoder.finish()]);
        readback
    })?;
    map_read(device, &readback, OP)
}

/// Maps all of `buffer` (`MAP_READ`, with its copies submitted) and returns its bytes.
pub(crate) fn map_read(
    device: &wgpu::Device,
    buffer: &wgpu::Buffer,
    operation: &'static str,
) -> Result<Vec<u8>, GpuError> {
    let (tx, rx) = std::sync::mpsc::channel();
    buffer.map_async(wgpu::MapMode::Read, .., move |r| {
        // The receiver outlives the poll below; a send error only means we gave up.
        let _ = tx.send(r);
    });
    super::context::wait_idle(device, operation)?;
    match rx.try_recv() {
        Ok(Ok(())) => {}
        Ok(Err(e)) => {
            return Err(GpuError::Map {
                operation,
                message: e.to_string(),
            });
        }
        Err(_) => {
            return Err(GpuError::Map {
                operation,
                message: "the map callback did not run after waiting for the device".into(),
            });
        }
    }
    let bytes = buffer
        .get_mapped_range(..)
        .map_err(|e| GpuError::Map {
            operation,
            message: e.to_string(),
        })?
        .to_vec();
    buffer.unmap();
    Ok(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn capacity_grows_geometrically_and_shrinks_with_hysteresis() {
        assert_eq!(next_capacity(MIN_CAPACITY, 0), MIN_CAPACITY);
        assert_eq!(next_capacity(MIN_CAPACITY, 1000), MIN_CAPACITY);
        assert_eq!(next_capacity(MIN_CAPACITY, 1025), 2048);
        assert_eq!(next_capacity(2048, 100_000), 131_072);
        // Within [capacity / 4, capacity]: kept.
        assert_eq!(next_capacity(131_072, 131_072), 131_072);
        assert_eq!(next_capacity(131_072, 32_768), 131_072);
        // Below a quarter: shrunk to fit.
        assert_eq!(next_capacity(131_072, 32_767), 32_768);
        assert_eq!(next_capacity(131_072, 10), MIN_CAPACITY);
    }
}
