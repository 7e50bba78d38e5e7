//! Axes in physical units.
//!
//! Every coordinate of a loudscape point is normalized: `x`, `y`, `z` lie in [-1, 1] and `scalar`,
//! `hp` in [0, 1]. An [`Axis`] (one per coordinate, read from the file's `loudscape-meta`, see
//! docs/FORMAT.md) says what those normalized numbers mean: a label, a unit, the physical values
//! at the two ends, and whether the mapping is linear or logarithmic (log: linear in log10 of the
//! value). This module turns that into what a person reads: tick marks with labels ("2 kHz",
//! "-24 dB", "1:30", "1984"), hover read-outs with more precision, and note names for
//! frequencies ("A4", "C#5 +12 ct").
//!
//! Conventions, kept the same everywhere:
//! - Normalized positions passed to or returned by [`Axis`] methods are in [-1, 1] (the position
//!   axes' convention). For the `scalar` and `hp` axes, whose file coordinates are in [0, 1], use
//!   [`Axis::value_at_unit`] and [`Axis::unit_of`].
//! - Time (unit `"s"`) is written `"12 s"` when the axis spans less than a minute, and as a clock
//!   (`"1:05"`, `"1:02:03"`) when either end is a minute or more, for every label of that axis.
//! - Numbers use an ASCII minus sign and no thousands separator; years have no unit suffix.

use serde::{Deserialize, Serialize};

/// How normalized coordinates map to physical values.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum AxisScale {
    /// value = min + t * (max - min), t in [0, 1].
    #[default]
    Linear,
    /// log10(value) = log10(min) + t * (log10(max) - log10(min)); min and max are positive.
    Log,
    /// mel(value) = mel(min) + t * (mel(max) - mel(min)), with the HTK mel scale
    /// `mel(f) = 2595 log10(1 + f / 700)` (see [`mel_of_hz`]); min and max are at least 0.
    /// Files are written linear or log; the app builds mel axes at view time
    /// (src/data/freq_axis.rs).
    Mel,
}

/// The HTK mel of a frequency in Hz: `2595 log10(1 + f / 700)` (1000 Hz is 1000 mel).
pub fn mel_of_hz(hz: f64) -> f64 {
    2595.0 * (hz / 700.0).ln_1p() / std::f64::consts::LN_10
}

/// The frequency in Hz of a mel value (the inverse of [`mel_of_hz`]).
pub fn hz_of_mel(mel: f64) -> f64 {
    700.0 * (mel * std::f64::consts::LN_10 / 2595.0).exp_m1()
}

/// A tick mark: a normalized position in [-1, 1] and its label.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Tick {
    /// Normalized position, -1..1.
    pub at: f32,
    /// What to print there, units included.
    pub label: String,
}

/// One axis: what a normalized coordinate means in physical units.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Axis {
    /// For display, e.g. `"time"`, `"frequency"`, `"level"`.
    #[serde(default)]
    pub label: String,
    /// `"s"`, `"dB"`, `"Hz"`, `"year"`, or `""` for unitless; other units print after the number.
    #[serde(default)]
    pub unit: String,
    /// Physical value at normalized -1 (for `scalar` and `hp`: at 0).
    pub min: f64,
    /// Physical value at normalized +1 (for `scalar` and `hp`: at 1).
    pub max: f64,
    #[serde(default)]
    pub scale: AxisScale,
    /// Ticks given by the file, drawn instead of computed ones.
    #[serde(default)]
    pub ticks: Option<Vec<Tick>>,
}

/// The five axes of a point cloud.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Axes {
    pub x: Axis,
    pub y: Axis,
    pub z: Axis,
    pub scalar: Axis,
    pub hp: Axis,
}

impl Axes {
    /// Axes of a file without metadata: `x`, `y`, `z` over the given ranges (values at
    /// normalized -1 and +1), unitless `scalar` and `hp` over [0, 1].
    pub fn generic(ranges: [(f64, f64); 3]) -> Axes {
        let [x, y, z] = ranges;
        Axes {
            x: Axis::linear("x", "", x.0, x.1),
            y: Axis::linear("y", "", y.0, y.1),
            z: Axis::linear("z", "", z.0, z.1),
            scalar: Axis::linear("scalar", "", 0.0, 1.0),
            hp: Axis::linear("hp", "", 0.0, 1.0),
        }
    }

    /// The axes with their names as in the file: `[("x", x), ..., ("hp", hp)]`.
    pub fn named(&self) -> [(&'static str, &Axis); 5] {
        [
            ("x", &self.x),
            ("y", &self.y),
            ("z", &self.z),
            ("scalar", &self.scalar),
            ("hp", &self.hp),
        ]
    }
}

impl Axis {
    /// A linear axis without file ticks.
    pub fn linear(label: &str, unit: &str, min: f64, max: f64) -> Axis {
        Axis {
            label: label.to_owned(),
            unit: unit.to_owned(),
            min,
            max,
            scale: AxisScale::Linear,
            ticks: None,
        }
    }

    /// A logarithmic axis without file ticks (`min` and `max` must be positive).
    pub fn log(label: &str, unit: &str, min: f64, max: f64) -> Axis {
        Axis {
            scale: AxisScale::Log,
            ..Axis::linear(label, unit, min, max)
        }
    }

    /// Why this axis cannot map values, if it cannot: non-finite ends, or a log axis with an end
    /// that is not positive. Equal ends are allowed (docs/FORMAT.md: every coordinate on that
    /// axis is then 0, and every position reads the one value).
    pub fn problem(&self) -> Option<String> {
        if !self.min.is_finite() || !self.max.is_finite() {
            return Some(format!(
                "min {} and max {} must be finite numbers",
                self.min, self.max
            ));
        }
        if self.scale == AxisScale::Log && (self.min <= 0.0 || self.max <= 0.0) {
            return Some(format!(
                "a log axis needs positive min and max, found {} and {}",
                self.min, self.max
            ));
        }
        if self.scale == AxisScale::Mel && (self.min < 0.0 || self.max < 0.0) {
            return Some(format!(
                "a mel axis needs min and max of at least 0, found {} and {}",
                self.min, self.max
            ));
        }
        None
    }

    /// Whether both ends are the same value (every position reads it).
    pub fn is_degenerate(&self) -> bool {
        self.min == self.max
    }

    /// Physical value at a normalized position in [-1, 1]. Written so that no finite axis
    /// overflows in between (ends near the largest f64 included).
    pub fn value_at(&self, normalized: f64) -> f64 {
        let t = (normalized + 1.0) * 0.5;
        if self.is_degenerate() {
            return self.min;
        }
        match self.scale {
            AxisScale::Linear => self.min * (1.0 - t) + self.max * t,
            AxisScale::Log => {
                let (a, b) = (self.min.log10(), self.max.log10());
                10f64.powf(a + t * (b - a))
            }
            AxisScale::Mel => {
                let (a, b) = (mel_of_hz(self.min), mel_of_hz(self.max));
                hz_of_mel(a + t * (b - a))
            }
        }
    }

    /// Normalized position in [-1, 1] of a physical value (outside for values beyond the ends;
    /// NaN for a value that is not positive on a log axis). On an axis with equal ends the value
    /// itself is at 0, others at plus or minus infinity.
    pub fn normalized_of(&self, value: f64) -> f64 {
        if self.is_degenerate() {
            return if value == self.min {
                0.0
            } else if value.is_nan() {
                f64::NAN
            } else {
                (value - self.min).signum() * f64::INFINITY
            };
        }
        let t = match self.scale {
            // Halves first, so ends near the largest f64 do not overflow the span.
            AxisScale::Linear => (value * 0.5 - self.min * 0.5) / (self.max * 0.5 - self.min * 0.5),
            AxisScale::Log => {
                if value <= 0.0 {
                    return f64::NAN;
                }
                let (a, b) = (self.min.log10(), self.max.log10());
                (value.log10() - a) / (b - a)
            }
            AxisScale::Mel => {
                if value < 0.0 {
                    return f64::NAN;
                }
                let (a, b) = (mel_of_hz(self.min), mel_of_hz(self.max));
                (mel_of_hz(value) - a) / (b - a)
            }
        };
        t * 2.0 - 1.0
    }

    /// Physical value at a coordinate in [0, 1] (the `scalar` and `hp` convention).
    pub fn value_at_unit(&self, t: f64) -> f64 {
        self.value_at(t * 2.0 - 1.0)
    }

    /// Coordinate in [0, 1] of a physical value (the `scalar` and `hp` convention).
    pub fn unit_of(&self, value: f64) -> f64 {
        (self.normalized_of(value) + 1.0) * 0.5
    }

    /// At most `max_count` ticks: the file's ticks when it gives them, else round values —
    /// 1-2-5 steps on linear axes (minute-friendly steps on clock-time axes, whole years on year
    /// axes), decades with 2 and 5 between them on log axes when few decades are shown. Linear
    /// ticks include the ends when those are round; log ticks lie strictly inside the axis.
    pub fn ticks(&self, max_count: usize) -> Vec<Tick> {
        if let Some(ticks) = &self.ticks {
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

    /// A value as a hover read-out: like a tick label, with more precision.
    pub fn format_value(&self, value: f64) -> String {
        if !value.is_finite() {
            return format!("{value}");
        }
        match self.unit.as_str() {
            "s" if self.is_clock() => clock(value, 1),
            "s" => format!("{} s", fixed(value, 2)),
            "Hz" => hertz(value, None),
            "year" => fixed(value, 0),
            "" => fixed(value, significant_decimals(value, 3)),
            unit => format!("{} {unit}", fixed(value, 1)),
        }
    }

    /// The label of a tick at `value` on this axis, for ticks `step` apart (physical units).
    pub fn tick_label(&self, value: f64, step: f64) -> String {
        let decimals = step_decimals(step);
        match self.unit.as_str() {
            "s" if self.is_clock() => clock(value, step_decimals(step)),
            "s" => format!("{} s", fixed(value, decimals)),
            "Hz" => hertz(value, Some(step)),
            "year" => fixed(value, 0),
            "" => fixed(value, decimals),
            unit => format!("{} {unit}", fixed(value, decimals)),
        }
    }

    /// Whether time on this axis is written as a clock (`m:ss`): an end is a minute or more.
    fn is_clock(&self) -> bool {
        self.unit == "s" && self.min.abs().max(self.max.abs()) >= 60.0
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
}

impl Axis {
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

/// Decimals to show for values `step` apart (1-2-5 steps: 0.5 -> 1, 0.25 -> 2, 10 -> 0).
fn step_decimals(step: f64) -> usize {
    if !(step.is_finite() && step > 0.0) {
        return 0;
    }
    let mut decimals = 0;
    let mut scaled = step;
    while decimals < 9 && (scaled - scaled.round()).abs() > 1e-6 * scaled.max(1.0) {
        scaled *= 10.0;
        decimals += 1;
    }
    decimals
}

/// Decimals that show `digits` significant digits of `value` (at most 6).
fn significant_decimals(value: f64, digits: i32) -> usize {
    if value == 0.0 || !value.is_finite() {
        return 0;
    }
    let magnitude = value.abs().log10().floor() as i32;
    (digits - 1 - magnitude).clamp(0, 6) as usize
}

/// Beyond this magnitude numbers are written in scientific notation (`1.000e20`): f64 has no
/// more digits to show, and a plain 1e300 would be 301 characters.
const SCIENTIFIC_FROM: f64 = 1e15;

/// `value` with `decimals` decimals, ASCII minus, no "-0"; scientific beyond 1e15.
fn fixed(value: f64, decimals: usize) -> String {
    if value.abs() >= SCIENTIFIC_FROM {
        return format!("{value:.3e}");
    }
    let text = format!("{value:.decimals$}");
    match text.strip_prefix('-') {
        Some(rest) if rest.chars().all(|c| c == '0' || c == '.') => rest.to_owned(),
        _ => text,
    }
}

/// Seconds as a clock: `m:ss` or `h:mm:ss`, with `decimals` decimals on the seconds.
fn clock(seconds: f64, decimals: usize) -> String {
    if seconds.abs() >= SCIENTIFIC_FROM || seconds.is_nan() {
        return format!("{} s", fixed(seconds, 0));
    }
    let sign = if seconds < 0.0 { "-" } else { "" };
    let scale = 10f64.powi(decimals as i32);
    let total = (seconds.abs() * scale).round() / scale;
    let hours = (total / 3600.0).floor();
    let minutes = ((total - hours * 3600.0) / 60.0).floor();
    let secs = total - hours * 3600.0 - minutes * 60.0;
    let width = if decimals > 0 { decimals + 3 } else { 2 };
    let secs = format!("{secs:0width$.decimals$}");
    if hours > 0.0 {
        format!("{sign}{hours}:{minutes:02}:{secs}")
    } else {
        format!("{sign}{minutes}:{secs}")
    }
}

/// A frequency: `"500 Hz"`, `"2 kHz"`, `"12.5 kHz"`. With `step`, decimals follow the tick
/// spacing; without, the read-out keeps four significant digits.
fn hertz(value: f64, step: Option<f64>) -> String {
    let kilo = value.abs() >= 1000.0;
    let (shown, unit) = if kilo {
        (value / 1000.0, "kHz")
    } else {
        (value, "Hz")
    };
    let decimals = match step {
        Some(step) => {
            let shown_step = if kilo { step / 1000.0 } else { step };
            step_decimals(shown_step).min(significant_decimals(shown, 3))
        }
        None => significant_decimals(shown, 4),
    };
    format!("{} {unit}", fixed(shown, decimals))
}

/// The nearest equal-tempered note to a frequency (A4 = 440 Hz) and the deviation in cents:
/// `"A4"`, `"C#5 +12 ct"`, `"E2 -30 ct"`. None for a frequency that is not a positive number or
/// lies outside the MIDI-like range C-1 (8.2 Hz) .. about 100 kHz.
pub fn note_name(hz: f64) -> Option<String> {
    const NAMES: [&str; 12] = [
        "C", "C#", "D", "D#", "E", "F", "F#", "G", "G#", "A", "A#", "B",
    ];
    if !(hz.is_finite() && hz > 0.0) {
        return None;
    }
    let midi = 69.0 + 12.0 * (hz / 440.0).log2();
    let nearest = midi.round();
    if !(-0.5..=200.0).contains(&nearest) {
        return None;
    }
    let cents = ((midi - nearest) * 100.0).round() as i64;
    let nearest = nearest as i64;
    let name = NAMES[nearest.rem_euclid(12) as usize];
    let octave = nearest.div_euclid(12) - 1;
    Some(if cents == 0 {
        format!("{name}{octave}")
    } else {
        format!("{name}{octave} {cents:+} ct")
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn labels(ticks: &[Tick]) -> Vec<&str> {
        ticks.iter().map(|t| t.label.as_str()).collect()
    }

    #[test]
    fn linear_seconds_short() {
        let axis = Axis::linear("time", "s", 0.0, 30.0);
        let ticks = axis.ticks(8);
        assert_eq!(
            labels(&ticks),
            ["0 s", "5 s", "10 s", "15 s", "20 s", "25 s", "30 s"]
        );
        assert_eq!(ticks[0].at, -1.0);
        assert_eq!(ticks[6].at, 1.0);
        assert_eq!(axis.format_value(12.345), "12.35 s");
    }

    #[test]
    fn linear_seconds_clock() {
        let axis = Axis::linear("time", "s", 0.0, 215.0);
        let ticks = axis.ticks(8);
        assert_eq!(
            labels(&ticks),
            [
                "0:00", "0:30", "1:00", "1:30", "2:00", "2:30", "3:00", "3:30"
            ]
        );
        assert_eq!(labels(&axis.ticks(4)), ["0:00", "1:00", "2:00", "3:00"]);
        let axis = Axis::linear("time", "s", 0.0, 65.0);
        assert_eq!(
            labels(&axis.ticks(8)),
            ["0:00", "0:10", "0:20", "0:30", "0:40", "0:50", "1:00"]
        );
        assert_eq!(axis.format_value(65.25), "1:05.3");
        assert_eq!(
            Axis::linear("t", "s", 0.0, 4000.0).format_value(3723.0),
            "1:02:03.0"
        );
    }

    #[test]
    fn negative_decibels() {
        let axis = Axis::linear("level", "dB", -60.0, 0.0);
        assert_eq!(
            labels(&axis.ticks(7)),
            [
                "-60 dB", "-50 dB", "-40 dB", "-30 dB", "-20 dB", "-10 dB", "0 dB"
            ]
        );
        let axis = Axis::linear("level", "dB", -48.0, 0.0);
        assert_eq!(labels(&axis.ticks(3)), ["-40 dB", "-20 dB", "0 dB"]);
        assert_eq!(axis.tick_label(-24.0, 6.0), "-24 dB");
        assert_eq!(axis.format_value(-23.456), "-23.5 dB");
        assert_eq!(axis.format_value(-0.01), "0.0 dB");
    }

    #[test]
    fn log_hertz() {
        let axis = Axis::log("frequency", "Hz", 20.0, 20000.0);
        assert_eq!(
            labels(&axis.ticks(10)),
            [
                "50 Hz", "100 Hz", "200 Hz", "500 Hz", "1 kHz", "2 kHz", "5 kHz", "10 kHz"
            ]
        );
        let ticks = axis.ticks(10);
        assert!((ticks[4].at as f64 - axis.normalized_of(1000.0)).abs() < 1e-6);
        // Few ticks wanted: decades only.
        assert_eq!(labels(&axis.ticks(4)), ["100 Hz", "1 kHz", "10 kHz"]);
        assert_eq!(axis.format_value(440.0), "440.0 Hz");
        assert_eq!(axis.format_value(1234.6), "1.235 kHz");
        assert_eq!(
            labels(&Axis::log("f", "Hz", 20.0, 22050.0).ticks(10)),
            [
                "50 Hz", "100 Hz", "200 Hz", "500 Hz", "1 kHz", "2 kHz", "5 kHz", "10 kHz",
                "20 kHz"
            ]
        );
    }

    #[test]
    fn log_mapping_round_trips() {
        let axis = Axis::log("frequency", "Hz", 20.0, 20000.0);
        assert!((axis.value_at(-1.0) - 20.0).abs() < 1e-9);
        assert!((axis.value_at(1.0) - 20000.0).abs() < 1e-6);
        assert!((axis.value_at(0.0) - 632.455_532).abs() < 1e-3);
        for v in [20.0, 100.0, 1000.0, 15000.0] {
            assert!((axis.value_at(axis.normalized_of(v)) - v).abs() < 1e-6 * v);
        }
        assert!(axis.normalized_of(0.0).is_nan());
    }

    #[test]
    fn mel_axis_maps_and_ticks() {
        // HTK: 999.99 mel at 1 kHz.
        assert!((mel_of_hz(1000.0) - 1000.0).abs() < 0.05);
        assert!((hz_of_mel(mel_of_hz(440.0)) - 440.0).abs() < 1e-9);
        let axis = Axis {
            scale: AxisScale::Mel,
            ..Axis::linear("frequency", "Hz", 0.0, 11025.0)
        };
        assert_eq!(axis.problem(), None);
        assert_eq!(axis.normalized_of(0.0), -1.0);
        assert!((axis.normalized_of(11025.0) - 1.0).abs() < 1e-12);
        for v in [0.0, 50.0, 1000.0, 8000.0] {
            assert!((axis.value_at(axis.normalized_of(v)) - v).abs() < 1e-6 * v.max(1.0));
        }
        // Mel gives the bass more room than linear and less than log.
        let at_500 = axis.normalized_of(500.0);
        let linear = Axis::linear("f", "Hz", 0.0, 11025.0).normalized_of(500.0);
        let log = Axis::log("f", "Hz", 5.0, 11025.0).normalized_of(500.0);
        assert!(linear < at_500 && at_500 < log, "{linear} {at_500} {log}");
        let ticks = axis.ticks(8);
        assert_eq!(
            labels(&ticks),
            ["100 Hz", "500 Hz", "1 kHz", "2 kHz", "5 kHz", "10 kHz"]
        );
        for pair in ticks.windows(2) {
            assert!(
                pair[1].at - pair[0].at >= 0.9 * 2.0 / 8.0 - 1e-6,
                "{ticks:?}"
            );
        }
        for n in 1..12 {
            assert!(axis.ticks(n).len() <= n);
        }
        assert!(axis.normalized_of(-1.0).is_nan());
    }

    #[test]
    fn years() {
        let axis = Axis::linear("year", "year", 1960.0, 2024.0);
        let ticks = axis.ticks(8);
        assert_eq!(
            labels(&ticks),
            ["1960", "1970", "1980", "1990", "2000", "2010", "2020"]
        );
        let axis = Axis::linear("year", "year", 1983.0, 1986.0);
        assert_eq!(labels(&axis.ticks(10)), ["1983", "1984", "1985", "1986"]);
        assert_eq!(axis.format_value(1984.2), "1984");
    }

    #[test]
    fn unitless_and_other_units() {
        let axis = Axis::linear("hp", "", 0.0, 1.0);
        assert_eq!(
            labels(&axis.ticks(6)),
            ["0.0", "0.2", "0.4", "0.6", "0.8", "1.0"]
        );
        assert_eq!(axis.format_value(0.52345), "0.523");
        assert!((axis.value_at_unit(0.25) - 0.25).abs() < 1e-12);
        assert!((axis.unit_of(0.75) - 0.75).abs() < 1e-12);
        let axis = Axis::linear("loudness", "LUFS", -30.0, -5.0);
        assert_eq!(
            labels(&axis.ticks(6)),
            [
                "-30 LUFS", "-25 LUFS", "-20 LUFS", "-15 LUFS", "-10 LUFS", "-5 LUFS"
            ]
        );
    }

    #[test]
    fn file_ticks_win_and_bad_axes_give_none() {
        let mut axis = Axis::linear("x", "", 0.0, 1.0);
        axis.ticks = Some(vec![Tick {
            at: 0.0,
            label: "middle".into(),
        }]);
        assert_eq!(labels(&axis.ticks(5)), ["middle"]);
        assert_eq!(labels(&Axis::linear("x", "", 1.0, 1.0).ticks(5)), ["1.00"]);
        assert!(Axis::log("f", "Hz", 0.0, 10.0).ticks(5).is_empty());
        assert!(Axis::linear("x", "", f64::NAN, 1.0).ticks(5).is_empty());
        assert!(Axis::linear("x", "", 0.0, 1.0).ticks(0).is_empty());
        // Inverted axes still tick.
        assert_eq!(Axis::linear("x", "", 10.0, 0.0).ticks(3).len(), 3);
    }

    #[test]
    fn tick_counts_stay_within_max() {
        for (min, max) in [
            (0.0, 1.0),
            (-3.7, 12.9),
            (0.0, 1e9),
            (1e-6, 2e-6),
            (-1.0, 1.0),
        ] {
            for n in 1..12 {
                let ticks = Axis::linear("v", "", min, max).ticks(n);
                assert!(ticks.len() <= n, "{min}..{max} n={n}: {ticks:?}");
                assert!(ticks.iter().all(|t| (-1.0..=1.0).contains(&t.at)));
            }
        }
        for n in 1..12 {
            assert!(Axis::log("f", "Hz", 20.0, 20000.0).ticks(n).len() <= n);
            assert!(Axis::log("f", "", 1e-30, 1e30).ticks(n).len() <= n);
        }
    }

    /// Every tick, label and read-out of `axis`, checked for what the labels and hover rely on.
    fn exercise(axis: &Axis) {
        for n in 0..14 {
            let ticks = axis.ticks(n);
            assert!(ticks.len() <= n.max(1), "{axis:?} n={n}: {ticks:?}");
            for tick in &ticks {
                assert!((-1.0..=1.0).contains(&tick.at), "{axis:?}: {tick:?}");
                assert!(!tick.label.is_empty() && tick.label.len() < 400);
            }
        }
        for t in [-1.0, -0.5, 0.0, 0.3, 1.0, 2.0, f64::NAN] {
            let value = axis.value_at(t);
            let _ = axis.format_value(value);
            let _ = axis.normalized_of(value);
            let _ = axis.tick_label(value, value.abs());
            let _ = note_name(value);
        }
        if axis.problem().is_none() && axis.scale == AxisScale::Linear {
            assert_eq!(axis.value_at(-1.0), axis.min, "{axis:?}");
            assert_eq!(axis.value_at(1.0), axis.max, "{axis:?}");
            assert!(axis.value_at(0.0).is_finite(), "{axis:?}");
        }
    }

    #[test]
    fn extreme_ranges_are_total() {
        let ends = [
            (-1e38, 1e38),
            (-f64::MAX, f64::MAX),
            (f64::MAX / 2.0, f64::MAX),
            (0.0, f64::MIN_POSITIVE),
            (1.0, 1.0 + f64::EPSILON),
            (1e300, 1e300 * (1.0 + 1e-15)),
            (-5e-324, 5e-324),
            (0.0, 5e-324),
            (1e15, 1e15 + 1.0),
            (-3.0, -3.0),
            (0.0, 0.0),
            (f64::MAX, f64::MAX),
            (2024.0, 2024.0),
        ];
        for (min, max) in ends {
            for unit in ["", "s", "Hz", "year", "dB"] {
                exercise(&Axis::linear("v", unit, min, max));
                exercise(&Axis::linear("v", unit, max, min));
                if min > 0.0 {
                    exercise(&Axis::log("v", unit, min, max));
                }
            }
        }
        exercise(&Axis::log("f", "Hz", f64::MIN_POSITIVE, f64::MAX));
        exercise(&Axis::log("f", "Hz", 5e-324, 1e308));
        // Labels and read-outs stay short whatever the magnitude.
        for value in [1e300, -f64::MAX, 1e20, 3.6e20] {
            for unit in ["", "s", "Hz", "year", "dB"] {
                let axis = Axis::linear("v", unit, -f64::MAX, f64::MAX);
                assert!(axis.format_value(value).len() < 40, "{unit} {value}");
                assert!(axis.tick_label(value, 1e19).len() < 40, "{unit} {value}");
            }
        }
        assert_eq!(fixed(1e20, 2), "1.000e20");
        // Wide ranges still get round ticks where f64 allows.
        let wide = Axis::linear("v", "", -1e38, 1e38);
        assert!(wide.ticks(5).len() >= 2);
    }

    #[test]
    fn equal_ends_read_their_value_at_zero() {
        let axis = Axis::linear("crest", "dB", 12.0, 12.0);
        assert_eq!(axis.problem(), None);
        assert_eq!(axis.value_at(0.0), 12.0);
        assert_eq!(axis.value_at(0.7), 12.0);
        assert_eq!(axis.normalized_of(12.0), 0.0);
        assert_eq!(axis.normalized_of(13.0), f64::INFINITY);
        let ticks = axis.ticks(6);
        assert_eq!(labels(&ticks), ["12.0 dB"]);
        assert_eq!(ticks[0].at, 0.0);
        let year = Axis::linear("year", "year", 1984.0, 1984.0);
        assert_eq!(labels(&year.ticks(6)), ["1984"]);
        let log = Axis::log("f", "Hz", 440.0, 440.0);
        assert_eq!(log.problem(), None);
        assert_eq!(log.value_at(0.2), 440.0);
        // Spans at the limit of f64 still get a tick or two (round values, else the ends).
        for (min, max) in [
            (1.0, 1.0 + 4.0 * f64::EPSILON),
            (1e300, 1e300 * (1.0 + 1e-15)),
        ] {
            let tiny = Axis::linear("v", "", min, max);
            for n in 1..6 {
                let count = tiny.ticks(n).len();
                assert!((1..=n).contains(&count), "{min}..{max} n={n}: {count}");
            }
        }
    }

    #[test]
    fn note_names() {
        assert_eq!(note_name(440.0).as_deref(), Some("A4"));
        assert_eq!(note_name(261.625_565).as_deref(), Some("C4"));
        assert_eq!(note_name(27.5).as_deref(), Some("A0"));
        // C#5 is 554.365 Hz; 12 cents above it:
        assert_eq!(
            note_name(554.365 * 2f64.powf(12.0 / 1200.0)).as_deref(),
            Some("C#5 +12 ct")
        );
        assert_eq!(
            note_name(440.0 * 2f64.powf(-30.0 / 1200.0)).as_deref(),
            Some("A4 -30 ct")
        );
        assert_eq!(note_name(0.0), None);
        assert_eq!(note_name(-5.0), None);
        assert_eq!(note_name(f64::NAN), None);
        assert_eq!(note_name(1.0), None);
    }
}
