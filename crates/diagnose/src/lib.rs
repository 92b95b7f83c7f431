//! imudrift diagnose crate (being built).
