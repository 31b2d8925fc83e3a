//! The host's integration tests, one binary: each module is one subject.

mod bad_inputs;
mod cli;
mod fixtures;
mod formats;
mod groups;
mod properties;
mod run;
