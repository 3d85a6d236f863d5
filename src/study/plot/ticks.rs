//! A log axis's ticks, chosen before its chart is built: plotters' own log ticks start at
//! the first power of ten inside the range, so a range within one decade, or the part of one
//! below its first power of ten, would get none.

use plotters::coord::combinators::{BindKeyPoints, IntoLogRange, LogCoord, WithKeyPoints};

/// The ticks of a log axis: the values it marks and labels, chosen before the chart is
/// built (plotters' own log ticks start at the first power of ten inside the range, so a
/// range within one decade, or the part of one below its first power of ten, gets none).
/// The powers of ten and as many of their multiples as leave room between the labels;
/// where that gives fewer than two, evenly spaced values (steps of 1, 2 or 5 times a power
/// of ten) as close as the room allows.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct LogTicks {
    pub(super) values: Vec<f64>,
}

impl LogTicks {
    /// Ticks for an axis spanning `(lo, hi)` over `len_px`, each label needing `room_px`
    /// along it (a tick label's width on an x axis, its height on a y axis).
    pub(super) fn new((lo, hi): (f64, f64), len_px: u32, room_px: f64) -> Self {
        const SETS: [&[u8]; 4] = [
            &[1, 2, 3, 4, 5, 6, 7, 8, 9],
            &[1, 2, 3, 5],
            &[1, 2, 5],
            &[1],
        ];
        let per_decade = f64::from(len_px) / (hi / lo).log10().max(1e-9);
        let fits = |v: &[f64]| {
            v.len() >= 2
                && v.windows(2)
                    .all(|w| (w[1] / w[0]).log10() * per_decade >= room_px)
        };
        let (k0, k1) = (lo.log10().floor() as i32, hi.log10().ceil() as i32);
        for set in SETS {
            let values: Vec<f64> = (k0..=k1)
                .flat_map(|k| set.iter().map(move |&m| f64::from(m) * 10f64.powi(k)))
                .filter(|v| (lo..=hi).contains(v))
                .collect();
            if fits(&values) {
                return Self { values };
            }
        }
        // Within a decade: even steps, the finest that leaves room.
        let k = (hi - lo).log10().floor() as i32;
        for step in (k - 2..=k).flat_map(|k| [1.0, 2.0, 5.0].map(|m| m * 10f64.powi(k))) {
            let first = (lo / step).ceil() as i64;
            let values: Vec<f64> = (first..)
                .map(|i| i as f64 * step)
                .take_while(|v| *v <= hi)
                .collect();
            if fits(&values) {
                return Self { values };
            }
        }
        // No room for two: the power of ten inside, if any.
        let values = (k0..=k1)
            .map(|k| 10f64.powi(k))
            .filter(|v| (lo..=hi).contains(v))
            .collect();
        Self { values }
    }

    /// An axis over `(lo, hi)` with these ticks as its key points.
    pub(super) fn axis(&self, (lo, hi): (f64, f64)) -> LogAxis {
        (lo..hi).log_scale().with_key_points(self.values.clone())
    }

    /// The label of tick `v`: the fewest significant digits that give it back, `{:e}`.
    pub(super) fn label(v: &f64) -> String {
        (0..6)
            .map(|p| format!("{v:.p$e}"))
            .find(|s| {
                s.parse::<f64>()
                    .is_ok_and(|x| (x - v).abs() <= 1e-9 * v.abs())
            })
            .unwrap_or_else(|| format!("{v:e}"))
    }
}

/// A log axis with its ticks: see [`LogTicks`].
pub(super) type LogAxis = WithKeyPoints<LogCoord<f64>>;

#[cfg(test)]
mod tests {
    use super::*;

    /// The room a tick label needs along an x axis and a y axis (px), as the plots give it.
    const X_TICK_ROOM_PX: f64 = 56.0;
    const Y_TICK_ROOM_PX: f64 = 24.0;

    #[test]
    fn log_ticks_label_what_has_room() {
        // Two decades over 800 px: 400 px a decade, room for 1, 2, 3 and 5 at 56 px each.
        let ticks = LogTicks::new((1e-3, 1e-1), 800, X_TICK_ROOM_PX);
        let labels: Vec<String> = ticks.values.iter().map(LogTicks::label).collect();
        assert_eq!(
            labels,
            [
                "1e-3", "2e-3", "3e-3", "5e-3", "1e-2", "2e-2", "3e-2", "5e-2", "1e-1"
            ]
        );
        // Six decades over 300 px: the powers of ten alone.
        let ticks = LogTicks::new((1e-7, 1e-1), 300, X_TICK_ROOM_PX);
        assert_eq!(ticks.values.len(), 7);
        assert_eq!(LogTicks::label(&ticks.values[4]), "1e-3");
    }

    #[test]
    fn a_log_axis_within_a_decade_has_labelled_ticks() {
        // A two-point sweep's wall times, 0.055-0.13 s over 700 px: no power of ten inside
        // but 0.1, so the multiples and then even steps; every value labelled.
        let ticks = LogTicks::new((0.057, 0.0966), 700, X_TICK_ROOM_PX);
        assert!(ticks.values.len() >= 3, "{ticks:?}");
        assert!(ticks.values.iter().all(|v| (0.057..=0.0966).contains(v)));
        let labels: Vec<String> = ticks.values.iter().map(LogTicks::label).collect();
        assert!(
            labels.iter().all(|l| !l.is_empty() && l.len() <= 6),
            "{labels:?}"
        );
        assert_eq!(LogTicks::label(&0.075), "7.5e-2");
        assert_eq!(LogTicks::label(&(3.0 * 0.01)), "3e-2");
        // The part of a range below its first power of ten is marked too.
        let ticks = LogTicks::new((2e-4, 3e-2), 900, Y_TICK_ROOM_PX);
        assert!(ticks.values.iter().any(|v| *v < 1e-3), "{ticks:?}");
    }
}
