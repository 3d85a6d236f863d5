//! Numbers as `samples.csv` writes them: Rust's `{:.9e}` (ten significant digits, correctly
//! rounded), made by scaling to ten digits in floating point instead of the standard
//! library's exact decimal expansion, which took a sixth of the main job's time.
//!
//! Why the two agree: for `|v|` between 1e-13 and 1e19, `|v| 10^(9 - e)` (`e` the power of ten
//! of the first digit) multiplies by a power of ten that a double holds exactly, so it is
//! rounded once: below 1e10, it lies within 1e-6 of the exact scaled value. Rounding it to an
//! integer therefore gives the exact value's rounding, unless its fraction lies within that
//! distance of a half; within 1.2e-5 of one (a few numbers in a hundred thousand), and
//! outside that range, the standard library's formatting is used.

/// Appends `v`, finite, to `out` exactly as `format!("{v:.9e}")` writes it.
pub fn push_sci9(out: &mut String, v: f64) {
    debug_assert!(v.is_finite());
    match ten_digits(v) {
        Some((digits, exp)) => {
            if v.is_sign_negative() {
                out.push('-');
            }
            if digits == 0 {
                out.push_str("0.000000000e0");
                return;
            }
            let mut text = itoa::Buffer::new();
            let text = text.format(digits);
            out.push_str(&text[..1]);
            out.push('.');
            out.push_str(&text[1..]);
            out.push('e');
            out.push_str(itoa::Buffer::new().format(exp));
        }
        None => {
            use std::fmt::Write as _;
            let _ = write!(out, "{v:.9e}");
        }
    }
}

/// The ten significant digits of `|v|`, correctly rounded, as an integer in
/// `1e9..1e10`, with the power of ten of the first; zero as `(0, 0)`, written
/// `0.000000000e0`. `None` where the scaling cannot tell (see the module's text).
fn ten_digits(v: f64) -> Option<(u64, i32)> {
    /// Powers of ten a double holds exactly.
    const POW10: [f64; 23] = [
        1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16,
        1e17, 1e18, 1e19, 1e20, 1e21, 1e22,
    ];
    let a = v.abs();
    if a == 0.0 {
        return Some((0, 0));
    }
    if !(1e-13..1e19).contains(&a) {
        return None;
    }
    let mut exp = a.log10().floor() as i32;
    // log10 may land one off next to a power of ten: the scaled value says which.
    for _ in 0..2 {
        let shift = 9 - exp;
        let scaled = if shift >= 0 {
            a * POW10[usize::try_from(shift).ok()?]
        } else {
            a / POW10[usize::try_from(-shift).ok()?]
        };
        if scaled < 1e9 {
            exp -= 1;
            continue;
        }
        if scaled >= 1e10 {
            exp += 1;
            continue;
        }
        let floor = scaled.floor();
        let fraction = scaled - floor;
        if (fraction - 0.5).abs() < 1.2e-5 {
            return None;
        }
        let mut digits = floor as u64 + u64::from(fraction > 0.5);
        if digits == 10_000_000_000 {
            digits = 1_000_000_000;
            exp += 1;
        }
        return Some((digits, exp));
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check(v: f64) {
        let mut ours = String::new();
        push_sci9(&mut ours, v);
        assert_eq!(ours, format!("{v:.9e}"), "{v:e} ({:#x})", v.to_bits());
    }

    #[test]
    fn writes_what_the_standard_library_writes() {
        for v in [
            0.0,
            -0.0,
            1.0,
            -1.0,
            0.1,
            0.3,
            1e-300,
            5e-324,
            f64::MIN_POSITIVE,
            f64::MAX,
            f64::MIN,
            9.9999999995,
            9.99999999949,
            9.999999999_6e-5,
            1e-13,
            9.999_999_999_999e-14,
            1e19,
            9.999_999_999_999e18,
            999_999_999.5,
            0.000_999_999_999_96,
            99_999_999_995.0,
            1_234_567_890.5,
            1_234_567_891.5,
            0.000_123_456_789_05,
            123_456.0,
            1e16,
            1e15,
            2.5e-7,
            6.02214076e23,
        ] {
            check(v);
        }
        // Random doubles: every bit pattern's magnitude, and numbers like a run's.
        let mut x: u64 = 0x9e37_79b9_7f4a_7c15;
        for _ in 0..300_000 {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            let v = f64::from_bits(x);
            if v.is_finite() {
                check(v);
            }
            check((x >> 11) as f64 / (1_u64 << 53) as f64 * 20.0 - 10.0);
            // Every power of ten the fast path takes, and its edges.
            let unit = (x >> 11) as f64 / (1_u64 << 53) as f64;
            check(10f64.powf(-14.0 + 34.0 * unit));
            check(-10f64.powf(-14.0 + 34.0 * unit));
            // Ten digits and a half: the ties and near-ties the fallback is for.
            check(((x >> 30) % 10_000_000_000) as f64 + 0.5);
        }
    }
}
