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
}

mod labels;
mod ticks;

pub use labels::note_name;

#[cfg(test)]
mod tests;
