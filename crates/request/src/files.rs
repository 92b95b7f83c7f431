//! The input files a request names (sensor models, scenarios, shard files), each read with its
//! size bound (`logio::read_capped`: a regular file's size is checked before a byte is read, a
//! device or a pipe is read with the bound) and decoded as UTF-8 with the line and column of a
//! bad byte (`noise::utf8_text`). Errors name the file and what it was read as.

use crate::error::{FileError, FileProblem};
use noise::SensorModel;
use std::path::{Path, PathBuf};

/// Most bytes of a sensor model, scenario or noise file (16 MiB; the shipped ones are a few KiB).
pub const MAX_CONFIG_BYTES: u64 = 16 << 20;

/// What a config file is read as, in messages.
pub const CONFIG_WHAT: &str = "a sensor model, scenario or noise file";

/// A text file as read: its name as given (for messages) and its text.
#[derive(Clone, Debug)]
pub struct TextFile {
    pub name: String,
    pub text: String,
}

/// Read a text file of at most `max_bytes`, named in errors as `what`.
pub fn read_text(path: &Path, what: &'static str, max_bytes: u64) -> Result<TextFile, FileError> {
    let name = path.display().to_string();
    let err = |problem| FileError {
        name: name.clone(),
        what,
        within: None,
        problem,
    };
    let bytes = logio::read_capped(path, max_bytes).map_err(|e| err(FileProblem::Io(e)))?;
    let text = noise::utf8_text(bytes, &name).map_err(|e| err(FileProblem::Text(Box::new(e))))?;
    Ok(TextFile { name, text })
}

/// [`read_text`] of a sensor model, scenario or noise file ([`MAX_CONFIG_BYTES`]). A path that
/// names no file and is a shipped sensor's name (`mtx`, [`SHIPPED_SENSORS`]) reads that sensor's
/// TOML as the repository ships it (configs/sensors/NAME.toml, built into the program), so
/// `imudrift simulate mtx` and Python's `Sensor("mtx")` work from any directory; a file of that
/// name, where there is one, is read instead.
pub fn read_config(path: &Path) -> Result<TextFile, FileError> {
    if let Some(file) = shipped_sensor(path) {
        return Ok(file);
    }
    read_text(path, CONFIG_WHAT, MAX_CONFIG_BYTES)
}

pub use crate::shipped::SHIPPED_SENSORS;

/// The shipped sensor a path names: a bare name of [`SHIPPED_SENSORS`] (no directory, no
/// extension) where no file of that name exists.
pub fn shipped_sensor(path: &Path) -> Option<TextFile> {
    let name = path.to_str()?;
    let (_, text) = SHIPPED_SENSORS.iter().find(|(n, _)| *n == name)?;
    if path.exists() {
        return None;
    }
    Some(TextFile {
        name: name.to_string(),
        text: text.to_string(),
    })
}

/// Most bytes of shard files read together: a third of the memory available (their text, the
/// values parsed from it and the merged values each take about as much), or 8 GiB when the
/// memory available is not known.
pub fn shard_bytes() -> u64 {
    logio::available_memory_bytes().map_or(8 << 30, |a| a / 3)
}

/// A sensor model as a request names it: a file, or its text with a name for messages.
#[derive(Clone, Debug)]
pub enum SensorSource {
    Path(PathBuf),
    Text { text: String, source: String },
}

impl Default for SensorSource {
    fn default() -> Self {
        SensorSource::Text {
            text: String::new(),
            source: "<sensor text>".into(),
        }
    }
}

impl SensorSource {
    /// A model as a front end's one text argument names it (Python's `Sensor("...")`, `model=`):
    /// a text naming an existing path is that file (a directory is then a file that cannot be
    /// read); another text of one line without `=` is neither a file nor a model's text (a
    /// sensor TOML has `key = value` lines), and is refused as a missing file; anything else is
    /// the model's text, named `<sensor text>` in messages.
    pub fn of_argument(arg: &str) -> Result<SensorSource, crate::RequestError> {
        let one_line = !arg.contains('\n');
        if one_line && !arg.is_empty() && Path::new(arg).exists() {
            return Ok(SensorSource::Path(PathBuf::from(arg)));
        }
        if shipped_sensor(Path::new(arg)).is_some() {
            return Ok(SensorSource::Path(PathBuf::from(arg)));
        }
        if one_line && !arg.contains('=') {
            return Err(crate::RequestError::NoSuchModel(arg.to_string()));
        }
        Ok(SensorSource::Text {
            text: arg.to_string(),
            source: "<sensor text>".into(),
        })
    }

    /// The text and its name (a file read with [`read_config`]).
    pub fn read(&self) -> Result<TextFile, FileError> {
        match self {
            SensorSource::Path(p) => read_config(p),
            SensorSource::Text { text, source } => Ok(TextFile {
                name: source.clone(),
                text: text.clone(),
            }),
        }
    }

    /// The sensor model: a sensor TOML, or a Kalibr / OpenVINS / VINS-Fusion IMU noise file
    /// (`noise::SensorModel::from_text`).
    pub fn model(&self) -> Result<SensorModel, FileError> {
        let file = self.read()?;
        model_of(&file)
    }
}

/// The sensor model of a file's text.
pub fn model_of(file: &TextFile) -> Result<SensorModel, FileError> {
    SensorModel::from_text(&file.text, &file.name).map_err(|e| FileError {
        name: file.name.clone(),
        what: CONFIG_WHAT,
        within: None,
        problem: FileProblem::Text(Box::new(e)),
    })
}
