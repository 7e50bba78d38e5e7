//! Colour maps and the picture's background: what the user chooses, the CPU side of every
//! colour the passes draw, and the palette uniform (bind group 0, binding 1) that carries them
//! to the shaders (`shaders/utils/palette.wgsl`, keep [`PaletteUniforms`] in sync with
//! `Palette` there).
//!
//! Two roles:
//! - [`HpColourMap`], the two-ended map of hp (percussive 0 to harmonic 1) for the points, the
//!   surface and the volume's hp tint. `Classic` is the paper's five-stop red-white-blue palette
//!   for the points and the warm-to-cool gradient for the surface; `PuOr` (ColorBrewer's
//!   orange-purple, colour-blind safe) and the perceptually uniform `Cividis` (made for colour
//!   vision deficiency) and `Viridis` replace both.
//! - [`DensityColourMap`], the colour ramp of the volume's transfer function. `Preset` keeps the
//!   preset's own ramp (Classic, Ember, Glacial); `Viridis`, `Cividis`, `Magma`, `Inferno` are
//!   matplotlib's perceptually uniform maps. The preset still shapes density to ramp position and
//!   opacity; the map only colours it.
//!
//! Every map is a list of stops spaced evenly on [0, 1] and interpolated linearly in the
//! gamma-encoded space of the render target, on the CPU ([`Ramp::sample`]) and in the shader
//! (`palette_lookup`) by the same formula, so legends show exactly what the passes draw. The
//! matplotlib maps are its 256 published entries (src/render/colormap_data.rs, with their
//! licences); matplotlib looks its listed maps up by nearest entry, we interpolate between the
//! same entries.
//!
//! On the [`Background::Light`] background (for print) the density ramp runs reversed (its dark
//! end at density 1), so the dense cores are ink and the faint haze fades into the paper, and
//! the volume composites without its glow (emission gain 1): light added over white would wash
//! out. Box lines, ticks, labels and legends switch to dark ink.

use crate::render::colormap_data::{CIVIDIS, INFERNO, MAGMA, PUOR, VIRIDIS};
use crate::render::transfer::TransferPreset;

/// Stops in one map of the palette uniform: matplotlib's listed maps have 256.
pub const MAX_STOPS: usize = 256;

/// The points' Classic map, the five-stop harmonic-percussive palette (paper 3.4): red, orange,
/// white, light blue, deep blue, from percussive (hp = 0) to harmonic (hp = 1), gamma-encoded.
pub const HP_PALETTE: [[f32; 3]; 5] = [
    [0.843, 0.188, 0.153],
    [0.992, 0.553, 0.235],
    [0.969, 0.969, 0.969],
    [0.569, 0.749, 0.859],
    [0.129, 0.400, 0.675],
];

/// The surface's Classic map: warm (hp = 0, percussive), a light neutral (0.5), cool (hp = 1,
/// harmonic), gamma-encoded.
pub const WARM_COOL: [[f32; 3]; 3] = [
    [0.851, 0.325, 0.192],
    [0.914, 0.882, 0.827],
    [0.231, 0.443, 0.780],
];

/// A colour map: stops evenly spaced on [0, 1] (gamma-encoded RGB), optionally read backwards.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ramp {
    pub stops: &'static [[f32; 3]],
    pub reversed: bool,
}

impl Ramp {
    pub const fn new(stops: &'static [[f32; 3]]) -> Self {
        Self {
            stops,
            reversed: false,
        }
    }

    /// The colour at `t` in [0, 1]: the same arithmetic as `palette_lookup` in palette.wgsl.
    pub fn sample(&self, t: f32) -> [f32; 3] {
        let t = t.clamp(0.0, 1.0);
        let t = if self.reversed { 1.0 - t } else { t };
        let n = self.stops.len();
        if n == 1 {
            return self.stops[0];
        }
        let x = t * (n - 1) as f32;
        let i = (x.floor() as usize).min(n - 2);
        let f = x - i as f32;
        let (a, b) = (self.stops[i], self.stops[i + 1]);
        [0, 1, 2].map(|c| a[c] + (b[c] - a[c]) * f)
    }

    /// 8-bit gamma-encoded RGB at `t`.
    pub fn sample_u8(&self, t: f32) -> [u8; 3] {
        to_u8(self.sample(t))
    }

    /// The stops as the shader reads them (reversal applied), padded to [`MAX_STOPS`].
    fn uniform_stops(&self) -> (u32, [[f32; 4]; MAX_STOPS]) {
        let n = self.stops.len().min(MAX_STOPS);
        let mut out = [[0.0; 4]; MAX_STOPS];
        for (i, slot) in out.iter_mut().take(n).enumerate() {
            let [r, g, b] = if self.reversed {
                self.stops[n - 1 - i]
            } else {
                self.stops[i]
            };
            *slot = [r, g, b, 1.0];
        }
        (n as u32, out)
    }
}

/// Gamma-encoded [0, 1] RGB to 8 bits.
pub fn to_u8(c: [f32; 3]) -> [u8; 3] {
    c.map(|v| (v * 255.0).round().clamp(0.0, 255.0) as u8)
}

/// The hp map of the points, the surface and the volume's hp tint.
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize,
)]
pub enum HpColourMap {
    /// The paper's palettes: five-stop red-white-blue points, warm-to-cool surface.
    #[default]
    Classic,
    /// ColorBrewer's PuOr (11 classes): orange percussive, purple harmonic; colour-blind safe.
    PuOr,
    /// Perceptually uniform and made for colour vision deficiency (Nunez et al. 2018).
    Cividis,
    /// matplotlib's perceptually uniform default.
    Viridis,
}

impl HpColourMap {
    pub const ALL: [HpColourMap; 4] = [
        HpColourMap::Classic,
        HpColourMap::PuOr,
        HpColourMap::Cividis,
        HpColourMap::Viridis,
    ];

    pub fn name(self) -> &'static str {
        match self {
            HpColourMap::Classic => "Classic",
            HpColourMap::PuOr => "PuOr",
            HpColourMap::Cividis => "Cividis",
            HpColourMap::Viridis => "Viridis",
        }
    }

    pub fn parse(name: &str) -> Option<Self> {
        crate::parse_value(name)
    }

    /// The map of the points (and the volume's hp tint).
    pub fn points(self) -> Ramp {
        match self {
            HpColourMap::Classic => Ramp::new(&HP_PALETTE),
            other => other.shared(),
        }
    }

    /// The map of the surface.
    pub fn surface(self) -> Ramp {
        match self {
            HpColourMap::Classic => Ramp::new(&WARM_COOL),
            other => other.shared(),
        }
    }

    fn shared(self) -> Ramp {
        match self {
            HpColourMap::Classic | HpColourMap::PuOr => Ramp::new(&PUOR),
            HpColourMap::Cividis => Ramp::new(&CIVIDIS),
            HpColourMap::Viridis => Ramp::new(&VIRIDIS),
        }
    }
}

/// The colour ramp of the volume's transfer function.
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize,
)]
pub enum DensityColourMap {
    /// The transfer-function preset's own four-stop ramp.
    #[default]
    Preset,
    Viridis,
    Cividis,
    Magma,
    Inferno,
}

impl DensityColourMap {
    pub const ALL: [DensityColourMap; 5] = [
        DensityColourMap::Preset,
        DensityColourMap::Viridis,
        DensityColourMap::Cividis,
        DensityColourMap::Magma,
        DensityColourMap::Inferno,
    ];

    pub fn name(self) -> &'static str {
        match self {
            DensityColourMap::Preset => "Preset",
            DensityColourMap::Viridis => "Viridis",
            DensityColourMap::Cividis => "Cividis",
            DensityColourMap::Magma => "Magma",
            DensityColourMap::Inferno => "Inferno",
        }
    }

    pub fn parse(name: &str) -> Option<Self> {
        crate::parse_value(name)
    }

    /// The ramp for `preset` (whose own ramp `Preset` means), not yet oriented for a background.
    pub fn ramp(self, preset: TransferPreset) -> Ramp {
        match self {
            DensityColourMap::Preset => Ramp::new(preset.stops()),
            DensityColourMap::Viridis => Ramp::new(&VIRIDIS),
            DensityColourMap::Cividis => Ramp::new(&CIVIDIS),
            DensityColourMap::Magma => Ramp::new(&MAGMA),
            DensityColourMap::Inferno => Ramp::new(&INFERNO),
        }
    }
}

command_line_names!(HpColourMap, |map| map.name().to_lowercase());
command_line_names!(DensityColourMap, |map| map.name().to_lowercase());
command_line_names!(Background, |background| background.name());

/// The picture's background: dark for the screen, light for print.
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize,
)]
pub enum Background {
    #[default]
    Dark,
    Light,
}

impl Background {
    pub const ALL: [Background; 2] = [Background::Dark, Background::Light];

    pub fn name(self) -> &'static str {
        match self {
            Background::Dark => "dark",
            Background::Light => "light",
        }
    }

    pub fn parse(name: &str) -> Option<Self> {
        crate::parse_value(name)
    }

    /// The clear colour (gamma-encoded RGB).
    pub fn rgb(self) -> [f32; 3] {
        match self {
            Background::Dark => [0.055, 0.063, 0.078],
            Background::Light => [1.0, 1.0, 1.0],
        }
    }

    /// Text and line colour for titles (strong) and ticks (soft) on this background.
    pub fn ink(self, strong: bool) -> [u8; 3] {
        match (self, strong) {
            (Background::Dark, true) => [225, 230, 238],
            (Background::Dark, false) => [160, 168, 182],
            (Background::Light, true) => [20, 24, 32],
            (Background::Light, false) => [70, 76, 88],
        }
    }

    pub fn is_light(self) -> bool {
        self == Background::Light
    }
}

/// Everything about the colours of a picture.
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize,
)]
pub struct Colours {
    pub hp: HpColourMap,
    pub density: DensityColourMap,
    pub background: Background,
}

impl Colours {
    /// `width` colours of the transfer function (`preset` shaped, coloured by `colours`' density
    /// ramp) from density 0 to 1 as RGBA8, over the background: the colour mixed with the
    /// background by 0.25 + 0.75 of its opacity, so transparent densities fade toward the
    /// background as they do in the picture, and still show their hue.
    pub fn legend(&self, preset: TransferPreset, width: usize) -> Vec<[u8; 4]> {
        let colours = self;
        let background = colours.background.rgb();
        (0..width)
            .map(|i| {
                let s = i as f32 / (width.max(2) - 1) as f32;
                let [r, g, b, a] = colours.transfer(preset, s);
                let k = 0.25 + 0.75 * a;
                let mix = |v: f32, bg: f32| {
                    (((v * k) + bg * (1.0 - k)) * 255.0)
                        .round()
                        .clamp(0.0, 255.0) as u8
                };
                let bg = if colours.background.is_light() {
                    background
                } else {
                    [0.0; 3]
                };
                [mix(r, bg[0]), mix(g, bg[1]), mix(b, bg[2]), 255]
            })
            .collect()
    }

    /// The volume's density ramp for `preset`, oriented for the background (reversed on light).
    pub fn density_ramp(&self, preset: TransferPreset) -> Ramp {
        Ramp {
            reversed: self.background.is_light(),
            ..self.density.ramp(preset)
        }
    }

    /// Colour (gamma-encoded RGB) and opacity per voxel of the transfer function at density `s`.
    pub fn transfer(&self, preset: TransferPreset, s: f32) -> [f32; 4] {
        let (t, alpha) = preset.shape(s);
        let [r, g, b] = self.density_ramp(preset).sample(t);
        [r, g, b, alpha]
    }
}

/// The palette uniform. Keep in sync with `Palette` in shaders/utils/palette.wgsl.
/// `counts`: x, y, z the number of stops of the points' hp map, the surface's hp map and the
/// density ramp; w: 1 on the light background. `stops`: the three maps, [`MAX_STOPS`] each.
#[derive(Clone, Copy, Debug)]
pub struct PaletteUniforms {
    pub counts: [u32; 4],
    pub stops: [[[f32; 4]; MAX_STOPS]; 3],
}

/// Bytes of [`PaletteUniforms`] in the uniform buffer.
pub const PALETTE_BYTES: u64 = 16 + 3 * MAX_STOPS as u64 * 16;

impl PaletteUniforms {
    pub fn new(colours: &Colours, preset: TransferPreset) -> Self {
        let (n0, hp) = colours.hp.points().uniform_stops();
        let (n1, surface) = colours.hp.surface().uniform_stops();
        let (n2, density) = colours.density_ramp(preset).uniform_stops();
        Self {
            counts: [n0, n1, n2, u32::from(colours.background.is_light())],
            stops: [hp, surface, density],
        }
    }

    /// The uniform's bytes, as palette.wgsl reads them.
    pub fn bytes(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(PALETTE_BYTES as usize);
        for c in self.counts {
            out.extend_from_slice(&c.to_le_bytes());
        }
        for map in &self.stops {
            for stop in map {
                for v in stop {
                    out.extend_from_slice(&v.to_le_bytes());
                }
            }
        }
        debug_assert_eq!(out.len() as u64, PALETTE_BYTES);
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: [f32; 3], b: [f32; 3], tolerance: f32) -> bool {
        a.iter().zip(b).all(|(x, y)| (x - y).abs() <= tolerance)
    }

    /// Values as matplotlib 3.11 gives them for `cmap(i / 255)` (the listed entries i = 0,
    /// 128, 255), spelled here from matplotlib's `_cm_listed.py`, and the hex codes the maps'
    /// authors publish for their ends.
    #[test]
    fn a_transfer_legend_has_the_width_asked() {
        assert_eq!(
            Colours::default().legend(TransferPreset::Classic, 16).len(),
            16
        );
    }

    #[test]
    fn matplotlib_maps_sample_to_their_published_values() {
        let cases: [(&str, Ramp, [[f32; 3]; 3]); 4] = [
            (
                "viridis",
                Ramp::new(&VIRIDIS),
                [
                    [0.267004, 0.004874, 0.329415],
                    [0.127568, 0.566949, 0.550556],
                    [0.993248, 0.906157, 0.143936],
                ],
            ),
            (
                "magma",
                Ramp::new(&MAGMA),
                [
                    [0.001462, 0.000466, 0.013866],
                    [0.716387, 0.214982, 0.47529],
                    [0.987053, 0.991438, 0.749504],
                ],
            ),
            (
                "inferno",
                Ramp::new(&INFERNO),
                [
                    [0.001462, 0.000466, 0.013866],
                    [0.735683, 0.215906, 0.330245],
                    [0.988362, 0.998364, 0.644924],
                ],
            ),
            (
                "cividis",
                Ramp::new(&CIVIDIS),
                [
                    [0.0, 0.135112, 0.304751],
                    [0.488697, 0.485318, 0.471008],
                    [0.995737, 0.909344, 0.217772],
                ],
            ),
        ];
        for (name, ramp, [first, middle, last]) in cases {
            assert_eq!(ramp.stops.len(), 256, "{name}");
            assert!(close(ramp.sample(0.0), first, 1e-6), "{name} at 0");
            assert!(
                close(ramp.sample(128.0 / 255.0), middle, 1e-5),
                "{name} at 128/255: {:?}",
                ramp.sample(128.0 / 255.0)
            );
            assert!(close(ramp.sample(1.0), last, 1e-6), "{name} at 1");
        }
        // The published hex ends: viridis #440154 to #fde725, magma #000004 to #fcfdbf.
        assert_eq!(Ramp::new(&VIRIDIS).sample_u8(0.0), [0x44, 0x01, 0x54]);
        assert_eq!(Ramp::new(&VIRIDIS).sample_u8(1.0), [0xfd, 0xe7, 0x25]);
        assert_eq!(Ramp::new(&MAGMA).sample_u8(0.0), [0x00, 0x00, 0x04]);
        assert_eq!(Ramp::new(&MAGMA).sample_u8(1.0), [0xfc, 0xfd, 0xbf]);
        // ColorBrewer PuOr, 11 classes: #7f3b08, ..., #f7f7f7 (middle), ..., #2d004b.
        let puor = HpColourMap::PuOr.points();
        assert_eq!(puor.sample_u8(0.0), [0x7f, 0x3b, 0x08]);
        assert_eq!(puor.sample_u8(0.5), [0xf7, 0xf7, 0xf7]);
        assert_eq!(puor.sample_u8(0.1), [0xb3, 0x58, 0x06]);
        assert_eq!(puor.sample_u8(1.0), [0x2d, 0x00, 0x4b]);
    }

    #[test]
    fn perceptually_uniform_maps_rise_in_lightness() {
        // Relative luminance of the gamma-encoded colour rises monotonically along the
        // sequential maps: the property that lets a reader order densities by eye.
        fn luminance(c: [f32; 3]) -> f32 {
            let lin = c.map(|v| {
                if v <= 0.04045 {
                    v / 12.92
                } else {
                    ((v + 0.055) / 1.055).powf(2.4)
                }
            });
            0.2126 * lin[0] + 0.7152 * lin[1] + 0.0722 * lin[2]
        }
        for map in &DensityColourMap::ALL[1..] {
            let ramp = map.ramp(TransferPreset::Classic);
            let mut last = -1.0;
            for i in 0..=64 {
                let l = luminance(ramp.sample(i as f32 / 64.0));
                assert!(l > last, "{map:?} at {i}");
                last = l;
            }
        }
    }

    /// The Classic hp maps are the paper's palettes: through each stop, evenly spaced, and
    /// straight between neighbours; the transfer function colours the preset's shape with the
    /// preset's own stops.
    #[test]
    fn classic_maps_are_the_old_palettes() {
        let maps = [
            (HpColourMap::Classic.points(), &HP_PALETTE[..]),
            (HpColourMap::Classic.surface(), &WARM_COOL[..]),
        ];
        for (ramp, stops) in maps {
            let last = (stops.len() - 1) as f32;
            for (k, pair) in stops.windows(2).enumerate() {
                let (a, b) = (pair[0], pair[1]);
                assert_eq!(ramp.sample(k as f32 / last), a, "stop {k}");
                let middle = [0, 1, 2].map(|c| (a[c] + b[c]) / 2.0);
                let got = ramp.sample((k as f32 + 0.5) / last);
                assert!(
                    close(got, middle, 1e-6),
                    "between {k} and {}: {got:?}",
                    k + 1
                );
            }
            assert!(close(ramp.sample(1.0), stops[stops.len() - 1], 1e-6));
        }
        let colours = Colours::default();
        for preset in TransferPreset::ALL {
            for i in 0..=40 {
                let s = i as f32 / 40.0;
                let (t, alpha) = preset.shape(s);
                let [r, g, b] = Ramp::new(preset.stops()).sample(t);
                assert_eq!(colours.transfer(preset, s), [r, g, b, alpha]);
            }
            let [r, g, b, _] = colours.transfer(preset, 1.0);
            assert!(close([r, g, b], preset.stops()[3], 1e-6), "{preset:?} at 1");
        }
    }

    #[test]
    fn light_background_reverses_the_density_ramp_and_names_parse() {
        let dark = Colours::default();
        let light = Colours {
            background: Background::Light,
            ..dark
        };
        let preset = TransferPreset::Classic;
        assert_eq!(
            dark.density_ramp(preset).sample(0.0),
            light.density_ramp(preset).sample(1.0)
        );
        let uniforms = PaletteUniforms::new(&light, preset);
        assert_eq!(uniforms.counts, [5, 3, 4, 1]);
        assert_eq!(uniforms.stops[2][0][..3], CLASSIC_TOP);
        assert_eq!(uniforms.bytes().len() as u64, PALETTE_BYTES);
        assert_eq!(HpColourMap::parse("puor"), Some(HpColourMap::PuOr));
        assert_eq!(
            DensityColourMap::parse("MAGMA"),
            Some(DensityColourMap::Magma)
        );
        assert_eq!(Background::parse("Light"), Some(Background::Light));
        let names: Vec<String> = HpColourMap::ALL.iter().map(crate::value_name).collect();
        assert_eq!(names, ["classic", "puor", "cividis", "viridis"]);
    }

    const CLASSIC_TOP: [f32; 3] = [1.00, 0.97, 0.88];
}
