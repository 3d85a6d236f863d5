//! Integration tests: one binary, so the engine links once.

mod cli;
mod mcap;
mod sim;
