//! The application's integration tests: one binary (ripgrep's layout).

mod bag;
mod cli;
mod compare;
mod diff;
mod map;
mod near;
mod noise;
mod regression;
mod ros;
mod settings;
mod simulate;
mod util;
mod watch;
