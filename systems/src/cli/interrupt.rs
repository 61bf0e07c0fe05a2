//! Ctrl-C (SIGINT) and SIGTERM while `strata sample` writes its file: the write stops
//! at the next block of samples and the half-written temporary file is removed, so an
//! interrupted run leaves the old output (or none) and no `.<name>.<random>.tmp`
//! behind. Outside a write the signal ends the process at once (status 130, as a shell
//! reports an interrupted command), since there is nothing to clean up; a second
//! signal during a write does too.
//!
//! Input: the signal, and [`check`] called between blocks. Output: an
//! [`std::io::ErrorKind::Interrupted`] error out of the writer, which the atomic writer
//! answers by removing its temporary file. Cost: one atomic load per block.

use std::io;
use std::sync::atomic::{AtomicU8, Ordering};

/// No write under way: a signal exits at once.
const IDLE: u8 = 0;
/// A write is under way: a signal asks it to stop.
const WRITING: u8 = 1;
/// A signal came during a write; the write stops at its next block.
const STOPPING: u8 = 2;

static STATE: AtomicU8 = AtomicU8::new(IDLE);

/// The exit status of an interrupted command (128 + SIGINT).
pub const INTERRUPTED_STATUS: u8 = 130;

/// Installs the handler (once per process; a second call, or a handler installed by
/// someone else, leaves the default behaviour, which only risks a leftover temporary
/// file).
pub fn install() {
    let _ = ctrlc::set_handler(|| {
        if STATE
            .compare_exchange(WRITING, STOPPING, Ordering::SeqCst, Ordering::SeqCst)
            .is_err()
        {
            std::process::exit(i32::from(INTERRUPTED_STATUS));
        }
    });
}

/// Marks a write as under way until the guard is dropped.
pub fn writing() -> Writing {
    STATE.store(WRITING, Ordering::SeqCst);
    Writing
}

/// While it lives, a signal stops the write (see [`check`]) instead of the process.
pub struct Writing;

impl Drop for Writing {
    fn drop(&mut self) {
        STATE.store(IDLE, Ordering::SeqCst);
    }
}

/// `Err(Interrupted)` once a signal asked the write to stop.
pub fn check() -> io::Result<()> {
    if STATE.load(Ordering::SeqCst) == STOPPING {
        Err(io::Error::new(io::ErrorKind::Interrupted, "interrupted"))
    } else {
        Ok(())
    }
}

/// Whether `error` is a write stopped by a signal.
pub fn is_interrupted(error: &anyhow::Error) -> bool {
    error.chain().any(|cause| {
        cause
            .downcast_ref::<io::Error>()
            .is_some_and(|e| e.kind() == io::ErrorKind::Interrupted)
    })
}
