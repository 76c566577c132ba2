//! Every path of a dataset, in one place. Writers and readers both find files through [`Layout`], so the
//! dataset's layout is defined once:
//!
//! ```text
//! DIR/manifest.json                         what the dataset is, every clip's status and file hashes
//! DIR/spec.resolved.yaml                    the fully defaulted spec
//! DIR/tables/<table>/<clip_id>.parquet      the annotation tables, one file per clip and table
//! DIR/sensors/<stream>/<clip_id>/...        sensor blobs
//! ```

use std::path::{Path, PathBuf};

/// Name of the manifest file.
pub const MANIFEST: &str = "manifest.json";
/// Name of the resolved spec file.
pub const SPEC_RESOLVED: &str = "spec.resolved.yaml";
/// Directory of the tables.
pub const TABLES_DIR: &str = "tables";
/// Directory of the sensor blobs.
pub const SENSORS_DIR: &str = "sensors";

/// The paths of one dataset directory.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Layout {
    root: PathBuf,
}

impl Layout {
    /// The layout of the dataset at `root`.
    pub fn new(root: impl Into<PathBuf>) -> Layout {
        Layout { root: root.into() }
    }

    /// The dataset directory.
    pub fn root(&self) -> &Path {
        &self.root
    }

    /// `manifest.json`.
    pub fn manifest(&self) -> PathBuf {
        self.root.join(MANIFEST)
    }

    /// `spec.resolved.yaml`.
    pub fn spec_resolved(&self) -> PathBuf {
        self.root.join(SPEC_RESOLVED)
    }

    /// The directory of one table's files.
    pub fn table_dir(&self, table: &str) -> PathBuf {
        self.root.join(TABLES_DIR).join(table)
    }

    /// One clip's file of one table.
    pub fn table(&self, table: &str, clip_id: &str) -> PathBuf {
        self.table_dir(table).join(format!("{clip_id}.parquet"))
    }

    /// The directory of one stream's files of one clip: `sensors/<stream>/<clip_id>`.
    pub fn sensor_dir(&self, stream: &str, clip_id: &str) -> PathBuf {
        self.root.join(SENSORS_DIR).join(stream).join(clip_id)
    }

    /// One frame's file of a sensor stream: `sensors/<stream>/<clip_id>/<frame:06>.<ext>`.
    pub fn sensor_frame(&self, stream: &str, clip_id: &str, frame: u32, ext: &str) -> PathBuf {
        self.sensor_dir(stream, clip_id).join(format!("{frame:06}.{ext}"))
    }

    /// A clip's single file of a sensor stream: `sensors/<stream>/<clip_id>.<ext>`.
    pub fn sensor_clip(&self, stream: &str, clip_id: &str, ext: &str) -> PathBuf {
        self.root
            .join(SENSORS_DIR)
            .join(stream)
            .join(format!("{clip_id}.{ext}"))
    }

    /// The path of a dataset file relative to the root, with `/` separators (as the manifest records it).
    pub fn relative(&self, path: &Path) -> String {
        let rel = path.strip_prefix(&self.root).unwrap_or(path);
        rel.components()
            .map(|c| c.as_os_str().to_string_lossy())
            .collect::<Vec<_>>()
            .join("/")
    }
}
