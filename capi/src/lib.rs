//! # strata-capi
//!
//! strata's C API, for hosts that load native code through a C ABI (C and C++
//! engines, C# through P/Invoke). The header is `capi/include/strata.h`, generated from
//! this crate by cbindgen (`capi/cbindgen.toml`; `tests/header.rs` fails when the
//! checked-in header differs from a fresh generation). `docs/c-api.md` is the guide.
//!
//! - Opaque handles: `StrataMesh`, `StrataField` ([`mesh`]), `StrataBuild`
//!   ([`build`]), `StrataSampler` ([`sample`]), `StrataLod` ([`lod`]). Each is made by
//!   a `strata_*` function into an out-pointer and freed by its `strata_*_free`; a
//!   freed or mistyped handle is refused with `STRATA_STATUS_INVALID_HANDLE`.
//! - Every function returns a [`StrataStatus`]; on failure `strata_last_error()` holds a
//!   one-line message (thread-local) with the engine's text. No panic crosses the
//!   boundary: one is caught and returned as `STRATA_STATUS_PANIC`.
//! - Option structs begin with `struct_size` (`sizeof` the struct as the host compiled
//!   it), and [`strata_version`] says which library is loaded, so a host built against
//!   another header is refused instead of misread.
//!
//! Cost: an entry point adds a registry look-up per handle and a `catch_unwind` to
//! the engine call it makes (tens of nanoseconds; `docs/c-api.md` has measurements).

pub mod build;
mod handle;
pub mod lod;
pub mod mesh;
pub mod sample;

use std::ffi::c_char;

pub use handle::StrataStatus;

/// The API version this library implements: `major * 10000 + minor * 100 + patch`.
/// Hosts compare it with the header's `STRATA_API_VERSION`; the major part changes
/// when a function or struct changes incompatibly.
pub const STRATA_API_VERSION: u32 = 100;

/// The version of the loaded library (`STRATA_API_VERSION` of its header).
#[unsafe(no_mangle)]
#[allow(unsafe_code)] // `no_mangle` exports the symbol; nothing unsafe runs.
pub extern "C" fn strata_version() -> u32 {
    STRATA_API_VERSION
}

/// This thread's last error message: NUL-terminated UTF-8, owned by the library,
/// valid until this thread's next failing call (empty when none failed).
#[unsafe(no_mangle)]
#[allow(unsafe_code)] // `no_mangle` exports the symbol; nothing unsafe runs.
pub extern "C" fn strata_last_error() -> *const c_char {
    handle::guard_value(c"".as_ptr(), handle::last_error_ptr)
}

/// Makes the calling thread (a host's frame thread) a worker of the thread pool that
/// sampling and level-of-detail updates run on, beside one worker per core, and
/// writes the pool's thread count into `threads` (may be null). Call it once, on the
/// thread that will call `strata_sample`, before any other `strata_` call that
/// computes: parallel work then starts on that thread at once instead of waking a
/// sleeping worker (1-2 ms on a small machine), and sampling calls allocate nothing
/// (from another thread, each call hands its work to the pool through a queue that
/// allocates a block every 63 calls). `STRATA_STATUS_INVALID_ARGUMENT` when the pool
/// exists already (it then serves unchanged).
///
/// # Safety
/// `threads` is null or writable.
#[unsafe(no_mangle)]
#[allow(unsafe_code)] // `no_mangle` exports the symbol; the pointer goes to `write_out`.
pub unsafe extern "C" fn strata_join_thread_pool(threads: *mut usize) -> StrataStatus {
    handle::guard(|| {
        let count = strata_systems::frame_thread::join_rayon_pool().map_err(|e| {
            handle::Failure::new(
                StrataStatus::InvalidArgument,
                format!("thread pool: {e} (call strata_join_thread_pool first, once)"),
            )
        })?;
        if !threads.is_null() {
            handle::write_out(threads, count, "threads")?;
        }
        Ok(())
    })
}
