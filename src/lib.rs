//! `uncoil`: a coiled tape uncoiling on a floor, simulated as a chain of rigid links in
//! rapier2d and held against K. T. McDonald's continuum theory ("Uncoiling on a Horizontal
//! Surface", with the corrections listed in ERRATA.md).

pub mod model;
pub mod reference;
pub mod scene;
pub mod spiral;
