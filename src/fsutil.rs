//! File-system helpers shared by every writer: atomic writes (a complete file or none at the target path).

use std::io::Write;
use std::path::Path;

/// Writes `bytes` to `path` through a temporary file in the same directory and a rename, creating the
/// directory if needed, so that a complete file or nothing appears at `path`.
pub fn write_atomically(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    write_atomically_with(path, bytes, true)
}

/// [`write_atomically`] without the fsync: still a complete file or none after a crash of the process (the
/// rename is atomic), but not ordered against a power loss. For sensor blobs, thousands per clip, whose
/// clip is only marked complete by its tables, written (and synced) after them.
pub fn write_atomically_unsynced(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    write_atomically_with(path, bytes, false)
}

fn write_atomically_with(path: &Path, bytes: &[u8], sync: bool) -> std::io::Result<()> {
    let dir = path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    std::fs::create_dir_all(dir)?;
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let tmp = dir.join(format!(".{name}.tmp-{}", std::process::id()));
    let result = (|| {
        let mut file = std::fs::File::create(&tmp)?;
        file.write_all(bytes)?;
        if sync {
            file.sync_all()?;
        }
        std::fs::rename(&tmp, path)
    })();
    if result.is_err() {
        // The write failed (the error is returned): the temporary file goes too, if it can; a leftover one is
        // removed by the next run (`DatasetWriter::open`).
        std::fs::remove_file(&tmp).ok();
    }
    result
}
