//! `pedsynth merge`: completes a dataset from shards generated into separate directories (node-local scratch,
//! one directory per SLURM task), or finishes a shared one. Every clip that `--out` does not have yet is taken
//! from a shard directory where it is finished: its sensor files (checked against the clip's sensor index:
//! size and SHA-256) and then its tables (the `clips` table last, since its presence marks a finished clip) are
//! hard-linked, or copied across file systems, through a temporary name and a rename. The manifest and the
//! dataset card are then written as `generate` writes them, so the merged dataset is byte-identical to a
//! single-machine run of the same plan.

use std::path::{Path, PathBuf};

use crate::dataset::write::manifest::Manifest;
use crate::dataset::write::tables::TABLES;
use crate::dataset::write::{DatasetWriter, Layout};
use crate::error::{Error, code};
use crate::plan::PreparedPlan;

/// What a merge did.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct MergeReport {
    /// Clips `--out` already had.
    pub kept: usize,
    /// Clips taken from shard directories.
    pub merged: usize,
    /// Files linked or copied (sensor files and tables).
    pub files: usize,
    /// Bytes of those files.
    pub bytes: u64,
    /// Clips no directory has finished (the merge then fails, after writing the manifest of what it has).
    pub missing: Vec<String>,
}

/// Merges the finished clips of `shards` (dataset directories of the same spec and plan) into `out`, then
/// writes the manifest and, when every clip is there, the card.
pub fn merge(plan: &PreparedPlan, out: &Path, shards: &[PathBuf]) -> Result<MergeReport, Error> {
    let writer = DatasetWriter::open(out, plan, false)?;
    let sources: Vec<Layout> = shards.iter().map(Layout::new).collect();
    for source in &sources {
        check_source(source, writer.manifest_hashes())?;
    }
    let mut report = MergeReport::default();
    for clip in plan.clips() {
        let id = &*clip.clip_id;
        if writer.is_clip_done(id) {
            report.kept += 1;
            continue;
        }
        let Some(source) = sources.iter().find(|s| TABLES.iter().all(|t| s.table(t, id).is_file())) else {
            report.missing.push(id.to_owned());
            continue;
        };
        copy_clip(source, writer.layout(), id, &mut report)?;
        report.merged += 1;
    }
    let _guard = writer.manifest_lock()?;
    let complete = super::finish_dataset(plan, &writer, out, true)?;
    if !report.missing.is_empty() || !complete {
        let shown: Vec<&str> = report.missing.iter().take(10).map(String::as_str).collect();
        return Err(Error::new(
            code::MERGE_INCOMPLETE,
            format!(
                "{}: {} of {} clips are finished in no directory given ({}{}); the manifest lists them as pending",
                out.display(),
                report.missing.len(),
                plan.len(),
                shown.join(", "),
                if report.missing.len() > shown.len() {
                    ", ..."
                } else {
                    ""
                }
            ),
        )
        .help("re-run the shards that failed (`pedsynth generate ... --shard I/N`), then merge again"));
    }
    Ok(report)
}

/// A shard directory must be a dataset of the same spec and plan.
fn check_source(source: &Layout, (spec_hash, plan_hash): (&str, &str)) -> Result<(), Error> {
    let path = source.manifest();
    let text = std::fs::read_to_string(&path).map_err(|e| {
        Error::new(
            code::MERGE_MISMATCH,
            format!(
                "{}: not a pedsynth dataset ({}: {e})",
                source.root().display(),
                path.display()
            ),
        )
        .help("give the --out directories of `pedsynth generate --shard I/N` runs of this spec")
    })?;
    let manifest = Manifest::parse(&text, &path.display().to_string())?;
    let why = if manifest.spec_hash != spec_hash {
        "it holds a dataset of another spec"
    } else if manifest.plan_hash != plan_hash {
        "it holds a dataset of another plan of this spec (another pedsynth version?)"
    } else {
        return Ok(());
    };
    Err(
        Error::new(code::MERGE_MISMATCH, format!("{}: {why}", source.root().display()))
            .help("merge only shards generated from the same spec with the same pedsynth"),
    )
}

/// Links or copies one finished clip: sensor files first (each checked against the clip's index), tables
/// after them, `clips` last.
fn copy_clip(source: &Layout, out: &Layout, id: &str, report: &mut MergeReport) -> Result<(), Error> {
    let mut problems = Vec::new();
    crate::dataset::verify::read_sensor_files(
        source,
        id,
        |rel, data| {
            link_or_copy(&source.root().join(rel), &out.root().join(rel), data)?;
            report.files += 1;
            report.bytes += data.len() as u64;
            Ok(())
        },
        |problem| problems.push(problem),
    )?;
    if !problems.is_empty() {
        // No table is copied, so the clip stays unfinished in --out.
        return Err(Error::new(
            code::DATASET_INVALID,
            format!("{}: clip {id}: {}", source.root().display(), problems.join("; ")),
        )
        .help("regenerate the clip in that shard (delete its tables/*/<clip_id>.parquet, re-run it)"));
    }
    // `clips` is the last table (its presence marks a finished clip).
    debug_assert_eq!(TABLES.last(), Some(&"clips"));
    for table in TABLES {
        let from = source.table(table, id);
        let data = std::fs::read(&from).map_err(|e| Error::read(&from, e))?;
        link_or_copy(&from, &out.table(table, id), &data)?;
        report.files += 1;
        report.bytes += data.len() as u64;
    }
    Ok(())
}

/// Puts `from` (whose bytes are `data`) at `to`: a hard link under a temporary name renamed into place, or,
/// where linking fails (another file system), the bytes written atomically.
fn link_or_copy(from: &Path, to: &Path, data: &[u8]) -> Result<(), Error> {
    if let Some(dir) = to.parent() {
        std::fs::create_dir_all(dir).map_err(|e| Error::write(dir, e))?;
    }
    let tmp = crate::util::files::temporary_path(to);
    std::fs::remove_file(&tmp).ok();
    if std::fs::hard_link(from, &tmp).is_ok() {
        return std::fs::rename(&tmp, to).map_err(|e| {
            std::fs::remove_file(&tmp).ok();
            Error::write(to, e)
        });
    }
    crate::util::files::write_atomically(to, data).map_err(|e| Error::write(to, e))
}
