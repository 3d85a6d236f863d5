//! Vectors of the plane as `[f64; 2]`: the few operations the nodal chain needs.

pub(super) fn add(a: [f64; 2], b: [f64; 2]) -> [f64; 2] {
    [a[0] + b[0], a[1] + b[1]]
}

pub(super) fn sub(a: [f64; 2], b: [f64; 2]) -> [f64; 2] {
    [a[0] - b[0], a[1] - b[1]]
}

pub(super) fn scale(k: f64, a: [f64; 2]) -> [f64; 2] {
    [k * a[0], k * a[1]]
}

pub(super) fn dot(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[0] + a[1] * b[1]
}

pub(super) fn cross(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}

pub(super) fn norm(a: [f64; 2]) -> f64 {
    a[0].hypot(a[1])
}

/// `a` turned a quarter counter-clockwise: `J a`.
pub(super) fn quarter(a: [f64; 2]) -> [f64; 2] {
    [-a[1], a[0]]
}
