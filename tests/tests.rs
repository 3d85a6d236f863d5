//! Integration tests: one binary, so the engine links once.

mod bang;
mod cli;
mod errata;
mod exact_chain;
mod folded;
mod folder;
mod fuzz;
mod hard;
mod house;
mod mcap;
mod paths;
mod readme;
mod scene_files;
mod sim;
mod study;
mod support;
mod sweep;
mod variants;
