//! imudrift noise crate (being built).
