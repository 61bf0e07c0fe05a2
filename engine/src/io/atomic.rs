//! Atomic file writing: a reader of the target sees the old file or the whole new one,
//! never a part, and a failed write leaves the old file as it was.
//!
//! Input: a target path and a closure that writes the content. Output: the target
//! replaced, or the closure's (or the file system's) error with the target untouched.
//! Cost: the write itself through a [`BufWriter`], one `fsync` and one rename.
//!
//! [`write_atomically`] creates a new temporary file in the target's folder (renames
//! are atomic only within one file system), named `.<name>.<pid>.<nanos>.<try>.tmp`
//! and opened with `create_new`: the process id and the clock keep writers in different
//! processes apart, and a name that exists already (two writers in one process at the
//! same instant) is retried with the next `<try>`, so two writes never share a
//! temporary file and no process-global state is needed. The content is flushed and
//! synced to disk before the rename, so that a crash right after it cannot leave an
//! empty or partial target. The temporary file is removed on every error, and on a
//! panic in the closure.

use std::fs::File;
use std::io::{self, BufWriter};
use std::path::{Path, PathBuf};
use std::time::{SystemTime, UNIX_EPOCH};

/// How many temporary names are tried before giving up (each collision needs another
/// writer that picked the same pid, instant and try number).
const MAX_TRIES: u32 = 64;

/// Characters of the target's file name kept in the temporary name (the rest of a
/// very long name is left out, so that the temporary name stays a valid name).
const NAME_CHARS: usize = 64;

/// Writes a file atomically: runs `write` on a buffered temporary file in `path`'s
/// folder, syncs it and renames it over `path`, so that a reader sees the old file or
/// the whole new one. The temporary file is `.<name>.<pid>.<nanos>.<try>.tmp`, created
/// with `create_new` (a name taken by another writer is retried with the next `<try>`),
/// so concurrent writes never share one. On any error (of `write`, of creating,
/// flushing, syncing or renaming) or a panic in `write`, the temporary file is removed
/// and `path` keeps its old content (or stays absent); the error is returned, file-system
/// errors as `E::from(io::Error)`.
///
/// ```
/// use std::io::Write;
/// use strata_engine::io::write_atomically;
/// let dir = tempfile::tempdir()?;
/// let path = dir.path().join("numbers.txt");
/// write_atomically(&path, |w| writeln!(w, "1 2 3"))?;
/// assert_eq!(std::fs::read_to_string(&path)?, "1 2 3\n");
/// // A failing writer leaves the old file.
/// let failed = write_atomically(&path, |w| {
///     write!(w, "4 5")?;
///     Err::<(), _>(std::io::Error::other("out of numbers"))
/// });
/// assert!(failed.is_err());
/// assert_eq!(std::fs::read_to_string(&path)?, "1 2 3\n");
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn write_atomically<T, E: From<io::Error>>(
    path: &Path,
    write: impl FnOnce(&mut BufWriter<File>) -> Result<T, E>,
) -> Result<T, E> {
    let (file, temporary) = create_temporary(path)?;
    let mut w = BufWriter::new(file);
    let value = write(&mut w)?;
    let file = w.into_inner().map_err(io::IntoInnerError::into_error)?;
    file.sync_all()?;
    drop(file);
    std::fs::rename(&temporary.path, path)?;
    temporary.keep();
    Ok(value)
}

/// A temporary file that is removed when dropped, unless kept (renamed away).
struct Temporary {
    path: PathBuf,
    armed: bool,
}

impl Temporary {
    /// The file was renamed over its target: nothing to remove.
    fn keep(mut self) {
        self.armed = false;
    }
}

impl Drop for Temporary {
    fn drop(&mut self) {
        if self.armed {
            // Best effort: the error being returned is the one that matters.
            let _ = std::fs::remove_file(&self.path);
        }
    }
}

/// Creates a new temporary file beside `path` (see the module docs for the name).
fn create_temporary(path: &Path) -> io::Result<(File, Temporary)> {
    let nanos = SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |d| d.as_nanos());
    create_temporary_at(path, nanos)
}

/// [`create_temporary`] at the clock reading `nanos`.
fn create_temporary_at(path: &Path, nanos: u128) -> io::Result<(File, Temporary)> {
    let name = path.file_name().ok_or_else(|| {
        io::Error::new(
            io::ErrorKind::InvalidInput,
            format!("{}: not a file path", path.display()),
        )
    })?;
    let name: String = name.to_string_lossy().chars().take(NAME_CHARS).collect();
    let folder = path.parent().unwrap_or(Path::new(""));
    let pid = std::process::id();
    let mut last = None;
    for attempt in 0..MAX_TRIES {
        let candidate = folder.join(format!(".{name}.{pid}.{nanos}.{attempt}.tmp"));
        match File::create_new(&candidate) {
            Ok(file) => {
                let temporary = Temporary {
                    path: candidate,
                    armed: true,
                };
                return Ok((file, temporary));
            }
            Err(e) if e.kind() == io::ErrorKind::AlreadyExists => last = Some(e),
            Err(e) => return Err(e),
        }
    }
    Err(last.unwrap_or_else(|| io::Error::from(io::ErrorKind::AlreadyExists)))
}

#[cfg(test)]
mod tests {
    use std::io::Write;

    use super::*;

    /// The names in `dir`, sorted.
    fn names(dir: &Path) -> Vec<String> {
        let mut names: Vec<String> = std::fs::read_dir(dir)
            .expect("read dir")
            .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        names
    }

    #[test]
    fn replaces_the_target_whole() {
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("out.txt");
        std::fs::write(&path, "a much longer old content than the new one").expect("write");
        let n = write_atomically(&path, |w| {
            // While writing, the old target is intact and the temporary file sits
            // beside it, hidden, named after it.
            assert_eq!(
                std::fs::read_to_string(&path).expect("read"),
                "a much longer old content than the new one"
            );
            let during = names(dir.path());
            assert_eq!(during.len(), 2, "{during:?}");
            assert!(
                during[0].starts_with(".out.txt.") && during[0].ends_with(".tmp"),
                "{during:?}"
            );
            w.write_all(b"new")?;
            Ok::<_, io::Error>(3)
        })
        .expect("write");
        assert_eq!(n, 3);
        assert_eq!(std::fs::read_to_string(&path).expect("read"), "new");
        assert_eq!(names(dir.path()), ["out.txt"]);
        // A target that did not exist is created.
        let fresh = dir.path().join("fresh");
        write_atomically(&fresh, |w| w.write_all(b"x")).expect("write");
        assert_eq!(std::fs::read(&fresh).expect("read"), b"x");
    }

    #[test]
    fn an_error_in_the_writer_keeps_the_old_target_and_leaves_no_temporary() {
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("keep.ply");
        std::fs::write(&path, "old").expect("write");
        let e = write_atomically(&path, |w| -> io::Result<()> {
            w.write_all(&[7u8; 100_000])?; // more than the buffer: part reaches the file
            Err(io::Error::other("disk on fire"))
        })
        .expect_err("the writer failed");
        assert_eq!(e.to_string(), "disk on fire");
        assert_eq!(std::fs::read_to_string(&path).expect("read"), "old");
        assert_eq!(names(dir.path()), ["keep.ply"]);
        // Absent before, absent after.
        let absent = dir.path().join("absent.csv");
        let _ = write_atomically(&absent, |_| Err::<(), _>(io::Error::other("no")));
        assert!(!absent.exists());
        assert_eq!(names(dir.path()), ["keep.ply"]);
    }

    #[test]
    fn a_panic_in_the_writer_leaves_no_temporary() {
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("p.txt");
        let caught = std::panic::catch_unwind(|| {
            let _ = write_atomically(&path, |_| -> io::Result<()> { panic!("writer bug") });
        });
        assert!(caught.is_err());
        assert!(names(dir.path()).is_empty());
    }

    #[test]
    fn file_system_errors_name_their_cause() {
        let dir = tempfile::tempdir().expect("tempdir");
        let missing = dir.path().join("no/such/folder/x.txt");
        let e = write_atomically(&missing, |w| w.write_all(b"x")).expect_err("no folder");
        assert_eq!(e.kind(), io::ErrorKind::NotFound);
        let e = write_atomically(Path::new("/"), |w| w.write_all(b"x")).expect_err("no name");
        assert_eq!(e.kind(), io::ErrorKind::InvalidInput);
        // Renaming a file over a folder fails; the temporary file is removed.
        let folder = dir.path().join("folder");
        std::fs::create_dir(&folder).expect("mkdir");
        std::fs::write(folder.join("inside"), "x").expect("write");
        assert!(write_atomically(&folder, |w| w.write_all(b"x")).is_err());
        assert_eq!(names(dir.path()), ["folder"]);
    }

    #[test]
    fn concurrent_writes_to_one_folder_do_not_collide() {
        let dir = tempfile::tempdir().expect("tempdir");
        let shared = dir.path().join("shared.txt");
        std::thread::scope(|s| {
            for t in 0..8u8 {
                let (dir, shared) = (dir.path(), &shared);
                s.spawn(move || {
                    for k in 0..25u8 {
                        // Each writer's content is long and its own, so that a shared
                        // temporary file would show up as mixed bytes.
                        let content = vec![b'a' + t; 20_000 + usize::from(k)];
                        write_atomically(shared, |w| w.write_all(&content)).expect("shared");
                        let own = dir.join(format!("own-{t}.txt"));
                        write_atomically(&own, |w| w.write_all(&content)).expect("own");
                        assert_eq!(std::fs::read(&own).expect("read"), content);
                    }
                });
            }
        });
        let last = std::fs::read(&shared).expect("read");
        assert!(last.len() >= 20_000 && last.iter().all(|&b| b == last[0]));
        let mut want: Vec<String> = (0..8).map(|t| format!("own-{t}.txt")).collect();
        want.push("shared.txt".to_owned());
        assert_eq!(names(dir.path()), want);
    }

    #[test]
    fn a_taken_temporary_name_is_retried() {
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("t.txt");
        let (_first, a) = create_temporary_at(&path, 42).expect("first");
        let (_second, b) = create_temporary_at(&path, 42).expect("second");
        let pid = std::process::id();
        assert_eq!(a.path, dir.path().join(format!(".t.txt.{pid}.42.0.tmp")));
        assert_eq!(b.path, dir.path().join(format!(".t.txt.{pid}.42.1.tmp")));
        drop((a, b));
        assert!(names(dir.path()).is_empty());
        // A very long name is shortened in the temporary name.
        let long = dir.path().join("n".repeat(250));
        write_atomically(&long, |w| w.write_all(b"x")).expect("long name");
        assert_eq!(names(dir.path()), ["n".repeat(250)]);
    }
}
