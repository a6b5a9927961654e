//! Acoustic scene mapping with I-ASM (Fu et al.): the particle filter, DBSCAN clustering,
//! implicit association, occupancy maps and the OSPA metric.
//!
//! This crate is laid down by the workspace skeleton; issue 3 fills it.
