//! The simulator's errors.

use std::path::PathBuf;

/// A scene or room that cannot be simulated.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum SimError {
    /// A scene file that is not valid TOML or does not have a scene's fields.
    #[error("scene: {0}")]
    Parse(String),
    /// A field with a value that cannot be used.
    #[error("{field}: {message}")]
    Invalid {
        /// The field, as named in a scene file (`room.rt60`, `sources[2].pos`).
        field: String,
        /// What is wrong.
        message: String,
    },
    /// A source's recording that cannot be played.
    #[error("{field}: {path}: {message}", path = path.display())]
    Wav {
        /// The field (`sources[2].wav`).
        field: String,
        /// The recording.
        path: PathBuf,
        /// What is wrong with it.
        message: String,
    },
}
