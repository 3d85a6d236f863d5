//! The study layer: what is done with many runs or with a run's files. `check` runs the
//! hard cases and verifies their outputs, `sweep` runs grids of scenes, `analysis` says
//! what a sweep shows, `plot` draws a run or a sweep. It builds on every layer below and
//! nothing below imports it.

pub mod analysis;
pub mod check;
pub mod plot;
pub mod sweep;
