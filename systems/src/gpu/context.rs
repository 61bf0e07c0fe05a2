//! Instance, adapter and device creation with typed errors, and error scopes that turn
//! wgpu validation errors into [`GpuError`]s instead of panics.
//!
//! The adapter is chosen from [`GpuOptions`]: the backends (default: `WGPU_BACKEND`,
//! else all compiled in: Vulkan and GL) and an optional adapter-name substring (default:
//! `WGPU_ADAPTER_NAME`), matched over `enumerate_adapters` ourselves because wgpu's own
//! helper panics when nothing matches.

use std::sync::{Arc, Mutex};

use wgpu::{Adapter, Backends, Device, Instance, Queue};

/// Errors of the GPU layer.
#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    /// No adapter for the requested backends (no driver, no device, or no backend).
    #[error(
        "no GPU adapter found for backends {backends} ({reason}); install a Vulkan driver (e.g. Debian's mesa-vulkan-drivers for the lavapipe software adapter) or set WGPU_BACKEND=gl"
    )]
    NoAdapter {
        /// The backends searched.
        backends: String,
        /// wgpu's explanation.
        reason: String,
    },
    /// No adapter's name contains the requested name.
    #[error("no GPU adapter named like {name:?}; available: {available}")]
    AdapterNotFound {
        /// The requested name (a case-insensitive substring).
        name: String,
        /// The adapters present, as `name (backend)`, comma separated.
        available: String,
    },
    /// The adapter refused to open a device.
    #[error("could not open a device on {adapter}: {source}")]
    RequestDevice {
        /// The adapter's name.
        adapter: String,
        /// wgpu's error.
        source: wgpu::RequestDeviceError,
    },
    /// wgpu reported a validation, out-of-memory or internal error during `operation`.
    #[error("GPU error while {operation}: {message}")]
    Device {
        /// What we were doing.
        operation: &'static str,
        /// wgpu's description.
        message: String,
    },
    /// Waiting for the device failed (device lost or timeout).
    #[error("GPU error while {operation}: {source}")]
    Poll {
        /// What we were doing.
        operation: &'static str,
        /// wgpu's error.
        source: wgpu::PollError,
    },
    /// Mapping a buffer for reading failed.
    #[error("GPU error while {operation}: could not map a buffer: {message}")]
    Map {
        /// What we were doing.
        operation: &'static str,
        /// wgpu's description.
        message: String,
    },
    /// Data that does not fit what the GPU side was built for (a deformed mesh with
    /// another vertex count, say).
    #[error("{what} does not match: {detail}")]
    Mismatch {
        /// What was given.
        what: &'static str,
        /// How it differs.
        detail: String,
    },
    /// A render target or upload larger than the device allows.
    #[error("{what} of {requested} exceeds the device limit of {limit}")]
    Limit {
        /// Which limit.
        what: &'static str,
        /// The size asked for.
        requested: u64,
        /// The device's limit.
        limit: u64,
    },
    /// A request the GPU sampler cannot draw from its tables.
    #[error("GPU sampling: {0}")]
    Sampling(#[from] strata_engine::sample::flat::FlatError),
}

/// Which adapter to open.
#[derive(Clone, Debug, Default)]
pub struct GpuOptions {
    /// Backends to search; `None`: `WGPU_BACKEND` if set, else every compiled-in one.
    pub backends: Option<Backends>,
    /// Case-insensitive substring of the adapter name; `None`: `WGPU_ADAPTER_NAME` if
    /// set, else the default adapter (wgpu's choice, a software one when it is alone).
    pub adapter_name: Option<String>,
}

/// An open device with its queue and where it came from.
#[derive(Debug)]
pub struct GpuContext {
    /// The instance (keeps the backends alive; makes window surfaces).
    pub instance: Instance,
    /// The adapter.
    pub adapter: Adapter,
    /// The device.
    pub device: Device,
    /// Its queue.
    pub queue: Queue,
    uncaptured: Arc<Mutex<Vec<String>>>,
}

/// Makes an instance for `options` (display-less; windows pass theirs to
/// [`GpuContext::with_instance`] through their own instance).
pub fn make_instance(options: &GpuOptions) -> Instance {
    let mut desc = wgpu::InstanceDescriptor::new_without_display_handle_from_env();
    if let Some(b) = options.backends {
        desc.backends = b;
    }
    Instance::new(desc)
}

fn backends_of(options: &GpuOptions) -> Backends {
    options
        .backends
        .unwrap_or_else(|| Backends::all().with_env())
}

impl GpuContext {
    /// Opens a device without a window (for `strata render`, tests and benchmarks).
    pub fn headless(options: &GpuOptions) -> Result<Self, GpuError> {
        let instance = make_instance(options);
        Self::with_instance(instance, options, None)
    }

    /// A headless device with the default options for a test or a check named `test`,
    /// or `None` after a line on stderr when no adapter opens (a machine without a GPU
    /// or a software adapter); panics instead when the environment sets
    /// `STRATA_REQUIRE_GPU=1`, so a machine that should have a GPU fails loudly.
    pub fn headless_or_skip(test: &str) -> Option<Self> {
        match Self::headless(&GpuOptions::default()) {
            Ok(ctx) => Some(ctx),
            Err(e) => {
                assert!(
                    std::env::var("STRATA_REQUIRE_GPU").as_deref() != Ok("1"),
                    "STRATA_REQUIRE_GPU=1 but no GPU adapter could be opened: {e}"
                );
                // Straight to the process's stderr: the test harness hides `eprintln!`.
                use std::io::Write;
                let _ = writeln!(std::io::stderr(), "skipping {test}: {e}");
                None
            }
        }
    }

    /// Picks an adapter on `instance` (compatible with `surface` if given) and opens a
    /// device on it.
    pub fn with_instance(
        instance: Instance,
        options: &GpuOptions,
        surface: Option<&wgpu::Surface<'_>>,
    ) -> Result<Self, GpuError> {
        let adapter = pick_adapter(&instance, options, surface)?;
        let info = adapter.get_info();
        // Software adapters offer the downlevel limits at least; take what the adapter
        // has so that large sample buffers fit.
        let limits = adapter.limits();
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("strata"),
            // Timestamps where the adapter has them (`strata bench --gpu` times the
            // passes with them); nothing else is optional.
            required_features: adapter.features() & wgpu::Features::TIMESTAMP_QUERY,
            required_limits: limits,
            ..Default::default()
        }))
        .map_err(|source| GpuError::RequestDevice {
            adapter: info.name.clone(),
            source,
        })?;
        // Errors outside our scopes are recorded, not panicked on (wgpu's default);
        // `take_uncaptured` reports them.
        let uncaptured = Arc::new(Mutex::new(Vec::new()));
        let sink = uncaptured.clone();
        device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
            if let Ok(mut v) = sink.lock() {
                v.push(e.to_string());
            }
        }));
        Ok(Self {
            instance,
            adapter,
            device,
            queue,
            uncaptured,
        })
    }

    /// The adapter's description: name, backend and device type.
    pub fn adapter_summary(&self) -> String {
        let info = self.adapter.get_info();
        format!(
            "{} ({:?}, {:?}, driver {} {})",
            info.name, info.backend, info.device_type, info.driver, info.driver_info
        )
    }

    /// The first error wgpu reported outside any error scope since the last call.
    pub fn take_uncaptured(&self, operation: &'static str) -> Result<(), GpuError> {
        let first = self
            .uncaptured
            .lock()
            .ok()
            .and_then(|mut v| (!v.is_empty()).then(|| v.remove(0)));
        match first {
            Some(message) => Err(GpuError::Device { operation, message }),
            None => Ok(()),
        }
    }

    /// Waits until the device has finished all submitted work.
    pub fn wait_idle(&self, operation: &'static str) -> Result<(), GpuError> {
        wait_idle(&self.device, operation)
    }
}

/// Waits until `device` has finished all submitted work.
pub fn wait_idle(device: &Device, operation: &'static str) -> Result<(), GpuError> {
    device
        .poll(wgpu::PollType::wait_indefinitely())
        .map(|_| ())
        .map_err(|source| GpuError::Poll { operation, source })
}

/// Runs `f` inside validation and out-of-memory error scopes on `device`: any error it
/// causes becomes [`GpuError::Device`] naming `operation`.
pub fn scoped<T>(
    device: &Device,
    operation: &'static str,
    f: impl FnOnce() -> T,
) -> Result<T, GpuError> {
    let oom = device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
    let validation = device.push_error_scope(wgpu::ErrorFilter::Validation);
    let value = f();
    let v = pollster::block_on(validation.pop());
    let o = pollster::block_on(oom.pop());
    match v.or(o) {
        Some(e) => Err(GpuError::Device {
            operation,
            message: e.to_string(),
        }),
        None => Ok(value),
    }
}

/// Chooses the adapter: by name among all adapters of the backends when a name is
/// given, else wgpu's default request.
pub fn pick_adapter(
    instance: &Instance,
    options: &GpuOptions,
    surface: Option<&wgpu::Surface<'_>>,
) -> Result<Adapter, GpuError> {
    let backends = backends_of(options);
    let name = options
        .adapter_name
        .clone()
        .or_else(|| std::env::var("WGPU_ADAPTER_NAME").ok())
        .filter(|n| !n.is_empty());
    if let Some(name) = name {
        let adapters = pollster::block_on(instance.enumerate_adapters(backends));
        let wanted = name.to_lowercase();
        let mut available = Vec::new();
        for adapter in adapters {
            let info = adapter.get_info();
            let compatible = surface.is_none_or(|s| adapter.is_surface_supported(s));
            if compatible && info.name.to_lowercase().contains(&wanted) {
                return Ok(adapter);
            }
            available.push(format!("{} ({:?})", info.name, info.backend));
        }
        return Err(GpuError::AdapterNotFound {
            name,
            available: if available.is_empty() {
                "none".into()
            } else {
                available.join(", ")
            },
        });
    }
    pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
        power_preference: wgpu::PowerPreference::HighPerformance,
        force_fallback_adapter: false,
        compatible_surface: surface,
        ..Default::default()
    }))
    .map_err(|e| GpuError::NoAdapter {
        backends: format!("{backends:?}"),
        reason: e.to_string(),
    })
}
