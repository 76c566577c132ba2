//! File-system helpers shared by every writer: atomic writes (a complete file or none at the target path;
//! written straight to a device or FIFO, such as `--out /dev/null`, which a rename would replace).

use std::io::Write;
use std::path::Path;

/// Writes `bytes` to `path` through a temporary file in the same directory and a rename, creating the
/// directory if needed, so that a complete file or nothing appears at `path`. A `path` that is a device, a FIFO
/// or a socket (`/dev/null`, `/dev/stdout`, a pipe) is written to directly: a rename would put a regular file in
/// its place.
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
    /// The temporary name; `None` where `path` is a device or FIFO, written directly ([`is_special`]).
    tmp: Option<std::path::PathBuf>,
    file: Option<std::io::BufWriter<std::fs::File>>,
    hasher: sha2::Sha256,
    bytes: u64,
}

impl AtomicFile {
    /// Starts writing the file at `path` (creating its directory).
    pub fn create(path: &Path) -> std::io::Result<AtomicFile> {
        let tmp = (!is_special(path)).then(|| temporary_path(path));
        if let Some(dir) = tmp.as_deref().and_then(Path::parent) {
            std::fs::create_dir_all(dir)?;
        }
        let file = std::fs::File::create(tmp.as_deref().unwrap_or(path))?;
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
        if let Some(tmp) = &self.tmp
            && let Err(e) = std::fs::rename(tmp, &self.path)
        {
            std::fs::remove_file(tmp).ok();
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
        if self.file.take().is_some()
            && let Some(tmp) = &self.tmp
        {
            std::fs::remove_file(tmp).ok();
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

/// Whether `path` (followed through links) is neither a regular file nor a directory: a device, a FIFO or a
/// socket, which is written to in place.
fn is_special(path: &Path) -> bool {
    std::fs::metadata(path).is_ok_and(|m| !m.is_file() && !m.is_dir())
}

fn write_atomically_with(path: &Path, bytes: &[u8], sync: bool) -> std::io::Result<()> {
    if is_special(path) {
        return std::fs::OpenOptions::new().write(true).open(path)?.write_all(bytes);
    }
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A FIFO in a fresh directory, made with `mkfifo` (no unsafe code here), and its read end opened without
    /// blocking, so that writers can open it and a regression (a rename over it) fails instead of hanging.
    fn fifo(name: &str) -> (std::path::PathBuf, std::fs::File) {
        use std::os::unix::fs::OpenOptionsExt;
        let dir = std::env::temp_dir().join(format!("pedsynth-fifo-{name}-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        let path = dir.join("out");
        std::fs::remove_file(&path).ok();
        let made = std::process::Command::new("mkfifo")
            .arg(&path)
            .status()
            .expect("runs mkfifo");
        assert!(made.success(), "mkfifo");
        // O_NONBLOCK (Linux's value): the open returns at once with no writer.
        let reader = std::fs::OpenOptions::new()
            .read(true)
            .custom_flags(0o4000)
            .open(&path)
            .expect("opens the read end");
        (path, reader)
    }

    fn drain(mut reader: std::fs::File) -> Vec<u8> {
        use std::io::Read;
        let mut out = Vec::new();
        reader.read_to_end(&mut out).ok();
        out
    }

    fn is_fifo(path: &Path) -> bool {
        use std::os::unix::fs::FileTypeExt;
        std::fs::symlink_metadata(path).is_ok_and(|m| m.file_type().is_fifo())
    }

    #[test]
    fn a_fifo_or_device_is_written_in_place_not_replaced_by_a_file() {
        // `--out /dev/null` as root once replaced the device with a regular file (a rename over it); a FIFO
        // stands in for the device here, so that a regression cannot break the machine's /dev/null.
        let (path, reader) = fifo("whole");
        write_atomically(&path, b"profile").expect("writes");
        assert_eq!(drain(reader), b"profile");
        assert!(is_fifo(&path), "the FIFO is still a FIFO");
        std::fs::remove_dir_all(path.parent().expect("dir")).ok();

        let (path, reader) = fifo("pieces");
        let mut file = AtomicFile::create(&path).expect("opens");
        file.write_all(b"two ").expect("writes");
        file.write_all(b"pieces").expect("writes");
        let (bytes, _) = file.commit().expect("commits");
        assert_eq!((bytes, drain(reader)), (10, b"two pieces".to_vec()));
        assert!(is_fifo(&path), "the FIFO is still a FIFO");
        std::fs::remove_dir_all(path.parent().expect("dir")).ok();
    }

    #[test]
    fn a_regular_file_is_replaced_whole_and_leaves_no_temporary_file() {
        let dir = std::env::temp_dir().join(format!("pedsynth-atomic-{}", std::process::id()));
        let path = dir.join("out.txt");
        write_atomically(&path, b"first").expect("writes");
        write_atomically(&path, b"second").expect("writes");
        assert_eq!(std::fs::read(&path).expect("reads"), b"second");
        let names: Vec<_> = std::fs::read_dir(&dir)
            .expect("dir")
            .map(|e| e.expect("entry").file_name())
            .collect();
        assert_eq!(names, vec![std::ffi::OsString::from("out.txt")]);
        std::fs::remove_dir_all(&dir).ok();
    }
}
