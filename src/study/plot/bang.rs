//! `bang.svg`: the tape's shape through the final bang as a filmstrip, from the `/scene`
//! drawings of the run's `run.mcap` (read back by [`crate::output::view::drawings`]). Its
//! panels are drawings at times since the release spaced evenly in log time from the bang's
//! first drawing to its last (its impacts take microseconds, its settling a tenth of a
//! second); each shows the floor, the tape as a band of its thickness b about its drawn
//! midline, at one scale in x and y, red rings where the midline crosses itself, and a
//! dashed line where the tape's end comes to rest. It reads the run's files and runs nothing.

use std::path::{Path, PathBuf};

use plotters::prelude::*;

use super::{Area, DESC_PX, HouseStyle, LinChart, TICK_PX, err, font};
use crate::output::crossing::crossing_points;
pub use crate::output::folder::BANG_SVG;
use crate::output::folder::LOG;
use crate::output::view::drawings::{TapeDrawing, tape_drawings};
use crate::output::view::stamp_ns;

/// Panels of the filmstrip, where the bang has that many drawings.
pub const BANG_PANELS: usize = 10;

/// The canvas's width (px), its panels in [`COLUMNS`] columns.
const WIDTH: u32 = 1000;
const COLUMNS: usize = 2;
/// A panel's margin, and its label areas (px).
const PANEL_MARGIN: u32 = 8;
const PANEL_X_LABELS: u32 = 30;
const PANEL_Y_LABELS: u32 = 56;
/// The title's height above the panels (px): three lines.
const TITLE_PX: u32 = 68;

/// The floor, the tape's band, its midline, its crossings, where its end comes to rest.
const FLOOR: RGBColor = RGBColor(200, 200, 200);
const BAND: RGBColor = RGBColor(140, 175, 225);
const MIDLINE: RGBColor = RGBColor(26, 64, 153);
const CROSSING: RGBColor = RGBColor(214, 39, 40);
const REST: RGBColor = RGBColor(148, 103, 189);

/// `bang.svg` drawn, or why not.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum BangPicture {
    /// Written at this path.
    Drawn(PathBuf),
    /// Not drawn, for this reason.
    Skipped(String),
}

/// Draws `dir/bang.svg` from `dir/run.mcap`'s drawings after the release at `release`
/// (s; `None`: the run ended before its bang), for the scene `name`.
pub fn bang_plot(dir: &Path, release: Option<f64>, name: &str) -> anyhow::Result<BangPicture> {
    let Some(release) = release else {
        return Ok(BangPicture::Skipped(
            "the run ended before its final bang".into(),
        ));
    };
    let log = dir.join(LOG);
    if !log.exists() {
        return Ok(BangPicture::Skipped(format!(
            "{} has no {LOG} (a run with --no-mcap): the tape's shape is only in its /scene \
             drawings",
            dir.display()
        )));
    }
    let bytes =
        std::fs::read(&log).map_err(|e| anyhow::anyhow!("cannot read {}: {e}", log.display()))?;
    let (drawings, _) = tape_drawings(&bytes, Some(stamp_ns(release)))?;
    if drawings.iter().all(|d| d.midline_m.len() < 2) {
        return Ok(BangPicture::Skipped(format!(
            "{} has no drawing of the tape after the release (output.scene_rate_hz = 0?)",
            log.display()
        )));
    }
    let picked = panel_drawings(&drawings, release, BANG_PANELS);
    let panels: Vec<&TapeDrawing> = picked.iter().map(|&i| &drawings[i]).collect();
    let last = drawings.last().and_then(|d| d.midline_m.last().copied());
    let rest_x = last.map_or(0.0, |p| p[0]);
    let path = dir.join(BANG_SVG);
    draw(&path, &panels, release, rest_x, name)?;
    Ok(BangPicture::Drawn(path))
}

/// The drawings nearest (in log time) to `n` times since the release spaced evenly in log
/// time from the first drawing's to the last's, each taken once, in time order.
pub(crate) fn panel_drawings(drawings: &[TapeDrawing], release: f64, n: usize) -> Vec<usize> {
    let since: Vec<f64> = drawings
        .iter()
        .map(|d| (d.t_s - release).max(1e-12))
        .collect();
    let (Some(&a), Some(&z)) = (since.first(), since.last()) else {
        return Vec::new();
    };
    let mut picked: Vec<usize> = (0..n)
        .map(|k| {
            let f = if n > 1 {
                k as f64 / (n - 1) as f64
            } else {
                1.0
            };
            let target = (a.ln() + f * (z.ln() - a.ln())).exp();
            (0..since.len())
                .min_by(|&i, &j| {
                    let d = |m: usize| (since[m].ln() - target.ln()).abs();
                    d(i).total_cmp(&d(j))
                })
                .unwrap_or(0)
        })
        .collect();
    picked.dedup();
    picked
}

/// What a panel shows: x from `x0` to `x1` (m) and, at that scale, as much height as the
/// panel holds, with the floor below and the tape's points up to `top` (m) above it where
/// they fit (else the top `top` at the panel's top); the tape's thickness `b` (m).
#[derive(Debug, Clone, Copy)]
struct Window {
    x0: f64,
    x1: f64,
    top: f64,
    b: f64,
}

impl Window {
    /// The window that holds what moves in `panels`: their points off the floor (above 3/4
    /// b: the laid tape's midline lies at b/2) and their free ends, with room around them.
    fn whole(panels: &[&TapeDrawing], b: f64) -> Self {
        let (mut x0, mut x1, mut top) = (f64::INFINITY, f64::NEG_INFINITY, 2.0 * b);
        for d in panels {
            let lifted = d.midline_m.iter().filter(|p| p[1] > 0.75 * b);
            for p in lifted.chain(d.midline_m.last()) {
                (x0, x1, top) = (x0.min(p[0]), x1.max(p[0]), top.max(p[1]));
            }
        }
        if !x0.is_finite() {
            (x0, x1) = (0.0, 0.0);
        }
        let pad = 0.08 * (x1 - x0) + 3.0 * b;
        Self {
            x0: x0 - pad,
            x1: x1 + pad,
            top: 1.1 * top + 2.0 * b,
            b,
        }
    }

    /// The window `width` (m) wide about `d`'s free end, its end half way up where it is off
    /// the floor.
    fn about_end(d: &TapeDrawing, width: f64, aspect: f64) -> Self {
        let end = d.midline_m.last().copied().unwrap_or([0.0, 0.0]);
        Self {
            x0: end[0] - 0.5 * width,
            x1: end[0] + 0.5 * width,
            top: end[1] + 0.5 * width * aspect,
            b: d.thickness_m,
        }
    }

    /// The y range (m) that gives y the x axis's scale on a plot `aspect` (height / width)
    /// in pixels: the floor's top at `y = 0` a sixth of the way up if the tape up to `top`
    /// then fits, else `top` at the top.
    fn y_range(&self, aspect: f64) -> (f64, f64) {
        let span = (self.x1 - self.x0) * aspect;
        let y0 = (-span / 6.0).max(self.top - span);
        (y0, y0 + span)
    }
}

/// Text of a time since the release, to three digits, in microseconds below a millisecond.
fn since_label(s: f64) -> String {
    let (v, unit) = if s < 1e-3 {
        (s * 1e6, "µs")
    } else {
        (s * 1e3, "ms")
    };
    let digits = (2 - v.abs().max(1e-300).log10().floor() as i32).clamp(0, 6) as usize;
    format!("{v:.digits$} {unit}")
}

/// A length in mm, to three digits, without trailing zeros.
fn mm_label(m: f64) -> String {
    let v = m * 1e3;
    let digits = (2 - v.abs().max(1e-300).log10().floor() as i32).clamp(0, 6) as usize;
    let text = format!("{v:.digits$}");
    if text.contains('.') {
        text.trim_end_matches('0').trim_end_matches('.').to_owned()
    } else {
        text
    }
}

/// The band's width (px) the whole window needs for b to show: narrower, each panel gets a
/// second view about the tape's free end at [`ZOOM_BAND_PX`].
const MIN_BAND_PX: f64 = 4.0;
/// The band's width (px) in the view about the free end.
const ZOOM_BAND_PX: f64 = 6.0;

/// Writes the filmstrip of `panels` to `path`: one window over them all and, where b is
/// thinner than [`MIN_BAND_PX`] in it, each beside its view about its free end; `rest_x` is
/// where the tape's end comes to rest.
fn draw(
    path: &Path,
    panels: &[&TapeDrawing],
    release: f64,
    rest_x: f64,
    name: &str,
) -> anyhow::Result<()> {
    let b = panels.iter().map(|d| d.thickness_m).fold(0.0, f64::max);
    let mut whole = Window::whole(panels, b);
    // A panel no taller than square (x widened about its middle), no flatter than 1 : 4
    // (1 : 2.5 beside a view about the free end).
    let (mid, half) = (0.5 * (whole.x0 + whole.x1), 0.5 * (whole.x1 - whole.x0));
    let half = half.max(0.5 * (whole.top + 2.0 * b));
    (whole.x0, whole.x1) = (mid - half, mid + half);
    let col_w = WIDTH / COLUMNS as u32;
    let plot_w = f64::from(col_w - 2 * PANEL_MARGIN - PANEL_Y_LABELS);
    let zoom = b * plot_w / (whole.x1 - whole.x0) < MIN_BAND_PX;
    // Room for the view about the free end, which follows the tape up and down.
    let flattest = if zoom { 0.4 } else { 0.25 };
    let aspect = ((whole.top + 2.0 * b) / (whole.x1 - whole.x0)).clamp(flattest, 1.0);
    let views = if zoom { 2 } else { 1 };
    let rows = (panels.len() * views).div_ceil(COLUMNS).max(1);
    // The caption's line and its padding, as `DrawingArea::titled` lays it out.
    let caption = (1.5 * DESC_PX) as u32 + 5;
    let panel_h = (plot_w * aspect) as u32 + 2 * PANEL_MARGIN + PANEL_X_LABELS + caption;
    let root = SVGBackend::new(path, (WIDTH, TITLE_PX + panel_h * rows as u32)).into_drawing_area();
    root.fill(&WHITE).map_err(err)?;
    let (title, rest) = root.split_vertically(TITLE_PX);
    let lines = [
        format!(
            "{name}: the tape's shape through the final bang, from its release at t =              {release:.4} s"
        ),
        format!(
            "the tape: a band of its thickness b = {} mm about its drawn midline; black dot:              its free end",
            mm_label(b)
        ),
        "red rings: where the midline crosses itself; dashed: where the free end comes to          rest (x = 0; mm)"
            .to_owned(),
    ];
    let style = TextStyle::from(font(0.9 * DESC_PX).into_font());
    for (i, line) in lines.iter().enumerate() {
        title
            .draw_text(line, &style, (10, 4 + 20 * i as i32))
            .map_err(err)?;
    }
    let areas = rest.split_evenly((rows, COLUMNS));
    let mut areas = areas.iter();
    for d in panels {
        let when = since_label(d.t_s - release);
        let n = crossing_points(&d.midline_m).len();
        let s = if n == 1 { "" } else { "s" };
        let (Some(area), zoomed) = (areas.next(), zoom.then(|| areas.next()).flatten()) else {
            break;
        };
        panel(
            area,
            d,
            whole,
            rest_x,
            &format!("{when} after the release, {n} crossing{s}"),
        )?;
        if let Some(area) = zoomed {
            let width = ZOOM_BAND_PX.recip() * b * plot_w;
            let about = Window::about_end(d, width, aspect);
            panel(
                area,
                d,
                about,
                rest_x,
                &format!("{when}, about its free end"),
            )?;
        }
    }
    root.present().map_err(err)
}

/// One panel under `caption`: `d` in `win`, in mm from where the tape's end comes to rest
/// (`rest_x`), the tape as a band of its thickness.
fn panel(
    area: &Area<'_>,
    d: &TapeDrawing,
    win: Window,
    rest_x: f64,
    caption: &str,
) -> anyhow::Result<()> {
    let mm = |p: [f64; 2]| ((p[0] - rest_x) * 1e3, p[1] * 1e3);
    let area = area.titled(caption, font(DESC_PX)).map_err(err)?;
    let (w, h) = area.dim_in_pixel();
    let plot_w = f64::from(w.saturating_sub(2 * PANEL_MARGIN + PANEL_Y_LABELS)).max(1.0);
    let plot_h = f64::from(h.saturating_sub(2 * PANEL_MARGIN + PANEL_X_LABELS));
    let (y0, y1) = win.y_range(plot_h / plot_w);
    let (lo, hi) = (mm([win.x0, y0]), mm([win.x1, y1]));
    let mut chart = ChartBuilder::on(&area)
        .margin(PANEL_MARGIN)
        .x_label_area_size(PANEL_X_LABELS)
        .y_label_area_size(PANEL_Y_LABELS)
        .build_cartesian_2d(lo.0..hi.0, lo.1..hi.1)
        .map_err(err)?;
    chart
        .configure_mesh()
        .house_style()
        .label_style(font(0.8 * TICK_PX))
        .x_labels(6)
        .y_labels(3)
        .draw()
        .map_err(err)?;
    chart
        .draw_series([Rectangle::new([(lo.0, lo.1), (hi.0, 0.0)], FLOOR.filled())])
        .map_err(err)?;
    let bounds = [lo.0, hi.0, lo.1, hi.1];
    if inside((0.0, 0.0), bounds) {
        let rest = DashedLineSeries::new([(0.0, lo.1), (0.0, hi.1)], 6, 4, REST.stroke_width(2));
        chart.draw_series(rest).map_err(err)?;
    }
    let line: Vec<(f64, f64)> = d.midline_m.iter().map(|&p| mm(p)).collect();
    let band_px = (win.b * plot_w / (win.x1 - win.x0)).round().max(1.0);
    tape(&mut chart, &line, bounds, band_px)?;
    let end = line.last().filter(|p| inside(**p, bounds));
    chart
        .draw_series(end.map(|&p| Circle::new(p, 3, BLACK.filled())))
        .map_err(err)?;
    let rings = crossing_points(&d.midline_m)
        .into_iter()
        .map(mm)
        .filter(|p| inside(*p, bounds))
        .map(|p| Circle::new(p, 6, CROSSING.stroke_width(2)));
    chart.draw_series(rings).map_err(err)?;
    Ok(())
}

/// Whether `p` lies in `win` (x0, x1, y0, y1).
fn inside(p: (f64, f64), win: [f64; 4]) -> bool {
    p.0 >= win[0] && p.0 <= win[1] && p.1 >= win[2] && p.1 <= win[3]
}

/// The tape along `line` (mm) within `win`: a band `band_px` wide, each segment a stroke of
/// that width with a disc at each node (a round join, so that the band is b wide through
/// its kinks), and its midline on top where the band is wide enough to hold it.
fn tape(
    chart: &mut LinChart<'_, '_>,
    line: &[(f64, f64)],
    win: [f64; 4],
    band_px: f64,
) -> anyhow::Result<()> {
    let width = band_px as u32;
    let segments: Vec<[(f64, f64); 2]> = line
        .windows(2)
        .filter_map(|s| clip(s[0], s[1], win))
        .collect();
    let band = BAND.stroke_width(width);
    chart
        .draw_series(segments.iter().map(|s| PathElement::new(s.to_vec(), band)))
        .map_err(err)?;
    if band_px >= 3.0 {
        let r = (0.5 * band_px).round() as i32;
        let joins = line.iter().filter(|p| inside(**p, win));
        chart
            .draw_series(joins.map(|&p| Circle::new(p, r, BAND.filled())))
            .map_err(err)?;
    }
    let mid = MIDLINE.stroke_width(if band_px >= 4.0 { 1 } else { 2 });
    chart
        .draw_series(segments.iter().map(|s| PathElement::new(s.to_vec(), mid)))
        .map_err(err)?;
    Ok(())
}

/// The part of segment `p q` inside `win` (x0, x1, y0, y1), if any (Liang and Barsky).
fn clip(p: (f64, f64), q: (f64, f64), win: [f64; 4]) -> Option<[(f64, f64); 2]> {
    let (dx, dy) = (q.0 - p.0, q.1 - p.1);
    let (mut t0, mut t1) = (0.0_f64, 1.0_f64);
    for (den, num) in [
        (-dx, p.0 - win[0]),
        (dx, win[1] - p.0),
        (-dy, p.1 - win[2]),
        (dy, win[3] - p.1),
    ] {
        if den == 0.0 {
            if num < 0.0 {
                return None;
            }
        } else {
            let t = num / den;
            if den < 0.0 {
                t0 = t0.max(t);
            } else {
                t1 = t1.min(t);
            }
        }
    }
    (t0 <= t1).then_some([
        (p.0 + t0 * dx, p.1 + t0 * dy),
        (p.0 + t1 * dx, p.1 + t1 * dy),
    ])
}

#[cfg(test)]
mod tests {
    use super::*;

    fn drawing(t_s: f64) -> TapeDrawing {
        TapeDrawing {
            t_s,
            thickness_m: 0.005,
            midline_m: vec![[0.0, 0.0025], [1.0, 0.0025]],
        }
    }

    #[test]
    fn panels_are_spaced_in_log_time_from_the_first_drawing_to_the_last() {
        // Drawings every 1 % of time since a release at 2 s, from 10 us to 0.1 s.
        let drawings: Vec<TapeDrawing> = (0..=926)
            .map(|k| drawing(2.0 + 1e-5 * 1.01_f64.powi(k)))
            .collect();
        let picked = panel_drawings(&drawings, 2.0, 5);
        assert_eq!(picked.len(), 5);
        assert_eq!(picked[0], 0);
        assert_eq!(*picked.last().unwrap(), 926);
        // A decade apart: 231 drawings of 1 % each.
        for w in picked.windows(2) {
            assert!((230..=233).contains(&(w[1] - w[0])), "{picked:?}");
        }
        // Fewer drawings than panels: each once.
        let few: Vec<TapeDrawing> = (1..=3)
            .map(|k| drawing(2.0 + 1e-3 * f64::from(k)))
            .collect();
        assert_eq!(panel_drawings(&few, 2.0, 10), [0, 1, 2]);
    }

    #[test]
    fn clipping_keeps_what_lies_in_the_window() {
        let win = [0.0, 10.0, 0.0, 5.0];
        assert_eq!(
            clip((-5.0, 1.0), (5.0, 1.0), win),
            Some([(0.0, 1.0), (5.0, 1.0)])
        );
        assert_eq!(clip((-5.0, 6.0), (5.0, 6.0), win), None);
        assert_eq!(
            clip((2.0, 2.0), (3.0, 3.0), win),
            Some([(2.0, 2.0), (3.0, 3.0)])
        );
        assert_eq!(
            clip((5.0, -5.0), (5.0, 10.0), win),
            Some([(5.0, 0.0), (5.0, 5.0)])
        );
    }

    #[test]
    fn times_are_labelled_to_three_digits() {
        assert_eq!(since_label(8.5e-8), "0.0850 µs");
        assert_eq!(since_label(2.18e-5), "21.8 µs");
        assert_eq!(since_label(3.7e-4), "370 µs");
        assert_eq!(since_label(0.00245), "2.45 ms");
        assert_eq!(since_label(0.10999), "110 ms");
    }
}
