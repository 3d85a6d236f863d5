//! `uncoil`: a coiled tape uncoiling on a floor, simulated as a chain of rigid links in
//! rapier2d and held against K. T. McDonald's continuum theory ("Uncoiling on a Horizontal
//! Surface", with the corrections listed in docs/errata.md).
//!
//! The crate is a stack of layers; each imports only the layers below it (a test,
//! `house::each_layer_imports_only_the_layers_below_it` in `tests/house.rs`, keeps the rule):
//!
//! ```text
//! 7 python   the Python extension (feature `python`)  `uncoil` in numpy and pandas
//! 6 study    check, sweep, analysis, plot          many runs, a run's files
//! 5 output   CSV, JSON, summary, tables, MCAP      observers and what they print
//! 4 run      the loop, samples, guards, frames     puts the model beside the theory
//! 3 model    rapier: the chain, the coil, the bang | theory  eq. 7, eq. 17, exact model,
//!                                                  |         rivals, forces (pure f64)
//! 2 spiral   the Archimedean midline (pure f64)
//! 1 scene    TOML file, validation, overrides
//! ```
//!
//! [`model`] and [`theory`] stand side by side: neither imports the other. The binary
//! (`src/main.rs`) is a thin command line on top.

pub mod output;
pub mod run;
pub mod scene;
pub mod spiral;
pub mod study;
pub mod theory;

#[cfg(feature = "python")]
pub mod python;

pub mod model;
