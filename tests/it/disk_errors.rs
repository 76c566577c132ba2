//! The file system says no (issue 16): a full disk (a small tmpfs), a read-only file system, an `--out` that
//! is a file, and a directory the user may not write. Each gives a clear error naming the path and exit 1,
//! leaves no temporary file and no clip that looks finished but is not, and, for the full disk, the same command
//! resumes after space is freed and the dataset equals one written without trouble, byte for byte.
//!
//! Mounting a tmpfs and dropping privileges need root (CI runs as root): those tests are `#[ignore]`d, and
//! `cargo test -- --include-ignored` (CI) runs them, failing where it is not root.

use crate::common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn generate(out: &Path) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_pedsynth"));
    c.arg("generate")
        .arg(Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/specs/cluster_small.yaml"))
        .arg("--out")
        .arg(out)
        .arg("--quiet")
        .arg("--jobs")
        .arg("2");
    c
}

/// Whether the tests run as root: the owner of a file this process creates (probed once; the tests of this
/// file run in parallel threads of one process).
fn is_root() -> bool {
    static ROOT: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    *ROOT.get_or_init(|| {
        use std::os::unix::fs::MetadataExt;
        let probe = std::env::temp_dir().join(format!("pedsynth-uid-probe-{}", std::process::id()));
        std::fs::write(&probe, b"").unwrap();
        let uid = std::fs::metadata(&probe).unwrap().uid();
        std::fs::remove_file(&probe).ok();
        uid == 0
    })
}

/// Fails the test unless it runs as root (the root-only tests are `#[ignore]`d for that reason).
fn require_root(test: &str) {
    assert!(is_root(), "{test} needs root (to mount a tmpfs / drop privileges)");
}

/// A tmpfs mounted for the test's lifetime.
struct Tmpfs(PathBuf);

impl Tmpfs {
    fn mount(dir: &Path, options: &str) -> Tmpfs {
        std::fs::create_dir_all(dir).unwrap();
        let o = Command::new("mount")
            .args(["-t", "tmpfs", "-o", options, "tmpfs"])
            .arg(dir)
            .output()
            .unwrap();
        assert!(o.status.success(), "mount: {}", String::from_utf8_lossy(&o.stderr));
        Tmpfs(dir.to_path_buf())
    }

    fn remount(&self, options: &str) {
        let o = Command::new("mount")
            .args(["-o", &format!("remount,{options}")])
            .arg(&self.0)
            .output()
            .unwrap();
        assert!(o.status.success(), "remount: {}", String::from_utf8_lossy(&o.stderr));
    }
}

impl Drop for Tmpfs {
    fn drop(&mut self) {
        Command::new("umount").arg(&self.0).output().ok();
    }
}

fn stderr(o: &Output) -> String {
    let text = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(!text.contains("panicked"), "{text}");
    text
}

/// No temporary file anywhere under `dir`, and every clip whose `clips` table exists (the completion mark) has
/// all of its tables and every sensor file of its index.
fn nothing_half_written(dir: &Path) {
    let files = common::all_files(dir);
    let temporaries: Vec<&String> = files.keys().filter(|k| k.contains(".tmp-")).collect();
    assert!(temporaries.is_empty(), "temporary files left: {temporaries:?}");
    for key in files.keys().filter(|k| k.starts_with("tables/clips/")) {
        let id = key.trim_start_matches("tables/clips/").trim_end_matches(".parquet");
        for table in pedsynth::dataset::write::tables::TABLES {
            assert!(
                files.contains_key(&format!("tables/{table}/{id}.parquet")),
                "clip {id} is marked finished without its {table} table"
            );
        }
        let index =
            pedsynth::dataset::read::tables::read(&dir.join("tables/sensors").join(format!("{id}.parquet")), &["path"])
                .unwrap();
        for batch in index {
            let paths = batch.strings("path").unwrap();
            for path in paths.iter().take(batch.rows()) {
                assert!(files.contains_key(*path), "clip {id} is marked finished without {path}");
            }
        }
    }
}

#[test]
#[ignore = "needs root (mounts a tmpfs or drops privileges): cargo test -- --include-ignored"]
fn a_full_disk_fails_cleanly_and_the_same_command_resumes_after_freeing_space() {
    require_root("a_full_disk_fails_cleanly");
    let tmp = common::Scratch::new("diskfull");
    let reference = tmp.path().join("reference");
    let o = generate(&reference).output().unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let total: u64 = walk_bytes(&reference);

    // A file system with room for about a third of the dataset.
    let mnt = Tmpfs::mount(&tmp.path().join("small"), &format!("size={}k", total / 3 / 1024));
    let out = mnt.0.join("dataset");
    let o = generate(&out).output().unwrap();
    let err = stderr(&o);
    assert_eq!(
        o.status.code(),
        Some(1),
        "a full disk is the environment's failure (exit 1): {err}"
    );
    assert!(err.contains("No space left on device"), "{err}");
    assert!(
        err.contains(&out.display().to_string()),
        "the error names the path: {err}"
    );
    assert!(err.contains("pedsynth::io::write"), "{err}");
    nothing_half_written(&out);
    let done_before = common::all_files(&out)
        .keys()
        .filter(|k| k.starts_with("tables/clips/"))
        .count();

    // Space freed: the same command finishes, and the dataset equals the reference byte for byte.
    mnt.remount(&format!("size={}k", total * 3 / 1024 + 4096));
    let o = generate(&out).output().unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let (a, b) = (common::all_files(&reference), common::all_files(&out));
    assert_eq!(a.keys().collect::<Vec<_>>(), b.keys().collect::<Vec<_>>());
    for (k, v) in &a {
        assert!(b[k] == *v, "{k} differs from the reference after resuming");
    }
    let o = Command::new(env!("CARGO_BIN_EXE_pedsynth"))
        .arg("verify")
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    eprintln!(
        "disk full: {total} bytes in all, {done_before} of 6 clips finished before the disk filled; resumed to identical bytes"
    );
}

fn walk_bytes(dir: &Path) -> u64 {
    let mut total = 0;
    for entry in std::fs::read_dir(dir).unwrap().flatten() {
        let meta = entry.metadata().unwrap();
        total += if meta.is_dir() {
            walk_bytes(&entry.path())
        } else {
            meta.len()
        };
    }
    total
}

#[test]
#[ignore = "needs root (mounts a tmpfs or drops privileges): cargo test -- --include-ignored"]
fn a_read_only_file_system_is_refused_naming_the_path() {
    require_root("a_read_only_file_system_is_refused");
    let tmp = common::Scratch::new("readonly");
    let mnt = Tmpfs::mount(&tmp.path().join("ro"), "ro,size=1m");
    let out = mnt.0.join("dataset");
    let o = generate(&out).output().unwrap();
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("Read-only file system") && err.contains(&out.display().to_string()),
        "{err}"
    );
}

#[test]
fn an_out_that_is_a_file_is_refused_and_kept() {
    let tmp = common::Scratch::new("outfile");
    let file = tmp.path().join("notes.txt");
    std::fs::write(&file, "my notes").unwrap();
    let o = generate(&file).output().unwrap();
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains(&file.display().to_string()),
        "the error names the path: {err}"
    );
    assert!(err.to_lowercase().contains("not a directory"), "{err}");
    assert_eq!(std::fs::read_to_string(&file).unwrap(), "my notes", "nothing lost");
}

#[test]
fn a_directory_the_user_may_not_write_is_refused_naming_the_path() {
    let tmp = common::Scratch::new("perm");
    let locked = tmp.path().join("locked");
    std::fs::create_dir_all(&locked).unwrap();
    let out = locked.join("dataset");
    let mut c = generate(&out);
    if is_root() {
        // Root writes anywhere: run as `nobody` instead, in a directory only root may write.
        use std::os::unix::process::CommandExt;
        c.uid(65534).gid(65534);
        // `nobody` must reach the binary and the spec: both are world-readable in a checkout.
    } else {
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(&locked, std::fs::Permissions::from_mode(0o555)).unwrap();
    }
    let o = c.output().unwrap();
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("Permission denied") && err.contains(&out.display().to_string()),
        "{err}"
    );
    assert!(!out.exists(), "nothing was created");
}
