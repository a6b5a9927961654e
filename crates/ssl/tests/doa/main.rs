//! The analytic DoA tests: plane waves delayed exactly to the microphones of an array, from
//! known directions, through the localizer. One binary (as the application's tests are),
//! one module per idea.

mod channels;
mod common;
mod deflation;
mod doa_sim;
mod peaks;
mod pooling;
