//! The commands: each a thin user of the library modules ([`crate::pipeline`],
//! [`crate::settings`], [`crate::dataset`], [`crate::scenes`], [`crate::suite`],
//! [`crate::score`], [`crate::compare`], [`crate::figure`]) that parses nothing and prints its report. No
//! command imports another.

pub mod bag;
pub mod compare;
pub mod demo;
pub mod diff;
pub mod eval;
pub mod map;
pub mod regress;
#[cfg(feature = "ros2")]
pub mod ros2;
pub mod scenes;
pub mod simulate;
pub mod ssl;
pub mod watch;
