//! imudrift montecarlo crate (being built).
