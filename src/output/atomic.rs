//! Atomic file writes: a file is written beside its target under a hidden
//! temporary name, flushed to disk and renamed over the target. Readers (a
//! compositor watching the folder, another worker sharing the cache) see
//! either the old file or the whole new one, never a torn frame.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use super::OutputError;

/// Counts temporary files made by this process, so that two threads writing
/// the same target never share a temporary name.
static TEMP_COUNTER: AtomicU64 = AtomicU64::new(0);

/// Writes `path` atomically: `write` fills a temporary file in the same
/// directory (named `.<target>.<pid>-<n>.tmp`), which is fsynced and then
/// renamed over `path`. Missing parent directories are created. On any
/// error, or a panic in `write`, the temporary file is removed and an
/// existing `path` is left as it was.
pub fn write_atomically<F>(path: &Path, write: F) -> Result<(), OutputError>
where
    F: FnOnce(&mut BufWriter<File>) -> Result<(), OutputError>,
{
    let write_error = |source| OutputError::Write {
        path: path.to_path_buf(),
        source,
    };
    let file_name = path.file_name().ok_or_else(|| {
        write_error(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            "the path names no file",
        ))
    })?;
    let parent = match path.parent() {
        Some(parent) if !parent.as_os_str().is_empty() => parent,
        _ => Path::new("."),
    };
    std::fs::create_dir_all(parent).map_err(|source| OutputError::CreateDir {
        path: parent.to_path_buf(),
        source,
    })?;

    let serial = TEMP_COUNTER.fetch_add(1, Ordering::Relaxed);
    let temp_name = format!(
        ".{}.{}-{serial}.tmp",
        file_name.to_string_lossy(),
        std::process::id()
    );
    let temp = TempFile(parent.join(temp_name));
    let file = File::create_new(&temp.0).map_err(write_error)?;
    let mut writer = BufWriter::new(file);
    write(&mut writer)?;
    writer.flush().map_err(write_error)?;
    let file = writer
        .into_inner()
        .map_err(|error| write_error(error.into_error()))?;
    file.sync_all().map_err(write_error)?;
    drop(file);
    std::fs::rename(&temp.0, path).map_err(write_error)?;
    temp.keep();
    Ok(())
}

/// A temporary file that is deleted when dropped, unless it was renamed
/// into place ([`TempFile::keep`]).
struct TempFile(PathBuf);

impl TempFile {
    fn keep(self) {
        std::mem::forget(self);
    }
}

impl Drop for TempFile {
    fn drop(&mut self) {
        // Best effort: the write already failed, and that error is the one
        // the caller needs to see.
        let _ = std::fs::remove_file(&self.0);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Names in `dir`, sorted, to spot stray temporary files.
    fn entries(dir: &Path) -> Vec<String> {
        let mut names: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|entry| entry.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        names
    }

    #[test]
    fn writes_the_file_and_leaves_no_temporary() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("a/b/frame.txt");
        write_atomically(&target, |w| {
            w.write_all(b"hello").map_err(|source| OutputError::Write {
                path: target.clone(),
                source,
            })
        })
        .unwrap();
        assert_eq!(std::fs::read(&target).unwrap(), b"hello");
        assert_eq!(entries(&dir.path().join("a/b")), ["frame.txt"]);
    }

    #[test]
    fn replaces_an_existing_file() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("frame.txt");
        std::fs::write(&target, b"old").unwrap();
        write_atomically(&target, |w| {
            w.write_all(b"new").map_err(|source| OutputError::Write {
                path: target.clone(),
                source,
            })
        })
        .unwrap();
        assert_eq!(std::fs::read(&target).unwrap(), b"new");
        assert_eq!(entries(dir.path()), ["frame.txt"]);
    }

    #[test]
    fn a_failing_writer_keeps_the_old_file_and_removes_the_temporary() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("frame.txt");
        std::fs::write(&target, b"old").unwrap();
        let result = write_atomically(&target, |w| {
            w.write_all(b"half a fr").unwrap();
            Err(OutputError::Encode {
                path: target.clone(),
                fault: "encoder gave up".into(),
            })
        });
        assert!(matches!(result, Err(OutputError::Encode { .. })));
        assert_eq!(std::fs::read(&target).unwrap(), b"old");
        assert_eq!(entries(dir.path()), ["frame.txt"]);
    }

    #[test]
    fn a_panicking_writer_removes_the_temporary() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("frame.txt");
        let outcome = std::panic::catch_unwind(|| {
            let _ = write_atomically(&target, |_| panic!("encoder bug"));
        });
        assert!(outcome.is_err());
        assert!(entries(dir.path()).is_empty());
    }

    #[test]
    fn a_directory_in_the_way_fails_cleanly() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("frame.txt");
        std::fs::create_dir(&target).unwrap();
        std::fs::write(target.join("inside"), b"keep").unwrap();
        let result = write_atomically(&target, |_| Ok(()));
        let message = result.unwrap_err().to_string();
        assert!(message.contains("frame.txt"), "{message}");
        assert_eq!(std::fs::read(target.join("inside")).unwrap(), b"keep");
        assert_eq!(entries(dir.path()), ["frame.txt"]);
    }

    #[test]
    fn concurrent_writers_never_collide() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("shared.txt");
        std::thread::scope(|scope| {
            for thread in 0..8u8 {
                let target = &target;
                scope.spawn(move || {
                    write_atomically(target, |w| {
                        w.write_all(&[thread; 4096])
                            .map_err(|source| OutputError::Write {
                                path: target.clone(),
                                source,
                            })
                    })
                    .unwrap();
                });
            }
        });
        let bytes = std::fs::read(&target).unwrap();
        assert_eq!(bytes.len(), 4096);
        assert!(bytes.iter().all(|&b| b == bytes[0]), "torn file");
        assert_eq!(entries(dir.path()), ["shared.txt"]);
    }
}
