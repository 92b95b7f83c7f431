//! What can be wrong with a sensor config.

/// A config that cannot be used: names the file, the key and what was expected.
#[derive(Clone, Debug, thiserror::Error)]
pub enum ConfigError {
    /// TOML syntax, unknown keys, wrong types (the message carries line and column).
    #[error("{file}: {message}")]
    Parse { file: String, message: String },
    /// A Kalibr / OpenVINS / VINS-Fusion noise file that cannot be used.
    #[error(transparent)]
    NoiseFile(#[from] NoiseFileError),
    /// A value that parses but is not acceptable.
    #[error("{file}{at}: key `{key}`: expected {expected}, found {found}", at = line.map(|l| format!(":{l}")).unwrap_or_default())]
    Invalid {
        file: String,
        /// 1-based line of the value, when the value exists.
        line: Option<usize>,
        key: String,
        expected: String,
        found: String,
    },
}

/// A noise file that cannot be used: the file, the line where known, the key and what was expected.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{file}{at}: {message}", at = line.map(|l| format!(":{l}")).unwrap_or_default())]
pub struct NoiseFileError {
    pub file: String,
    pub line: Option<usize>,
    pub message: String,
}
