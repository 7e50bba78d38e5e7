//! What a person reads on an [`Axis`]: tick labels and hover read-outs in the axis's unit
//! (clock time, hertz, years, decibels) and note names for frequencies.

use super::Axis;

impl Axis {
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
    pub(super) fn is_clock(&self) -> bool {
        self.unit == "s" && self.min.abs().max(self.max.abs()) >= 60.0
    }
}

/// Decimals to show for values `step` apart (1-2-5 steps: 0.5 -> 1, 0.25 -> 2, 10 -> 0).
pub(super) fn step_decimals(step: f64) -> usize {
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
pub(super) fn fixed(value: f64, decimals: usize) -> String {
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
    let scale = 10f64.powi(decimals as i32);
    let total = (seconds.abs() * scale).round() / scale;
    // A time that rounds to zero has no sign ("-0:00.0" was shown at the start of a song).
    let sign = if seconds < 0.0 && total > 0.0 {
        "-"
    } else {
        ""
    };
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
