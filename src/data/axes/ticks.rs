//! Tick marks of an [`Axis`]: the file's own, else round values on linear, log and mel axes.

use super::{Axis, AxisScale, Tick};

impl Axis {
    /// At most `max_count` ticks: the file's ticks when it gives them, else round values —
    /// 1-2-5 steps on linear axes (minute-friendly steps on clock-time axes, whole years on year
    /// axes), decades with 2 and 5 between them on log axes when few decades are shown. Linear
    /// ticks include the ends when those are round; log ticks lie strictly inside the axis.
    pub fn ticks(&self, max_count: usize) -> Vec<Tick> {
        if let Some(ticks) = self.ticks.as_ref().filter(|t| !self.are_plain_years(t)) {
            // Up to 100 as the file gives them; more (which no axis can show) thinned evenly to
            // `max_count`, so a file's tick list cannot make every picture lay out a million
            // labels.
            let step = if ticks.len() > 100 {
                ticks.len().div_ceil(max_count.max(1))
            } else {
                1
            };
            return ticks.iter().step_by(step).cloned().collect();
        }
        if max_count == 0 || self.problem().is_some() {
            return Vec::new();
        }
        if self.is_degenerate() {
            return vec![Tick {
                at: 0.0,
                label: self.format_value(self.min),
            }];
        }
        let ticks = match self.scale {
            AxisScale::Linear => self.linear_ticks(max_count),
            AxisScale::Log => self.log_ticks(max_count),
            AxisScale::Mel => self.mel_ticks(max_count),
        };
        if ticks.is_empty() {
            self.end_ticks(max_count)
        } else {
            ticks
        }
    }

    /// Whether a file's `ticks` are only whole years, each where its year lies on this linear
    /// year axis (a timeline with x by year). The axis computes such ticks itself, as many as
    /// `max_count` allows (every 2 or 5 years over a span of 14), where a file may give one
    /// tick a decade ("2000" alone for 1996 to 2009). Ticks elsewhere (a timeline by order:
    /// each year's first song) are the file's to place.
    fn are_plain_years(&self, ticks: &[Tick]) -> bool {
        self.unit == "year"
            && self.scale == AxisScale::Linear
            && self.problem().is_none()
            && !self.is_degenerate()
            && !ticks.is_empty()
            && ticks.iter().all(|tick| {
                tick.label.trim().parse::<i32>().is_ok_and(|year| {
                    (self.normalized_of(f64::from(year)) - f64::from(tick.at)).abs() < 1e-4
                })
            })
    }

    /// When no round values fit (a span too small for f64 to step through, or too wide for a
    /// step to exist): the ends themselves, as read-outs, or the middle when one tick is wanted.
    fn end_ticks(&self, max_count: usize) -> Vec<Tick> {
        if max_count == 1 {
            return vec![Tick {
                at: 0.0,
                label: self.format_value(self.value_at(0.0)),
            }];
        }
        vec![
            Tick {
                at: -1.0,
                label: self.format_value(self.min),
            },
            Tick {
                at: 1.0,
                label: self.format_value(self.max),
            },
        ]
    }

    fn linear_ticks(&self, max_count: usize) -> Vec<Tick> {
        /// Beyond this many steps from 0, f64 cannot tell neighbouring ticks apart.
        const MAX_STEPS_FROM_ZERO: f64 = 1e15;
        let (lo, hi) = (self.min.min(self.max), self.min.max(self.max));
        // The span of ends near the largest f64 overflows; its half does not.
        let half_span = hi * 0.5 - lo * 0.5;
        if !(half_span > 0.0 && half_span.is_finite()) {
            return Vec::new();
        }
        // Tick indices k (ticks at k * step) from first to last, when f64 can hold them.
        let range_for = |step: f64| -> Option<(i64, i64)> {
            let eps = step * 1e-9;
            let first = ((lo - eps) / step).ceil();
            let last = ((hi + eps) / step).floor();
            let fits = |k: f64| k.is_finite() && k.abs() <= MAX_STEPS_FROM_ZERO;
            (fits(first) && fits(last) && first <= last).then_some((first as i64, last as i64))
        };
        let Some((step, first, last)) = self
            .step_candidates(half_span, max_count)
            .into_iter()
            .find_map(|step| {
                let (first, last) = range_for(step)?;
                (last - first < max_count as i64).then_some((step, first, last))
            })
        else {
            return Vec::new();
        };
        (first..=last)
            .map(|k| {
                let value = k as f64 * step;
                Tick {
                    at: self.normalized_of(value).clamp(-1.0, 1.0) as f32,
                    label: self.tick_label(value, step),
                }
            })
            .collect()
    }

    /// Steps to try, smallest first, from about span / max_count upwards (`half_span` is half
    /// the span, finite and positive); every one finite and positive.
    fn step_candidates(&self, half_span: f64, max_count: usize) -> Vec<f64> {
        let rough = half_span / max_count as f64 * 2.0;
        let mut steps = Vec::new();
        if self.is_clock() && rough >= 1.0 {
            const CLOCK: [f64; 14] = [
                1.0, 2.0, 5.0, 10.0, 15.0, 30.0, 60.0, 120.0, 300.0, 600.0, 900.0, 1800.0, 3600.0,
                7200.0,
            ];
            steps.extend(CLOCK.iter().copied().filter(|&s| s >= rough * 0.5));
            let mut hours = 18000.0;
            while steps.len() < 40 {
                steps.push(hours);
                hours *= 2.0;
            }
            return steps;
        }
        // f64 decades run from 1e-324 to 1e308: clamp so the 40 tried stay in range.
        let mut exponent = (rough.log10().floor() - 1.0).clamp(-330.0, 310.0) as i32;
        if self.unit == "year" {
            exponent = exponent.max(0);
        }
        for _ in 0..40 {
            let decade = 10f64.powi(exponent);
            steps.extend([decade, 2.0 * decade, 5.0 * decade]);
            exponent += 1;
        }
        steps.retain(|s| s.is_finite() && *s > 0.0);
        steps
    }

    fn log_ticks(&self, max_count: usize) -> Vec<Tick> {
        let (lo, hi) = (self.min.min(self.max), self.min.max(self.max));
        let inside = |v: f64| v > lo * (1.0 + 1e-9) && v < hi * (1.0 - 1e-9);
        let first_decade = lo.log10().floor() as i32;
        let last_decade = hi.log10().ceil() as i32;
        let values_for = |mantissas: &[f64], decade_stride: i32| -> Vec<f64> {
            let mut values = Vec::new();
            let mut decade = first_decade;
            while decade <= last_decade {
                for &m in mantissas {
                    let v = m * 10f64.powi(decade);
                    if inside(v) {
                        values.push(v);
                    }
                }
                decade += decade_stride;
            }
            values
        };
        let mut chosen = values_for(&[1.0, 2.0, 5.0], 1);
        if chosen.len() > max_count {
            chosen = values_for(&[1.0], 1);
        }
        let mut stride = 2;
        while chosen.len() > max_count && stride < 400 {
            chosen = values_for(&[1.0], stride);
            stride *= 2;
        }
        if chosen.len() > max_count {
            return Vec::new();
        }
        chosen
            .into_iter()
            .map(|value| Tick {
                at: self.normalized_of(value) as f32,
                label: self.tick_label(value, value),
            })
            .collect()
    }

    /// Round values for a mel axis, which is nearly linear below 700 Hz and nearly logarithmic
    /// above: 1..9 times a power of ten, taken greedily in order of roundness (1, 5, 2, then the
    /// rest; larger decades first) where they stand at least 90 % of an even spacing from every
    /// tick taken, then sorted along the axis. Strictly inside the axis, like log ticks.
    fn mel_ticks(&self, max_count: usize) -> Vec<Tick> {
        let (lo, hi) = (self.min.min(self.max), self.min.max(self.max));
        if hi.is_nan() || hi <= 0.0 {
            return Vec::new();
        }
        let inside = |v: f64| v > lo + (hi - lo) * 1e-9 && v < hi * (1.0 - 1e-9);
        let first_decade = (lo.max(hi * 1e-12)).log10().floor() as i32;
        let last_decade = hi.log10().ceil() as i32;
        let mut candidates = Vec::new();
        for mantissa in [1.0, 5.0, 2.0, 3.0, 4.0, 6.0, 7.0, 8.0, 9.0] {
            for decade in (first_decade..=last_decade).rev() {
                let value = mantissa * 10f64.powi(decade);
                if inside(value) {
                    candidates.push(value);
                }
            }
        }
        let gap = 2.0 / max_count as f64 * 0.9;
        let mut chosen: Vec<(f64, f64)> = Vec::new();
        for value in candidates {
            if chosen.len() == max_count {
                break;
            }
            let at = self.normalized_of(value);
            if at.is_finite() && chosen.iter().all(|&(_, other)| (other - at).abs() >= gap) {
                chosen.push((value, at));
            }
        }
        chosen.sort_by(|a, b| a.1.total_cmp(&b.1));
        chosen
            .into_iter()
            .map(|(value, at)| Tick {
                at: at as f32,
                label: self.tick_label(value, value),
            })
            .collect()
    }
}
