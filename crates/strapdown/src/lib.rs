//! imudrift strapdown crate (being built).
