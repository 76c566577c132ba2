//! Reading a dataset's Parquet tables: the files of a table, chosen columns of a file, and typed access to a
//! column that reports a mistyped or missing column as an error (a dataset is input: it may have been written
//! by another tool, with `large_string` columns, say) instead of panicking.

use std::fs::File;
use std::path::{Path, PathBuf};

use arrow_array::cast::AsArray;
use arrow_array::types::{Float32Type, Float64Type, Int32Type, UInt8Type, UInt16Type, UInt32Type, UInt64Type};
use arrow_array::{Array, ArrowPrimitiveType, PrimitiveArray, RecordBatch};
use parquet::arrow::arrow_reader::ParquetRecordBatchReaderBuilder;

use crate::dataset::write::Layout;
use crate::error::{Error, code};

/// Every file of `table`, sorted by name (clip id).
pub fn files(layout: &Layout, table: &str) -> Result<Vec<PathBuf>, Error> {
    let d = layout.table_dir(table);
    let mut out: Vec<PathBuf> = std::fs::read_dir(&d)
        .map_err(|e| {
            Error::new(
                code::DATASET_INVALID,
                format!("{}: {e} (is this a pedsynth dataset?)", d.display()),
            )
        })?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "parquet"))
        .collect();
    out.sort();
    Ok(out)
}

/// The number of rows of one Parquet file (from its footer).
pub fn row_count(path: &Path) -> Result<u64, Error> {
    let file = File::open(path).map_err(|e| Error::read(path, e))?;
    let builder = ParquetRecordBatchReaderBuilder::try_new(file)
        .map_err(|e| Error::new(code::DATASET_INVALID, format!("{}: {e}", path.display())))?;
    Ok(builder.metadata().file_metadata().num_rows().max(0) as u64)
}

/// The record batches of `columns` of one Parquet file.
pub fn read(path: &Path, columns: &[&str]) -> Result<Vec<Batch>, Error> {
    let invalid = |e: &dyn std::fmt::Display| Error::new(code::DATASET_INVALID, format!("{}: {e}", path.display()));
    let file = File::open(path).map_err(|e| Error::read(path, e))?;
    let builder = ParquetRecordBatchReaderBuilder::try_new(file).map_err(|e| invalid(&e))?;
    let schema = builder.parquet_schema();
    let indices: Vec<usize> = columns
        .iter()
        .map(|c| {
            schema
                .columns()
                .iter()
                .position(|col| col.path().parts()[0] == *c)
                .ok_or_else(|| invalid(&format!("no column `{c}`")))
        })
        .collect::<Result<_, _>>()?;
    let mask = parquet::arrow::ProjectionMask::roots(schema, indices);
    let reader = builder.with_projection(mask).build().map_err(|e| invalid(&e))?;
    reader
        .map(|b| {
            b.map(|batch| Batch {
                batch,
                path: path.to_path_buf(),
            })
            .map_err(|e| invalid(&e))
        })
        .collect()
}

/// A record batch read from a file, with typed column access.
pub struct Batch {
    batch: RecordBatch,
    path: PathBuf,
}

impl Batch {
    /// Rows.
    pub fn rows(&self) -> usize {
        self.batch.num_rows()
    }

    fn column(&self, name: &str) -> Result<&dyn Array, Error> {
        self.batch
            .column_by_name(name)
            .map(|c| c.as_ref())
            .ok_or_else(|| self.invalid(&format!("no column `{name}`")))
    }

    fn invalid(&self, what: &str) -> Error {
        Error::new(code::DATASET_INVALID, format!("{}: {what}", self.path.display()))
    }

    fn primitive<T: ArrowPrimitiveType>(&self, name: &str) -> Result<&PrimitiveArray<T>, Error> {
        let c = self.column(name)?;
        c.as_primitive_opt::<T>()
            .ok_or_else(|| self.invalid(&format!("column `{name}` is {}, not {}", c.data_type(), T::DATA_TYPE)))
    }

    /// A `uint8` column.
    pub fn u8s(&self, name: &str) -> Result<&PrimitiveArray<UInt8Type>, Error> {
        self.primitive(name)
    }

    /// A `uint16` column.
    pub fn u16s(&self, name: &str) -> Result<&PrimitiveArray<UInt16Type>, Error> {
        self.primitive(name)
    }

    /// A fixed-size list of `float32` column: all values, row after row, and the list width.
    pub fn f32_lists(&self, name: &str) -> Result<(&[f32], usize), Error> {
        let c = self.column(name)?;
        let list = c
            .as_fixed_size_list_opt()
            .ok_or_else(|| self.invalid(&format!("column `{name}` is {}, not a fixed-size list", c.data_type())))?;
        let values = list
            .values()
            .as_primitive_opt::<Float32Type>()
            .ok_or_else(|| self.invalid(&format!("column `{name}` does not hold float32 values")))?;
        let width = list.value_length() as usize;
        let start = list.offset() * width;
        Ok((&values.values()[start..start + list.len() * width], width))
    }

    /// A `uint32` column.
    pub fn u32s(&self, name: &str) -> Result<&PrimitiveArray<UInt32Type>, Error> {
        self.primitive(name)
    }

    /// A `uint64` column.
    pub fn u64s(&self, name: &str) -> Result<&PrimitiveArray<UInt64Type>, Error> {
        self.primitive(name)
    }

    /// An `int32` column.
    pub fn i32s(&self, name: &str) -> Result<&PrimitiveArray<Int32Type>, Error> {
        self.primitive(name)
    }

    /// A `float32` column.
    pub fn f32s(&self, name: &str) -> Result<&PrimitiveArray<Float32Type>, Error> {
        self.primitive(name)
    }

    /// A `float64` column.
    pub fn f64s(&self, name: &str) -> Result<&PrimitiveArray<Float64Type>, Error> {
        self.primitive(name)
    }

    /// A `bool` column.
    pub fn bools(&self, name: &str) -> Result<&arrow_array::BooleanArray, Error> {
        let c = self.column(name)?;
        c.as_boolean_opt()
            .ok_or_else(|| self.invalid(&format!("column `{name}` is {}, not bool", c.data_type())))
    }

    /// A string column (`string` or `large_string`), its values (null as "").
    pub fn strings(&self, name: &str) -> Result<Vec<&str>, Error> {
        let c = self.column(name)?;
        if let Some(s) = c.as_string_opt::<i32>() {
            Ok((0..s.len())
                .map(|i| if s.is_null(i) { "" } else { s.value(i) })
                .collect())
        } else if let Some(s) = c.as_string_opt::<i64>() {
            Ok((0..s.len())
                .map(|i| if s.is_null(i) { "" } else { s.value(i) })
                .collect())
        } else {
            Err(self.invalid(&format!("column `{name}` is {}, not a string", c.data_type())))
        }
    }
}
