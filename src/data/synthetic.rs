//! Data made in code, for tests, benchmarks and demos: clouds with song or timeline axes, a
//! song-like cloud and a song-like field.

use std::path::PathBuf;

use glam::{UVec3, Vec3};

use crate::data::axes::{Axes, Axis};
use crate::data::cloud::{Aabb, CloudMeta, DataMode, Point, PointCloud};

impl PointCloud {
    /// A cloud made in code: axes labelled as a song's (time 0-30 s, level -80-0 dB,
    /// frequency 0-22.05 kHz) or a timeline's (years 1970-2020).
    pub fn synthetic(points: Vec<Point>, mode: DataMode) -> Self {
        let axes = match mode {
            DataMode::Timeline => Axes {
                x: Axis::linear("year", "year", 1970.0, 2020.0),
                y: Axis::linear("level", "dB", -60.0, 0.0),
                z: Axis::linear("crest factor", "dB", 3.0, 20.0),
                scalar: Axis::linear("loudness", "dB", -60.0, 0.0),
                hp: Axis::linear("hp", "", 0.0, 1.0),
            },
            _ => Axes {
                x: Axis::linear("time", "s", 0.0, 30.0),
                y: Axis::linear("level", "dB", -80.0, 0.0),
                z: Axis::linear("frequency", "Hz", 0.0, 22050.0),
                scalar: Axis::linear("loudness", "dB", -80.0, 0.0),
                hp: Axis::linear("hp", "", 0.0, 1.0),
            },
        };
        Self {
            path: PathBuf::from("synthetic"),
            bounds: Aabb::from_points(&points),
            points,
            meta: CloudMeta {
                mode,
                axes,
                point_count: None,
                source: None,
                stft: None,
                metrics: None,
                songs: Vec::new(),
                warnings: Vec::new(),
                raw: serde_json::Value::Null,
            },
        }
    }
}

/// A deterministic song-like cloud for tests, benchmarks and demos: `count` points over a
/// time (x) by log-frequency (z) plane, lifted to their level (y), with sustained harmonic
/// ridges (hp near 1), broadband percussive hits (hp near 0) and a quiet noise floor. Like the
/// extractor's STFT clouds, points come frame by frame (x ascending), each frame's 1024 bins in
/// frequency order; each point lies at a random place within its (frame, bin) cell.
pub fn synthetic_song(count: usize, seed: u64) -> Vec<Point> {
    let mut state = seed ^ 0x9e37_79b9_7f4a_7c15;
    let mut next = move || {
        // splitmix64
        state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 31)) >> 40) as f32 / (1u64 << 24) as f32
    };
    // Onsets: a kick-and-snare pattern, twelve hits over the song.
    let beats: Vec<(f32, bool)> = (0..12)
        .map(|b| (-0.9 + b as f32 * 0.155, b % 2 == 1))
        .collect();
    const BINS: usize = 1024;
    let frames = count.div_ceil(BINS).max(1);
    (0..count)
        .map(|n| {
            let (frame, bin) = (n / BINS, n % BINS);
            let x = (frame as f32 + next()) / frames as f32 * 2.0 - 1.0;
            let z = (bin as f32 + next()) / BINS as f32 * 2.0 - 1.0;
            // A melody of held notes; partials at log-spaced heights above each (z is log
            // frequency, an octave is 0.22).
            let note = ((x * 2.6).sin() * 2.5).round() * 0.05;
            let fundamental = -0.62 + note;
            let mut harmonic = 0.0f32;
            for k in 1..=6 {
                let centre = fundamental + (k as f32).log2() * 0.22;
                let gain = 1.0 / (k as f32).sqrt();
                harmonic += gain * (-((z - centre) / 0.028).powi(2)).exp();
            }
            // Verses and a louder chorus.
            let section = 0.5 + 0.5 * ((x * 1.7 + 0.4).sin() * 0.5 + 0.5);
            harmonic *= section;
            let mut percussive = 0.0f32;
            for &(at, snare) in &beats {
                let dt = x - at;
                if dt >= 0.0 {
                    let decay = (-dt / 0.035).exp();
                    // A kick is low; a snare is broadband and falls off toward the top.
                    let spectrum = if snare {
                        0.75 - 0.25 * z
                    } else {
                        (-((z + 0.8) / 0.25).powi(2)).exp()
                    };
                    percussive += decay * spectrum;
                }
            }
            let noise = next() * 0.1;
            let tilt = -0.12 * (z + 1.0);
            let level = (0.18 + 0.75 * harmonic + 0.7 * percussive + noise + tilt).clamp(0.0, 1.0);
            let y = (level * 1.9 - 0.95 + (next() - 0.5) * 0.03).clamp(-1.0, 1.0);
            // A-weighting: the lowest bands count for less.
            let a_weight = 0.35 + 0.65 * ((z + 1.0) * 1.4).min(1.0);
            let scalar = (level * a_weight).clamp(0.0, 1.0);
            let hp = ((harmonic + 0.04) / (harmonic + percussive + 0.08) + (next() - 0.5) * 0.1)
                .clamp(0.0, 1.0);
            Point {
                position: [x, y, z],
                scalar,
                hp,
            }
        })
        .collect()
}

/// A song-like analytic field for benchmarks, golden images and the scikit-image comparison:
/// (density, hp) on a `dims` grid over [-1, 1]^3, in [`VoxelGrid`](crate::render::grid::VoxelGrid)
/// order (x fastest). x is time: a 4/4 pulse of percussive hits (hp near 0) over sustained harmonic
/// partials (hp near 1); y is log amplitude: energy sits on a ridge that falls with frequency and
/// rises on each hit; z is frequency: partials make stripes. bench/bench_surface.py reads the same
/// field from the .npy file `loudscape bench --fields-dir` writes.
pub fn song_like_field(dims: UVec3) -> (Vec<f32>, Vec<f32>) {
    let n = (dims.x * dims.y * dims.z) as usize;
    let mut density = Vec::with_capacity(n);
    let mut hp = Vec::with_capacity(n);
    let size = Vec3::splat(2.0) / dims.as_vec3();
    for k in 0..dims.z {
        for j in 0..dims.y {
            for i in 0..dims.x {
                let p = Vec3::new(-1.0, -1.0, -1.0) + (UVec3::new(i, j, k).as_vec3() + 0.5) * size;
                let (d, h) = song_like_sample(p);
                density.push(d);
                hp.push(h);
            }
        }
    }
    (density, hp)
}

fn song_like_sample(p: Vec3) -> (f32, f32) {
    let (x, y, z) = (p.x, p.y, p.z);
    let freq = (z + 1.0) * 0.5;
    // Percussive hits: 8 beats across the song, each decaying quickly.
    let beat_phase = ((x + 1.0) * 4.0).fract();
    let hit = (-beat_phase * 9.0).exp();
    // Sections: a quieter intro and a louder chorus in the second half.
    let section = 0.75 + 0.25 * (1.0 / (1.0 + (-(x - 0.1) * 8.0).exp()));
    // The spectral ridge: loud lows, quieter highs; hits lift and widen it.
    let ridge = 0.25 - 0.9 * freq + 0.35 * hit;
    let width = 0.16 + 0.12 * hit;
    let level = (-((y - ridge) / width).powi(2)).exp();
    // Harmonic partials: stripes in frequency, strongest in the lows and mids.
    let partials = 0.6 + 0.4 * (z * 28.0).cos().powi(2) * (1.0 - freq);
    let density = (level * section * (partials * (1.0 - 0.5 * hit) + 0.8 * hit)).clamp(0.0, 1.0);
    let hp = (0.85 - 0.8 * hit + 0.1 * (z * 28.0).cos()).clamp(0.0, 1.0);
    (density, hp)
}
