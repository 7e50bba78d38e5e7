//! Frequency axes at view time: a song cloud's `z` (frequency) shown linear, logarithmic or mel
//! without re-extracting.
//!
//! A Song cloud stores every point's frequency as its STFT bin: `z` is linear (or, with the
//! extractor's `--freq-scale log`, logarithmic) in the bin frequency `k * sample_rate / n_fft`,
//! as the file's `axes.z` says (docs/FORMAT.md). [`FreqMapping`] recovers the bin index `k` from
//! the stored `z` (so it works for clouds written with either `--freq-scale`) and gives each bin
//! a range of the view's normalized `z`: its centre on the linear axis, and on the log and mel
//! axes its whole extent `[f_k - df / 2, f_k + df / 2]` (clamped to the axis), over which its
//! points are spread by a deterministic jitter of the point index ([`jitter`]). Without the
//! spreading the lowest bins of a log axis are sheets far apart with nothing between them (at
//! 22.05 kHz / 2048, bin 1 alone covers 14 % of the log axis); with it each bin fills its own
//! share of the axis, so points and voxels cover the occupied range without empty sheets
//! (docs/ARCHITECTURE.md, "Frequency axis at view time").
//!
//! The GPU applies the same mapping: the per-bin table is uploaded and
//! shaders/utils/freq_axis.wgsl (`freq_view_z`) repeats [`FreqMapping::view_z`] operation for
//! operation in f32, in the points shader and in the voxelizer. The log view drops the 0 Hz
//! bin, which has no place on it (as the extractor's `--freq-scale log` does). Hover read-outs
//! of voxels invert the mapping through [`FreqMapping::view`]; a point reads its stored bin
//! frequency.

use serde::{Deserialize, Serialize};

use crate::data::axes::{Axes, Axis, AxisScale};
use crate::data::cloud::{CloudMeta, DataMode, Point};

/// How the frequency axis is shown.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum FreqAxis {
    /// Linear in Hz (the paper's axis, and the extractor's default).
    #[default]
    Linear,
    /// Linear in log10 of the frequency, from half a bin to Nyquist.
    Log,
    /// Linear in mel (HTK: `2595 log10(1 + f / 700)`).
    Mel,
}

impl FreqAxis {
    pub const ALL: [FreqAxis; 3] = [FreqAxis::Linear, FreqAxis::Log, FreqAxis::Mel];

    /// The command-line name: `linear`, `log`, `mel`.
    pub fn name(self) -> &'static str {
        match self {
            FreqAxis::Linear => "linear",
            FreqAxis::Log => "log",
            FreqAxis::Mel => "mel",
        }
    }

    /// For the side panel.
    pub fn title(self) -> &'static str {
        match self {
            FreqAxis::Linear => "Linear",
            FreqAxis::Log => "Logarithmic",
            FreqAxis::Mel => "Mel",
        }
    }

    pub fn parse(text: &str) -> Option<Self> {
        crate::parse_value(text)
    }

    fn scale(self) -> AxisScale {
        match self {
            FreqAxis::Linear => AxisScale::Linear,
            FreqAxis::Log => AxisScale::Log,
            FreqAxis::Mel => AxisScale::Mel,
        }
    }
}

command_line_names!(FreqAxis, |axis| axis.name());

/// The mapping's constants as the shaders read them. Keep in sync with `FreqParams` in
/// shaders/utils/freq_axis.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct FreqParams {
    /// x: 0 as stored (identity), 1 bin index linear in z, 2 bin index exponential in z;
    /// y: bins in the table; z: index of the chunk's first point in the cloud; w: unused.
    pub mode: [u32; 4],
    /// x, y: bin index = floor(x z + y + 0.5) (mode 1) or floor(exp2(x z + y) + 0.5) (mode 2).
    pub bin_of_z: [f32; 4],
}
const _: () = assert!(std::mem::size_of::<FreqParams>() == 32);

impl FreqParams {
    /// The stored z as is.
    pub const IDENTITY: FreqParams = FreqParams {
        mode: [0, 1, 0, 0],
        bin_of_z: [0.0; 4],
    };

    /// The same constants for a chunk whose first point is point `first` of the cloud.
    pub fn for_chunk(self, first: u32) -> FreqParams {
        FreqParams {
            mode: [self.mode[0], self.mode[1], first, 0],
            ..self
        }
    }
}

/// The table entry of a bin that the view does not show (lo > hi).
pub const HIDDEN: [f32; 2] = [2.0, -2.0];

/// A deterministic number in [0, 1) per point index (the PCG hash's output, 24 bits, so the
/// f32 is exact). Keep in sync with `freq_jitter` in shaders/utils/freq_axis.wgsl.
pub fn jitter(index: u32) -> f32 {
    let state = index.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
    let word = ((state >> ((state >> 28) + 4)) ^ state).wrapping_mul(277_803_737);
    let hash = (word >> 22) ^ word;
    (hash >> 8) as f32 * (1.0 / 16_777_216.0)
}

/// Why `meta` has no frequency axis to remap, if it has none.
pub fn unsupported(meta: &CloudMeta) -> Option<String> {
    if meta.mode != DataMode::Song {
        return Some("only song clouds have a frequency axis".into());
    }
    let z = &meta.axes.z;
    if z.unit != "Hz" {
        return Some(format!("the z axis is in '{}', not Hz", z.unit));
    }
    if z.problem().is_some() || z.scale == AxisScale::Mel || z.min >= z.max {
        return Some("the z axis's range cannot be read as STFT bins".into());
    }
    let rate = meta.source.as_ref().and_then(|s| s.sample_rate);
    let n_fft = meta.stft.as_ref().and_then(|s| s.n_fft);
    match (rate, n_fft) {
        (Some(rate), Some(n_fft)) if rate > 0 && n_fft >= 2 => None,
        _ => Some("the metadata gives no sample rate and FFT size (source, stft)".into()),
    }
}

/// One frequency axis for one cloud: the view's z axis and, per STFT bin, where its points go.
#[derive(Clone, Debug, PartialEq)]
pub struct FreqMapping {
    pub axis: FreqAxis,
    /// The view's z axis: what ticks, axis titles and voxel read-outs use.
    pub view: Axis,
    /// Bin spacing in Hz (`sample_rate / n_fft`).
    pub bin_hz: f64,
    /// Per bin `k` (0 Hz to Nyquist): the view's normalized z range `[lo, hi]` its points are
    /// spread over; `lo == hi` puts them on one plane, [`HIDDEN`] leaves them out.
    pub table: Vec<[f32; 2]>,
    params: FreqParams,
}

impl FreqMapping {
    /// The mapping of `meta`'s stored frequencies onto `axis`; an error (one line) when the
    /// cloud has no frequency axis (see [`unsupported`]).
    pub fn new(meta: &CloudMeta, axis: FreqAxis) -> Result<FreqMapping, String> {
        if let Some(reason) = unsupported(meta) {
            return Err(reason);
        }
        let stored = &meta.axes.z;
        let rate = f64::from(
            meta.source
                .as_ref()
                .and_then(|s| s.sample_rate)
                .unwrap_or(1),
        );
        let n_fft = meta.stft.as_ref().and_then(|s| s.n_fft).unwrap_or(2);
        let bins = n_fft / 2 + 1;
        let bin_hz = rate / f64::from(n_fft);
        let stored_log = stored.scale == AxisScale::Log;
        // The bin index from the stored z (docs/FORMAT.md, Song mode's z column).
        let (a, b, mode) = if stored_log {
            let (lo, hi) = (stored.min.log2(), stored.max.log2());
            let a = (hi - lo) * 0.5;
            (a, lo + a - bin_hz.log2(), 2)
        } else {
            let a = (stored.max - stored.min) / (2.0 * bin_hz);
            (a, a + stored.min / bin_hz, 1)
        };
        let identity = axis == FreqAxis::Linear && !stored_log;
        let params = if identity {
            FreqParams::IDENTITY
        } else {
            FreqParams {
                mode: [mode, bins, 0, 0],
                bin_of_z: [a as f32, b as f32, 0.0, 0.0],
            }
        };
        let half = bin_hz * 0.5;
        let (lo_hz, hi_hz) = match axis {
            FreqAxis::Linear => (stored.min, stored.max),
            FreqAxis::Log => (half, stored.max),
            FreqAxis::Mel => (if stored.min > 0.0 { half } else { 0.0 }, stored.max),
        };
        let view = if identity {
            stored.clone()
        } else {
            Axis {
                scale: axis.scale(),
                ticks: None,
                ..Axis::linear(&stored.label, "Hz", lo_hz, hi_hz)
            }
        };
        let table = (0..bins)
            .map(|k| {
                let f = f64::from(k) * bin_hz;
                match axis {
                    FreqAxis::Linear => {
                        let at = view.normalized_of(f) as f32;
                        [at, at]
                    }
                    FreqAxis::Log if k == 0 => HIDDEN,
                    FreqAxis::Log | FreqAxis::Mel => {
                        let low = (f - half).max(lo_hz);
                        let high = (f + half).min(hi_hz);
                        [
                            view.normalized_of(low) as f32,
                            view.normalized_of(high) as f32,
                        ]
                    }
                }
            })
            .collect();
        Ok(FreqMapping {
            axis,
            view,
            bin_hz,
            table,
            params,
        })
    }

    /// Whether the view's z is the stored z (a linear view of a linear file).
    pub fn is_identity(&self) -> bool {
        self.params.mode[0] == 0
    }

    /// The constants for the shaders (chunk offset 0; see [`FreqParams::for_chunk`]).
    pub fn params(&self) -> FreqParams {
        self.params
    }

    /// The table as the shaders read it: at least one entry.
    pub fn gpu_table(&self) -> Vec<[f32; 2]> {
        if self.table.is_empty() {
            vec![HIDDEN]
        } else {
            self.table.clone()
        }
    }

    /// The STFT bin of a stored z. Keep in sync with `freq_view_z` in freq_axis.wgsl.
    pub fn bin_of(&self, z: f32) -> u32 {
        let [a, b, _, _] = self.params.bin_of_z;
        let t = a * z + b;
        let k = if self.params.mode[0] == 2 {
            t.exp2()
        } else {
            t
        };
        let top = (self.params.mode[1] - 1) as f32;
        (k + 0.5).floor().clamp(0.0, top) as u32
    }

    /// The view's z of point number `index` (in the whole cloud) whose stored z is `z`; `None`
    /// where the view leaves the point out. The same f32 operations as `freq_view_z` in
    /// shaders/utils/freq_axis.wgsl.
    pub fn view_z(&self, z: f32, index: u32) -> Option<f32> {
        if self.is_identity() {
            return Some(z);
        }
        let [lo, hi] = self.table[self.bin_of(z) as usize];
        if lo > hi {
            return None;
        }
        Some(lo + jitter(index) * (hi - lo))
    }

    /// The points as the view shows them (the CPU reference of the shaders, and what hover
    /// picks among): z remapped, points the view leaves out at z = NaN.
    pub fn view_points(&self, points: &[Point]) -> Vec<Point> {
        points
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let z = self.view_z(p.position[2], i as u32).unwrap_or(f32::NAN);
                Point {
                    position: [p.position[0], p.position[1], z],
                    ..*p
                }
            })
            .collect()
    }

    /// `axes` with z replaced by the view's z axis.
    pub fn view_axes(&self, axes: &Axes) -> Axes {
        Axes {
            z: self.view.clone(),
            ..axes.clone()
        }
    }

    /// The frequency (Hz) shown at the view's normalized z (hover read-outs of voxels).
    pub fn frequency_at(&self, view_z: f64) -> f64 {
        self.view.value_at(view_z)
    }
}

/// Empty sheets: of `sheets` equal slices of the view's z range [-1, 1], how many inside the
/// occupied range (from the lowest to the highest slice holding a point) hold no point. Points
/// with a NaN z are not counted.
pub fn empty_sheets(points: &[Point], sheets: usize) -> (usize, usize) {
    let mut filled = vec![false; sheets];
    for p in points {
        let z = p.position[2];
        if z.is_nan() {
            continue;
        }
        let at = (((z + 1.0) * 0.5 * sheets as f32).floor() as isize).clamp(0, sheets as isize - 1);
        filled[at as usize] = true;
    }
    let first = filled.iter().position(|&f| f);
    let last = filled.iter().rposition(|&f| f);
    match (first, last) {
        (Some(first), Some(last)) => {
            let empty = filled[first..=last].iter().filter(|&&f| !f).count();
            (empty, last - first + 1)
        }
        _ => (0, 0),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::cloud::{Source, Stft};

    fn meta(rate: u32, n_fft: u32, scale: AxisScale) -> CloudMeta {
        let nyquist = f64::from(rate) / 2.0;
        let z = match scale {
            AxisScale::Log => Axis::log(
                "frequency",
                "Hz",
                f64::from(rate) / f64::from(n_fft),
                nyquist,
            ),
            _ => Axis::linear("frequency", "Hz", 0.0, nyquist),
        };
        let mut axes = Axes::generic([(0.0, 1.0), (0.0, 1.0), (0.0, 1.0)]);
        axes.z = z;
        CloudMeta {
            mode: DataMode::Song,
            axes,
            point_count: None,
            source: Some(Source {
                sample_rate: Some(rate),
                ..Default::default()
            }),
            stft: Some(Stft {
                n_fft: Some(n_fft),
                ..Default::default()
            }),
            metrics: None,
            songs: Vec::new(),
            warnings: Vec::new(),
            raw: serde_json::Value::Null,
        }
    }

    /// The stored z of bin k, as the extractor writes it.
    fn stored_z(meta: &CloudMeta, k: u32) -> f32 {
        let rate = f64::from(meta.source.as_ref().unwrap().sample_rate.unwrap());
        let n_fft = f64::from(meta.stft.as_ref().unwrap().n_fft.unwrap());
        meta.axes.z.normalized_of(f64::from(k) * rate / n_fft) as f32
    }

    #[test]
    fn bins_come_back_from_either_stored_scale() {
        for scale in [AxisScale::Linear, AxisScale::Log] {
            for (rate, n_fft) in [(44100, 2048), (22050, 2048), (8000, 64), (48000, 4096)] {
                let meta = meta(rate, n_fft, scale);
                let first = if scale == AxisScale::Log { 1 } else { 0 };
                for axis in FreqAxis::ALL {
                    let mapping = FreqMapping::new(&meta, axis).unwrap();
                    if mapping.is_identity() {
                        continue;
                    }
                    for k in first..=n_fft / 2 {
                        assert_eq!(
                            mapping.bin_of(stored_z(&meta, k)),
                            k,
                            "{scale:?} {rate} {k}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn each_axis_puts_a_bin_where_its_frequency_is() {
        // 32 kHz / 2048: bin 64 is exactly 1 kHz.
        for scale in [AxisScale::Linear, AxisScale::Log] {
            let meta = meta(32000, 2048, scale);
            for axis in FreqAxis::ALL {
                let mapping = FreqMapping::new(&meta, axis).unwrap();
                let z = stored_z(&meta, 64);
                for index in [0, 1, 77, 4000] {
                    let view_z = mapping.view_z(z, index).unwrap();
                    let hz = mapping.frequency_at(f64::from(view_z));
                    // Within half a bin (the spreading), and at the centre on a linear axis.
                    assert!((hz - 1000.0).abs() <= 7.82, "{axis:?} {scale:?}: {hz}");
                    if axis == FreqAxis::Linear {
                        assert!((hz - 1000.0).abs() < 0.05, "{axis:?} {scale:?}: {hz}");
                    }
                }
            }
        }
    }

    #[test]
    fn log_bins_tile_the_axis_without_gaps() {
        let meta = meta(22050, 2048, AxisScale::Linear);
        let mapping = FreqMapping::new(&meta, FreqAxis::Log).unwrap();
        assert_eq!(mapping.table[0], HIDDEN);
        assert_eq!(mapping.table[1][0], -1.0);
        assert_eq!(mapping.table[1024][1], 1.0);
        for k in 1..1024 {
            let gap = mapping.table[k + 1][0] - mapping.table[k][1];
            assert!(gap.abs() < 1e-6, "bins {k} and {}: {gap}", k + 1);
        }
        // Bin 1 covers log10(3) of log10(11025 / 5.38) decades: 14 %.
        let width = (mapping.table[1][1] - mapping.table[1][0]) / 2.0;
        assert!((width - 0.1439).abs() < 1e-3, "{width}");
        assert!(mapping.view_z(stored_z(&meta, 0), 0).is_none());
    }

    #[test]
    fn jitter_is_uniform_and_in_range() {
        let mut buckets = [0u32; 10];
        for i in 0..100_000 {
            let j = jitter(i);
            assert!((0.0..1.0).contains(&j));
            buckets[(j * 10.0) as usize] += 1;
        }
        for b in buckets {
            assert!((9_500..10_500).contains(&b), "{buckets:?}");
        }
    }

    #[test]
    fn timelines_and_generic_clouds_have_no_frequency_axis() {
        let mut timeline = meta(44100, 2048, AxisScale::Linear);
        timeline.mode = DataMode::Timeline;
        assert!(FreqMapping::new(&timeline, FreqAxis::Log).is_err());
        let mut no_stft = meta(44100, 2048, AxisScale::Linear);
        no_stft.stft = None;
        assert!(unsupported(&no_stft).unwrap().contains("FFT size"));
    }

    #[test]
    fn empty_sheets_counts_inside_the_occupied_range() {
        let at = |z: f32| Point {
            position: [0.0, 0.0, z],
            scalar: 1.0,
            hp: 0.5,
        };
        let points = [at(-0.95), at(-0.05), at(0.95), at(f32::NAN)];
        // 10 sheets: 0, 4 and 9 hold points; 1-3 and 5-8 are empty.
        assert_eq!(empty_sheets(&points, 10), (7, 10));
        assert_eq!(empty_sheets(&[], 10), (0, 0));
    }
}
