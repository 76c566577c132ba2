//! Spec language: types, loading, validation and diagnostics.
