//! Transfer functions of the volume view (paper sections 3.3 and 5): density -> colour and
//! opacity. This is the CPU mirror of `transfer` in shaders/volume.wgsl, for legends and tests
//! (the colour through [`Colours::transfer`](crate::render::colormap::Colours::transfer));
//! keep the two in sync (a test compares them through rendered images).
//!
//! Each preset reshapes the density `s` in [0, 1] to a ramp position `t`, looks the colour up on
//! a four-stop ramp (gamma-encoded, like every colour of the render target) and takes the opacity
//! per voxel of ray length from `t`:
//! - Classic: `t = s`, opacity `t`; deep blue through teal and gold to near white: a balanced,
//!   mostly linear view of the whole field.
//! - Ember: `t = sqrt(s)`, which lifts low-to-mid densities; warm ramp from dark red through
//!   orange to pale yellow.
//! - Glacial: `t = smoothstep(0.2, 1, s)`, which suppresses the low densities; opacity `1.6 t^2`
//!   ramps steeply toward the dense cores; cool ramp from navy through blue to ice white.
//!
//! The ramp's colours can be swapped for a perceptually uniform map (viridis, cividis, magma,
//! inferno: [`crate::render::colormap::DensityColourMap`]); the shape stays the preset's. The
//! shader reads the ramp from the palette uniform, which src/render/colormap.rs fills from
//! these stops or the chosen map.

/// A transfer-function preset.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
pub enum TransferPreset {
    Classic,
    Ember,
    Glacial,
}

/// Colour stops per preset (gamma-encoded RGB), uploaded to the shader by colormap.rs.
const CLASSIC: [[f32; 3]; 4] = [
    [0.14, 0.24, 0.58],
    [0.16, 0.62, 0.78],
    [0.96, 0.78, 0.32],
    [1.00, 0.97, 0.88],
];
const EMBER: [[f32; 3]; 4] = [
    [0.40, 0.05, 0.02],
    [0.86, 0.26, 0.05],
    [1.00, 0.62, 0.16],
    [1.00, 0.93, 0.66],
];
const GLACIAL: [[f32; 3]; 4] = [
    [0.05, 0.12, 0.36],
    [0.14, 0.40, 0.80],
    [0.55, 0.82, 0.98],
    [0.93, 0.98, 1.00],
];

impl TransferPreset {
    pub const ALL: [TransferPreset; 3] = [
        TransferPreset::Classic,
        TransferPreset::Ember,
        TransferPreset::Glacial,
    ];

    pub fn name(self) -> &'static str {
        match self {
            TransferPreset::Classic => "Classic",
            TransferPreset::Ember => "Ember",
            TransferPreset::Glacial => "Glacial",
        }
    }

    pub fn parse(name: &str) -> Option<Self> {
        crate::parse_value(name)
    }

    /// The index the shader switches on. Keep in sync with volume.wgsl.
    pub fn index(self) -> u32 {
        self as u32
    }

    /// The preset's own four colour stops (the `Preset` density colour map).
    pub fn stops(self) -> &'static [[f32; 3]; 4] {
        match self {
            TransferPreset::Classic => &CLASSIC,
            TransferPreset::Ember => &EMBER,
            TransferPreset::Glacial => &GLACIAL,
        }
    }

    /// Ramp position and opacity (per voxel of ray length, before the opacity scale) of density
    /// `s` (already multiplied by the density scale).
    pub fn shape(self, s: f32) -> (f32, f32) {
        let s = s.clamp(0.0, 1.0);
        match self {
            TransferPreset::Classic => (s, s),
            TransferPreset::Ember => {
                let t = s.sqrt();
                (t, t)
            }
            TransferPreset::Glacial => {
                let u = ((s - 0.2) / 0.8).clamp(0.0, 1.0);
                let t = u * u * (3.0 - 2.0 * u);
                (t, (1.6 * t * t).min(1.0))
            }
        }
    }
}

command_line_names!(TransferPreset, |preset| preset.name().to_lowercase());

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_shape_density_as_documented() {
        for preset in TransferPreset::ALL {
            assert_eq!(preset.shape(0.0).1, 0.0, "{preset:?} empty is transparent");
            let mut last = -1.0;
            for i in 0..=100 {
                let (_, a) = preset.shape(i as f32 / 100.0);
                assert!(a >= last, "{preset:?} opacity must not fall with density");
                last = a;
            }
        }
        // Ember lifts the low-to-mid range above Classic; Glacial suppresses it.
        let (classic, ember, glacial) = (
            TransferPreset::Classic.shape(0.25).1,
            TransferPreset::Ember.shape(0.25).1,
            TransferPreset::Glacial.shape(0.25).1,
        );
        assert!(ember > classic && glacial < 0.05 && classic > glacial);
        // Glacial is the steepest at the top.
        assert!(TransferPreset::Glacial.shape(1.0).1 >= TransferPreset::Classic.shape(1.0).1);
        assert_eq!(TransferPreset::parse("ember"), Some(TransferPreset::Ember));
    }
}
