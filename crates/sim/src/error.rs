//! The simulator's errors.

/// A scene or room that cannot be simulated.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum SimError {
    /// A field with a value that cannot be used.
    #[error("{field}: {message}")]
    Invalid {
        /// The field, as named in a scene file (`room.rt60`, `sources[2].pos`).
        field: String,
        /// What is wrong.
        message: String,
    },
}
