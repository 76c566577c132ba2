//! A table declared once: each column's name and nullability beside the array that fills it, so a schema and
//! its columns cannot drift apart (there are no parallel lists to keep in step). The Arrow type of a column is
//! the array's own, or given where a nested type must be spelled out.

use std::sync::Arc;

use arrow_array::{Array, ArrayRef, RecordBatch, StringArray};
use arrow_schema::{DataType, Field, Schema};

/// A record batch under construction, column by column.
#[derive(Default)]
pub(crate) struct Table {
    fields: Vec<Field>,
    columns: Vec<ArrayRef>,
}

impl Table {
    /// A table without columns.
    pub(crate) fn new() -> Table {
        Table::default()
    }

    /// Appends a column whose Arrow type is its array's.
    pub(crate) fn column(self, name: &str, nullable: bool, values: ArrayRef) -> Table {
        let data_type = values.data_type().clone();
        self.column_of_type(name, data_type, nullable, values)
    }

    /// Appends a column of the given Arrow type (for nested types whose item field must be named as declared).
    pub(crate) fn column_of_type(mut self, name: &str, data_type: DataType, nullable: bool, values: ArrayRef) -> Table {
        self.fields.push(Field::new(name, data_type, nullable));
        self.columns.push(values);
        self
    }

    /// The record batch. Every column has its field's type and the same length: a mismatch is a bug in the
    /// table's declaration, caught by any test that writes the table.
    pub(crate) fn finish(self) -> RecordBatch {
        RecordBatch::try_new(Arc::new(Schema::new(self.fields)), self.columns)
            .expect("a table's columns match their declaration")
    }
}

/// A column of `n` copies of `value`.
pub(crate) fn repeated_utf8(n: usize, value: &str) -> ArrayRef {
    Arc::new(StringArray::from_iter_values(std::iter::repeat_n(value, n)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use arrow_array::UInt32Array;

    #[test]
    fn fields_follow_their_columns() {
        let t = Table::new()
            .column("clip_id", false, repeated_utf8(2, "c"))
            .column("frame", true, Arc::new(UInt32Array::from(vec![Some(1), None])))
            .finish();
        let schema = t.schema();
        let names: Vec<&str> = schema.fields().iter().map(|f| f.name().as_str()).collect();
        assert_eq!(names, ["clip_id", "frame"]);
        assert_eq!(schema.field(1).data_type(), &DataType::UInt32);
        assert!(!schema.field(0).is_nullable() && schema.field(1).is_nullable());
        assert_eq!(t.num_rows(), 2);
    }

    #[test]
    #[should_panic(expected = "match their declaration")]
    fn columns_of_different_lengths_are_a_bug() {
        let _ = Table::new()
            .column("a", false, repeated_utf8(2, "c"))
            .column("b", false, repeated_utf8(3, "c"))
            .finish();
    }
}
