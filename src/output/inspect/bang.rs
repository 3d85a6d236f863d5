//! `uncoil inspect`'s account of the final bang's drawings: how many `/scene` drawings
//! follow the release (the ledger's `bang_time_s`), how many fall in its first
//! millisecond, in how many the tape's drawn midline crosses itself and how often at most
//! ([`crate::output::crossing`]), and the closest it comes to itself between parts at
//! least pi b apart along it. It reads the file and writes nothing.

use std::f64::consts::PI;
use std::fmt::Write as _;

use super::Inventory;
use crate::output::crossing::self_contact;
use crate::output::view::drawings::tape_drawings;
use crate::output::view::stamp_ns;

/// The final bang's drawings, as [`bang_drawings`] counts them.
#[derive(Debug, Clone, PartialEq)]
pub struct BangDrawings {
    /// The release: the last rolling step (s).
    pub release_s: f64,
    /// Drawings after the release.
    pub drawn: usize,
    /// Of them, those within 1 ms of the release.
    pub first_ms: usize,
    /// The first and the last one's time since the release (s), if any.
    pub span_s: Option<(f64, f64)>,
    /// Drawings in which the tape crosses itself.
    pub crossing: usize,
    /// The most crossings in one drawing, and that drawing's time since the release (s).
    pub most: (usize, f64),
    /// The tape's thickness b as drawn (m).
    pub thickness_m: f64,
    /// The closest the tape's midline comes to itself within b, between segments at least
    /// pi b apart along it (m; 0 where it crosses), and when (s since the release).
    pub closest: Option<(f64, f64)>,
    /// Why reading stopped early, for a file cut short.
    pub read_error: Option<String>,
}

/// The release's time from the inventory's ledger, if the run reached one and finished
/// its file.
pub fn release_s(inv: &Inventory) -> Option<f64> {
    inv.metadata
        .get("ledger")?
        .get("bang_time_s")?
        .parse::<f64>()
        .ok()
}

/// Counts the drawings after the release in `bytes` (an MCAP file whose inventory is
/// `inv`); `None` where the ledger names no release.
pub fn bang_drawings(bytes: &[u8], inv: &Inventory) -> anyhow::Result<Option<BangDrawings>> {
    let Some(release) = release_s(inv) else {
        return Ok(None);
    };
    let (drawings, read_error) = tape_drawings(bytes, Some(stamp_ns(release)))?;
    let mut out = BangDrawings {
        release_s: release,
        drawn: drawings.len(),
        first_ms: 0,
        span_s: None,
        crossing: 0,
        most: (0, 0.0),
        thickness_m: 0.0,
        closest: None,
        read_error,
    };
    for d in &drawings {
        let since = d.t_s - release;
        let b = d.thickness_m;
        out.thickness_m = out.thickness_m.max(b);
        out.first_ms += usize::from(since <= 1e-3);
        out.span_s = Some(out.span_s.map_or((since, since), |(a, _)| (a, since)));
        let contact = self_contact(&d.midline_m, b, PI * b);
        out.crossing += usize::from(contact.crossings > 0);
        if contact.crossings > out.most.0 {
            out.most = (contact.crossings, since);
        }
        if let Some(c) = contact.closest_m
            && out.closest.is_none_or(|(best, _)| c < best)
        {
            out.closest = Some((c, since));
        }
    }
    Ok(Some(out))
}

/// The account's lines, for `uncoil inspect`.
pub fn describe(bang: &BangDrawings) -> String {
    let mut o = String::new();
    let _ = writeln!(
        o,
        "The final bang's drawings (/scene after the release at t = {:.6} s):",
        bang.release_s
    );
    let ms = |s: f64| format!("{:.4} ms", s * 1e3);
    match bang.span_s {
        Some((a, z)) => {
            let _ = writeln!(
                o,
                "  drawn: {} ({} in its first millisecond), from {} to {} after the release",
                bang.drawn,
                bang.first_ms,
                ms(a),
                ms(z)
            );
        }
        None => {
            let _ = writeln!(o, "  drawn: 0");
        }
    }
    let _ = writeln!(
        o,
        "  the tape's drawn midline crosses itself in {} of them, at most {} times in one{}",
        bang.crossing,
        bang.most.0,
        if bang.most.0 > 0 {
            format!(" ({} after the release)", ms(bang.most.1))
        } else {
            String::new()
        }
    );
    let b = bang.thickness_m;
    match bang.closest {
        Some((0.0, at)) => {
            let _ = writeln!(
                o,
                "  closest approach (segments at least pi b apart along the tape): 0, where it \
                 crosses itself, first {} after the release",
                ms(at)
            );
        }
        Some((d, at)) => {
            let _ = writeln!(
                o,
                "  closest approach (segments at least pi b apart along the tape): {:.3} b \
                 ({:.3e} m, b = {b:.3e} m), {} after the release",
                d / b,
                d,
                ms(at)
            );
        }
        None => {
            let _ = writeln!(
                o,
                "  closest approach (segments at least pi b apart along the tape): never \
                 within b = {b:.3e} m"
            );
        }
    }
    if let Some(e) = &bang.read_error {
        let _ = writeln!(o, "  reading stopped early: {e}");
    }
    o
}
