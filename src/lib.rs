//! `uncoil`: a coiled tape uncoiling on a floor, simulated as a chain of rigid links in
//! rapier2d and held against K. T. McDonald's continuum theory ("Uncoiling on a Horizontal
//! Surface", with the corrections listed in ERRATA.md).
//!
//! The pipeline: [`scene`] (TOML -> validated `Scene`) -> [`model`] (rapier) and
//! [`reference`](mod@reference) (pure `f64`) -> [`run`] (loop, samples, report) -> [`output`] (files and
//! the summary).

pub mod frame;
pub mod inspect;
pub mod mcap_log;
pub mod model;
pub mod output;
pub mod reference;
pub mod run;
pub mod scene;
pub mod spiral;
