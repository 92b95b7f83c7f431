//! No code. This crate only turns on features of shared dependencies so that the CLI, the tests
//! and the Python module compile each crate once (see its Cargo.toml).
