//! Writing the dataset: the only code that touches the output directory.
//!
//! - [`tables`] — the Parquet tables: schemas, record batches, atomic writes.
pub mod tables;
