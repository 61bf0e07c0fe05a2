//! Whether a request's samples fit, checked before any work: sample indices are
//! 32-bit, so one request draws at most [`MAX_COUNT`]; paths that hold every sample in
//! memory (`strata bench`, `strata analyze`, `strata watch`, the ECS engine) need
//! [`SAMPLE_BYTES`] per sample of memory, and a samples file needs its size in free
//! space. The CLI adds the override flag to the message where it has one.

use std::path::Path;

use strata_engine::sample::Sample;

/// The most samples one request draws (sample indices are 32-bit).
pub const MAX_COUNT: u64 = 1 << 32;

/// Bytes of one sample record in memory (and in a binary PLY file).
pub const SAMPLE_BYTES: u64 = size_of::<Sample>() as u64;

/// What a request would run out of.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Resource {
    /// Memory (`MemAvailable` of `/proc/meminfo`).
    Memory,
    /// Free space of the file system an output goes to.
    Space,
}

/// A request that cannot fit.
#[derive(Debug, thiserror::Error, PartialEq)]
#[non_exhaustive]
pub enum BudgetError {
    /// More samples than one request can index.
    #[error(
        "at most 2^32 = {MAX_COUNT} samples per request (sample indices are 32-bit), asked for {count}"
    )]
    TooMany {
        /// The count asked for.
        count: u64,
    },
    /// More memory or space than there is.
    #[error(
        "{count} samples: {} needed and {} {}",
        gb(*needed),
        gb(*available),
        match resource { Resource::Memory => "of memory available", Resource::Space => "free there" }
    )]
    TooLarge {
        /// The count asked for.
        count: u64,
        /// Bytes it needs (a lower bound for text outputs).
        needed: u64,
        /// Bytes there are.
        available: u64,
        /// Of what.
        resource: Resource,
    },
    /// The system refused the allocation.
    #[error("{count} samples: could not allocate {}", gb(count.saturating_mul(SAMPLE_BYTES)))]
    OutOfMemory {
        /// The count asked for.
        count: u64,
    },
}

fn gb(bytes: u64) -> String {
    format!("{:.1} GB", bytes as f64 / 1e9)
}

/// Refuses counts above [`MAX_COUNT`].
pub fn check_count(count: u64) -> Result<(), BudgetError> {
    if count > MAX_COUNT {
        return Err(BudgetError::TooMany { count });
    }
    Ok(())
}

/// Refuses `count` samples of `bytes_per_sample` each (after [`check_count`]) where
/// `available` bytes of `resource` are fewer; an unknown `available` passes.
pub fn check_fits(
    count: u64,
    bytes_per_sample: u64,
    available: Option<u64>,
    resource: Resource,
) -> Result<(), BudgetError> {
    check_count(count)?;
    // At most 2^32 x a few hundred bytes: no overflow.
    within(count, count * bytes_per_sample, available, resource)
}

/// `TooLarge` where `needed` bytes for `count` samples exceed a known `available`.
fn within(
    count: u64,
    needed: u64,
    available: Option<u64>,
    resource: Resource,
) -> Result<(), BudgetError> {
    match available {
        Some(available) if needed > available => Err(BudgetError::TooLarge {
            count,
            needed,
            available,
            resource,
        }),
        _ => Ok(()),
    }
}

/// [`check_fits`] against the memory available now, for `count` in-memory samples.
pub fn check_memory(count: u64) -> Result<(), BudgetError> {
    check_fits(count, SAMPLE_BYTES, available_memory(), Resource::Memory)
}

/// Whether `samples` in-memory samples in all (several requests of at most
/// [`MAX_COUNT`] each, checked apart) fit in the memory available now.
pub fn check_memory_total(samples: u64) -> Result<(), BudgetError> {
    let needed = samples.saturating_mul(SAMPLE_BYTES);
    within(samples, needed, available_memory(), Resource::Memory)
}

/// Memory available to new allocations (Linux `MemAvailable`), in bytes; `None` where
/// it cannot be read.
pub fn available_memory() -> Option<u64> {
    let info = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = info.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    kib.checked_mul(1024)
}

/// The space the file system of `path`'s folder can still give to this user, in
/// bytes; `None` where it cannot be read.
pub fn available_space(path: &Path) -> Option<u64> {
    let folder = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let stat = rustix::fs::statvfs(folder).ok()?;
    stat.f_bavail.checked_mul(stat.f_frsize)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_beyond_indices_memory_or_space_are_refused() {
        assert_eq!(SAMPLE_BYTES, 64);
        assert!(check_count(MAX_COUNT).is_ok());
        let e = check_count(u64::MAX).expect_err("2^64 - 1");
        assert_eq!(
            e.to_string(),
            "at most 2^32 = 4294967296 samples per request (sample indices are 32-bit), asked for 18446744073709551615"
        );
        assert!(check_fits(10, 64, Some(640), Resource::Memory).is_ok());
        assert!(check_fits(10, 64, None, Resource::Memory).is_ok());
        let e =
            check_fits(100_000_000, 64, Some(2_000_000_000), Resource::Memory).expect_err("6.4 GB");
        assert_eq!(
            e.to_string(),
            "100000000 samples: 6.4 GB needed and 2.0 GB of memory available"
        );
        let e =
            check_fits(100_000_000, 64, Some(2_000_000_000), Resource::Space).expect_err("6.4 GB");
        assert_eq!(
            e.to_string(),
            "100000000 samples: 6.4 GB needed and 2.0 GB free there"
        );
        // The count is checked first, whatever the budget.
        assert!(matches!(
            check_fits(MAX_COUNT + 1, 1, None, Resource::Space),
            Err(BudgetError::TooMany { .. })
        ));
        assert!(available_memory().is_some_and(|m| m > 0));
        // Totals over several requests saturate instead of overflowing.
        assert!(matches!(
            check_memory_total(u64::MAX),
            Err(BudgetError::TooLarge {
                needed: u64::MAX,
                ..
            })
        ));
        assert!(check_memory_total(1).is_ok());
        assert!(available_space(Path::new("out.ply")).is_some_and(|a| a > 0));
        assert_eq!(
            available_space(Path::new("/nonexistent/folder/out.ply")),
            None
        );
    }
}
