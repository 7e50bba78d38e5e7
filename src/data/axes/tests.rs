//! The axes' mapping, ticks, labels and note names.

use super::labels::fixed;
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
    // Just before zero (a playhead at the start, float error) reads 0, not "-0:00.0".
    assert_eq!(axis.format_value(-0.01), "0:00.0");
    assert_eq!(axis.format_value(-1.5), "-0:01.5");
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
            "50 Hz", "100 Hz", "200 Hz", "500 Hz", "1 kHz", "2 kHz", "5 kHz", "10 kHz", "20 kHz"
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

/// A timeline by year from 1996 to 2009 whose file gives one tick a decade ("2000"): the axis
/// ticks its years itself, several of them, where they lie. A timeline by order keeps the
/// file's ticks (each year's first song), which the axis cannot compute.
#[test]
fn a_span_of_years_shows_several_years_whatever_the_file_gives() {
    let mut axis = Axis::linear("year", "year", 1996.0, 2010.0);
    let at_year = |axis: &Axis, year: f64| axis.normalized_of(year) as f32;
    axis.ticks = Some(vec![Tick {
        at: at_year(&axis, 2000.0),
        label: "2000".into(),
    }]);
    let ticks = axis.ticks(8);
    assert_eq!(
        labels(&ticks),
        [
            "1996", "1998", "2000", "2002", "2004", "2006", "2008", "2010"
        ]
    );
    for tick in &ticks {
        let year: f64 = tick.label.parse().unwrap();
        assert!((tick.at - at_year(&axis, year)).abs() < 1e-6, "{tick:?}");
    }
    // Fewer labels fit: every 5 years.
    assert_eq!(labels(&axis.ticks(4)), ["2000", "2005", "2010"]);
    // By order: songs 1996..2009 spread evenly, a tick at the first song of 1996 and of 2000.
    let mut by_order = Axis::linear("year", "year", 1996.0, 2009.0);
    by_order.ticks = Some(vec![
        Tick {
            at: -1.0,
            label: "1996".into(),
        },
        Tick {
            at: 0.1,
            label: "2000".into(),
        },
    ]);
    assert_eq!(labels(&by_order.ticks(8)), ["1996", "2000"]);
    assert_eq!(by_order.ticks(8)[1].at, 0.1);
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
