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

/// Reads a whole file of at most `cap_bytes`, and refuses (`ErrorKind::FileTooLarge`) a larger one after
/// reading `cap_bytes + 1`: a size from the metadata is not enough, since `/dev/zero`, a FIFO or a file that
/// grows report no size or a wrong one, and an untrusted path must not make the program read without bound.
pub fn read_capped(path: &Path, cap_bytes: u64) -> std::io::Result<Vec<u8>> {
    use std::io::Read;
    let file = std::fs::File::open(path)?;
    let hint = file.metadata().map_or(0, |m| m.len()).min(cap_bytes);
    let mut bytes = Vec::with_capacity(usize::try_from(hint).unwrap_or(0));
    file.take(cap_bytes.saturating_add(1)).read_to_end(&mut bytes)?;
    if bytes.len() as u64 > cap_bytes {
        return Err(std::io::Error::new(
            std::io::ErrorKind::FileTooLarge,
            format!("larger than {cap_bytes} bytes"),
        ));
    }
    Ok(bytes)
}

/// A file written in pieces that appears at its path complete or not at all: it is written under a temporary
/// name in the same directory and renamed by [`AtomicFile::commit`]; dropped uncommitted, the temporary file
/// is removed. Counts and hashes (SHA-256) what is written, so the caller can index the file without reading
/// it back.
#[derive(Debug)]
pub struct AtomicFile {
    path: std::path::PathBuf,
    tmp: std::path::PathBuf,
    file: Option<std::io::BufWriter<std::fs::File>>,
    hasher: sha2::Sha256,
    bytes: u64,
}

impl AtomicFile {
    /// Starts writing the file at `path` (creating its directory).
    pub fn create(path: &Path) -> std::io::Result<AtomicFile> {
        let tmp = temporary_path(path);
        if let Some(dir) = tmp.parent() {
            std::fs::create_dir_all(dir)?;
        }
        let file = std::fs::File::create(&tmp)?;
        Ok(AtomicFile {
            path: path.to_path_buf(),
            tmp,
            file: Some(std::io::BufWriter::with_capacity(1 << 20, file)),
            hasher: sha2::Digest::new(),
            bytes: 0,
        })
    }

    /// Moves the complete file to its path (not fsynced: see [`write_atomically_unsynced`]); returns its size
    /// and SHA-256.
    pub fn commit(self) -> std::io::Result<(u64, [u8; 32])> {
        self.commit_with(false)
    }

    /// [`AtomicFile::commit`] after an fsync of the file, as [`write_atomically`] does.
    pub fn commit_synced(self) -> std::io::Result<(u64, [u8; 32])> {
        self.commit_with(true)
    }

    fn commit_with(mut self, sync: bool) -> std::io::Result<(u64, [u8; 32])> {
        if let Some(file) = self.file.as_mut() {
            file.flush()?;
            if sync {
                file.get_ref().sync_all()?;
            }
        }
        // Closed before the rename; on failure the temporary file goes too.
        self.file = None;
        if let Err(e) = std::fs::rename(&self.tmp, &self.path) {
            std::fs::remove_file(&self.tmp).ok();
            return Err(e);
        }
        let hasher = std::mem::take(&mut self.hasher);
        Ok((self.bytes, sha2::Digest::finalize(hasher).into()))
    }
}

impl Write for AtomicFile {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let file = self
            .file
            .as_mut()
            .ok_or_else(|| std::io::Error::other("file already committed"))?;
        let n = file.write(buf)?;
        sha2::Digest::update(&mut self.hasher, &buf[..n]);
        self.bytes += n as u64;
        Ok(n)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.file.as_mut().map_or(Ok(()), Write::flush)
    }
}

impl Drop for AtomicFile {
    fn drop(&mut self) {
        if self.file.take().is_some() {
            std::fs::remove_file(&self.tmp).ok();
        }
    }
}

/// The temporary name under which `path` is written: `.<name>.tmp-<pid>` in the same directory.
pub(crate) fn temporary_path(path: &Path) -> std::path::PathBuf {
    let dir = path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    dir.join(format!(".{name}.tmp-{}", std::process::id()))
}

fn write_atomically_with(path: &Path, bytes: &[u8], sync: bool) -> std::io::Result<()> {
    let dir = path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    std::fs::create_dir_all(dir)?;
    let tmp = temporary_path(path);
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
