//! Atomic file writing: a reader of the target sees the old file or the whole new one,
//! never a part, and a failed write leaves the old file as it was.
//!
//! Input: a target path and a closure that writes the content. Output: the target
//! replaced, or the closure's (or the file system's) error with the target untouched.
//! Cost: the write itself through a [`BufWriter`], one `fsync` and one rename.
//!
//! [`write_atomically`] creates a new temporary file in the target's folder (renames
//! are atomic only within one file system) with `tempfile`, named
//! `.<name>.<random>.tmp` and opened exclusively: a name that exists already (another
//! writer, in this process or another, picked the same random part) is retried with
//! new random characters, so two writes never share a temporary file and no
//! process-global state is needed. The content is flushed and synced to disk
//! (`sync_all`) before the temporary file is persisted (renamed) over the target, so
//! that a crash right after it cannot leave an empty or partial target. The temporary
//! file is removed on every error, and on a panic in the closure.
//!
//! Two targets are not replaced: one that exists and is not a regular file (a device
//! such as `/dev/stdout` or `/dev/null`, a named pipe) is opened and written in place,
//! since a rename would put a file where the device or pipe was (and needs a writable
//! folder, which `/dev` is not for most users); and a symbolic link to a file has the
//! file it points to replaced, so that the link stays a link.

use std::fs::File;
use std::io::{self, BufWriter};
use std::path::Path;

use tempfile::{NamedTempFile, TempPath};

/// Characters of the target's file name kept in the temporary name (the rest of a
/// very long name is left out, so that the temporary name stays a valid name).
const NAME_CHARS: usize = 64;

/// Writes a file atomically: runs `write` on a buffered temporary file in `path`'s
/// folder, syncs it and renames it over `path`, so that a reader sees the old file or
/// the whole new one. The temporary file is `.<name>.<random>.tmp`, created
/// exclusively (a name taken by another writer is retried with other random
/// characters), so concurrent writes never share one. On any error (of `write`, of
/// creating, flushing, syncing or renaming) or a panic in `write`, the temporary file
/// is removed and `path` keeps its old content (or stays absent); the error is
/// returned, file-system errors as `E::from(io::Error)`. A target that exists and is
/// not a regular file or a folder (a device, a named pipe) is written in place instead,
/// and a link to a file replaces the file it points to (see the module docs).
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
    if std::fs::metadata(path).is_ok_and(|m| !m.is_file() && !m.is_dir()) {
        return write_in_place(path, write);
    }
    let linked = std::fs::symlink_metadata(path)
        .is_ok_and(|m| m.file_type().is_symlink())
        .then(|| std::fs::canonicalize(path).ok())
        .flatten();
    let path = linked.as_deref().unwrap_or(path);
    // The path is removed when dropped: on every return before the rename, and on a
    // panic in `write`.
    let (file, temporary) = create_temporary(path)?.into_parts();
    let mut w = BufWriter::new(file);
    let value = write(&mut w)?;
    let file = w.into_inner().map_err(io::IntoInnerError::into_error)?;
    file.sync_all()?;
    drop(file);
    persist(temporary, path)?;
    Ok(value)
}

/// Writes a device or named pipe `path` in place: opened for writing (not created),
/// buffered and flushed; no sync, which devices and pipes need not support.
fn write_in_place<T, E: From<io::Error>>(
    path: &Path,
    write: impl FnOnce(&mut BufWriter<File>) -> Result<T, E>,
) -> Result<T, E> {
    let file = std::fs::OpenOptions::new().write(true).open(path)?;
    let mut w = BufWriter::new(file);
    let value = write(&mut w)?;
    w.into_inner().map_err(io::IntoInnerError::into_error)?;
    Ok(value)
}

/// Renames `temporary` over `path`; on failure the temporary file is removed.
fn persist(temporary: TempPath, path: &Path) -> io::Result<()> {
    temporary.persist(path).map_err(|e| e.error)
}

/// Creates a new temporary file beside `path` (see the module docs for the name).
fn create_temporary(path: &Path) -> io::Result<NamedTempFile> {
    let name = path.file_name().ok_or_else(|| {
        io::Error::new(
            io::ErrorKind::InvalidInput,
            format!("{}: not a file path", path.display()),
        )
    })?;
    let name: String = name.to_string_lossy().chars().take(NAME_CHARS).collect();
    let folder = path.parent().unwrap_or(Path::new(""));
    tempfile::Builder::new()
        .prefix(&format!(".{name}."))
        .suffix(".tmp")
        .tempfile_in(folder)
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
    fn a_named_pipe_is_written_in_place() {
        let dir = tempfile::tempdir().expect("tempdir");
        let fifo = dir.path().join("pipe");
        let made = std::process::Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .expect("mkfifo");
        assert!(made.success());
        let reader = {
            let fifo = fifo.clone();
            std::thread::spawn(move || std::fs::read(&fifo).expect("read the pipe"))
        };
        write_atomically(&fifo, |w| w.write_all(b"through the pipe")).expect("write");
        assert_eq!(reader.join().expect("reader"), b"through the pipe");
        // Still a pipe, and nothing else appeared beside it.
        use std::os::unix::fs::FileTypeExt;
        assert!(
            std::fs::metadata(&fifo)
                .expect("meta")
                .file_type()
                .is_fifo()
        );
        assert_eq!(names(dir.path()), ["pipe"]);
        // A device: /dev/null takes the bytes and stays a device.
        write_atomically(Path::new("/dev/null"), |w| w.write_all(b"gone")).expect("null");
        assert!(!std::fs::metadata("/dev/null").expect("meta").is_file());
    }

    #[test]
    fn a_link_to_a_file_stays_a_link() {
        let dir = tempfile::tempdir().expect("tempdir");
        let target = dir.path().join("target.txt");
        let link = dir.path().join("link.txt");
        std::fs::write(&target, "old").expect("write");
        std::os::unix::fs::symlink(&target, &link).expect("symlink");
        write_atomically(&link, |w| w.write_all(b"new")).expect("write");
        assert!(
            std::fs::symlink_metadata(&link)
                .expect("meta")
                .file_type()
                .is_symlink()
        );
        assert_eq!(std::fs::read_to_string(&target).expect("read"), "new");
        assert_eq!(names(dir.path()), ["link.txt", "target.txt"]);
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
    fn temporaries_beside_one_target_get_their_own_names() {
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("t.txt");
        let a = create_temporary(&path).expect("first");
        let b = create_temporary(&path).expect("second");
        assert_ne!(a.path(), b.path());
        for t in [&a, &b] {
            assert_eq!(t.path().parent(), Some(dir.path()));
            let name = t.path().file_name().expect("name").to_string_lossy();
            assert!(
                name.starts_with(".t.txt.") && name.ends_with(".tmp"),
                "{name}"
            );
        }
        drop((a, b));
        assert!(names(dir.path()).is_empty());
        // A very long name is shortened in the temporary name.
        let long = dir.path().join("n".repeat(250));
        write_atomically(&long, |w| w.write_all(b"x")).expect("long name");
        assert_eq!(names(dir.path()), ["n".repeat(250)]);
    }
}
