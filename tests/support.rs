//! Helpers shared by the test modules.

use uncoil::output::compare::SampleLog;
use uncoil::run::{RunReport, Sample, run};
use uncoil::scene::Scene;

/// Runs `scene` keeping every sample in memory; returns them with the report.
pub fn run_kept(scene: &Scene) -> (Vec<Sample>, RunReport) {
    let mut log = SampleLog::default();
    let report = run(scene, &mut [&mut log]).unwrap();
    (log.samples, report)
}

/// A legend box: its rectangle (x, y, width, height) and its place among the tags.
type LegendBox = ([f64; 4], usize);

/// A legend entry: its label's position, its box, its text.
type LegendLabel = (f64, f64, LegendBox, String);

/// A polyline of an SVG: its place among the tags, its stroke colour, width and points.
struct Polyline {
    index: usize,
    stroke: String,
    width: String,
    points: Vec<(f64, f64)>,
}

/// The value of attribute `name` in the tag `tag`.
fn attr<'a>(tag: &'a str, name: &str) -> Option<&'a str> {
    let start = tag.find(&format!(" {name}=\""))? + name.len() + 3;
    let len = tag[start..].find('"')?;
    Some(&tag[start..start + len])
}

/// Checks the legends of an SVG drawn by `uncoil plot` or `uncoil sweep-report`: each legend
/// entry's swatch (the strokes left of its label, in its row of a legend box) is one stroke
/// for a solid line or several for a dashed one, and the chart holds a line of that colour
/// and width drawn the same way: a long polyline for a solid line, many short ones for a
/// dashed. Returns the swatches checked (label, colour, dashed).
pub fn check_legends(svg: &str) -> Vec<(String, String, bool)> {
    let tags: Vec<&str> = svg.split('<').skip(1).collect();
    let num = |t: &str, k: &str| -> f64 { attr(t, k).unwrap().parse().unwrap() };
    // Legend boxes, with their place among the tags: a legend is drawn over its chart.
    let boxes: Vec<LegendBox> = tags
        .iter()
        .enumerate()
        .filter(|(_, t)| t.starts_with("rect") && attr(t, "opacity") == Some("0.85"))
        .map(|(i, t)| (["x", "y", "width", "height"].map(|k| num(t, k)), i))
        .collect();
    let in_box = |b: &[f64; 4], (px, py): (f64, f64)| {
        px >= b[0] && px <= b[0] + b[2] && py >= b[1] && py <= b[1] + b[3]
    };
    // Legend labels: start-anchored text inside a box, with the text that follows the tag.
    let labels: Vec<LegendLabel> = tags
        .iter()
        .filter(|t| t.starts_with("text") && attr(t, "text-anchor") == Some("start"))
        .filter_map(|t| {
            let (x, y) = (num(t, "x"), num(t, "y"));
            let b = *boxes.iter().find(|(b, _)| in_box(b, (x, y)))?;
            let text = t.split_once('>').map_or("", |p| p.1).trim().to_owned();
            Some((x, y, b, text))
        })
        .collect();
    let lines: Vec<Polyline> = tags
        .iter()
        .enumerate()
        .filter(|(_, t)| t.starts_with("polyline"))
        .map(|(index, t)| Polyline {
            index,
            stroke: attr(t, "stroke").unwrap().to_owned(),
            width: attr(t, "stroke-width").unwrap_or("1").to_owned(),
            points: attr(t, "points")
                .unwrap()
                .split_whitespace()
                .map(|p| {
                    let (x, y) = p.split_once(',').unwrap();
                    (x.parse().unwrap(), y.parse().unwrap())
                })
                .collect(),
        })
        .collect();
    let in_a_legend = |l: &Polyline| {
        boxes
            .iter()
            .any(|(b, i)| l.index > *i && l.points.iter().all(|&p| in_box(b, p)))
    };
    let extent = |l: &Polyline| {
        let span = |f: fn(&(f64, f64)) -> f64| {
            let v: Vec<f64> = l.points.iter().map(f).collect();
            v.iter().copied().fold(f64::MIN, f64::max) - v.iter().copied().fold(f64::MAX, f64::min)
        };
        span(|p| p.0).hypot(span(|p| p.1))
    };
    let mut checked = Vec::new();
    for (x, y, (b, drawn_at), text) in labels {
        // The swatch: horizontal strokes drawn with the legend, in the label's row, between
        // the box's edge and the label.
        let swatch: Vec<&Polyline> = lines
            .iter()
            .filter(|l| {
                l.index > drawn_at
                    && l.points.iter().all(|&(px, py)| {
                        px >= b[0] && px < x && py >= y && py <= y + 14.0 && py == l.points[0].1
                    })
            })
            .collect();
        let Some(first) = swatch.first() else {
            continue; // a marker's legend (a circle), not a line's
        };
        let (stroke, width) = (first.stroke.clone(), first.width.clone());
        assert!(
            swatch
                .iter()
                .all(|l| l.stroke == stroke && l.width == width),
            "legend entry {text:?} mixes strokes"
        );
        let dashed = swatch.len() >= 2;
        let series: Vec<&Polyline> = lines
            .iter()
            .filter(|l| !in_a_legend(l) && l.stroke == stroke && l.width == width)
            .collect();
        let drawn_so = if dashed {
            series.iter().filter(|l| extent(l) <= 12.0).count() >= 3
        } else {
            series.iter().any(|l| extent(l) > 20.0)
        };
        assert!(
            drawn_so,
            "the legend shows {text:?} as a {} {stroke} line of width {width}, but no series \
             is drawn so",
            if dashed { "dashed" } else { "solid" }
        );
        checked.push((text, stroke, dashed));
    }
    checked
}
