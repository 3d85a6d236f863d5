//! Integration tests: one binary, so the engine links once.

mod cli;
mod sim;
mod sweep;
