//! Shared by the examples.

pub mod table;
