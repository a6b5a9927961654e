//! Image-source room acoustics (Allen & Berkley, 1979) that renders what a robot's
//! microphone array hears at each stop of a trajectory through a room with many sources.
//!
//! This crate is laid down by the workspace skeleton; issue 4 fills it.
