//! imudrift allan crate (being built).
