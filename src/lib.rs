//! `uncoil`: a coiled tape uncoiling on a floor, simulated as a chain of rigid links in
//! rapier2d and held against K. T. McDonald's continuum theory ("Uncoiling on a Horizontal
//! Surface", with the corrections listed in ERRATA.md).
//!
//! The pipeline: [`scene`] (TOML -> validated `Scene`) -> [`model`] (rapier) and
//! [`reference`](mod@reference) (pure `f64`) -> [`run`] (loop, samples, report) -> [`output`] (files and
//! the summary). Around it: [`overrides`] (scene keys set from the command line),
//! [`sweep`] (grids of runs, one CSV row each), [`analysis`] (Pareto front, convergence
//! orders) and [`plot`] (SVG pictures of a run or a sweep).

pub mod analysis;
pub mod check;
pub mod compare;
pub mod force_window;
pub mod forces;
pub mod frame;
pub mod guard;
pub mod inspect;
pub mod mcap_log;
pub mod model;
pub mod output;
pub mod overrides;
pub mod plot;
pub mod reference;
pub mod rivals;
pub mod run;
pub mod scene;
pub mod spiral;
pub mod sweep;
