//! What is under the cursor, on the CPU: the nearest projected point, the first voxel along the
//! cursor's ray above a threshold, or the timeline song whose span holds an x position, and the
//! read-out of each in physical units.
//!
//! Picking runs once per hover event (when the cursor or the view changed), not per frame: a
//! linear scan projecting every point costs a few milliseconds for 200k points.

use glam::{UVec3, Vec2, Vec3, Vec4Swizzles};

use crate::data::axes::{Axes, Axis, note_name};
use crate::data::cloud::{DataMode, Point, SongInfo};
use crate::data::field::Field;
use crate::view::frame_view::FrameView;

/// The ray under pixel `px` (origin top left) in data space: origin on the near plane, unit
/// direction away from the camera.
pub fn cursor_ray(view: &FrameView, px: Vec2) -> (Vec3, Vec3) {
    let data_from_clip = view.clip_from_data().inverse();
    let ndc_x = px.x / view.width.max(1) as f32 * 2.0 - 1.0;
    let ndc_y = 1.0 - px.y / view.height.max(1) as f32 * 2.0;
    let unproject = |z: f32| {
        let p = data_from_clip * glam::Vec4::new(ndc_x, ndc_y, z, 1.0);
        p.xyz() / p.w
    };
    let near = unproject(0.0);
    let far = unproject(1.0);
    (near, (far - near).normalize_or_zero())
}

/// Where a ray enters and leaves the box `[min, max]`: parameters `(t_enter, t_exit)`, None when
/// it misses.
pub fn ray_box(origin: Vec3, dir: Vec3, min: Vec3, max: Vec3) -> Option<(f32, f32)> {
    let inv = dir.recip();
    let a = (min - origin) * inv;
    let b = (max - origin) * inv;
    let t_enter = a.min(b).max_element().max(0.0);
    let t_exit = a.max(b).min_element();
    (t_exit >= t_enter && t_exit.is_finite()).then_some((t_enter, t_exit))
}

/// The point drawn under pixel `px`: among the points projected within `radius_px` of it (and
/// shown: scalar at least `min_scalar`), the one nearest the camera.
pub fn pick_point(
    points: &[Point],
    view: &FrameView,
    px: Vec2,
    radius_px: f32,
    min_scalar: f32,
) -> Option<usize> {
    let clip_from_data = view.clip_from_data();
    let (w, h) = (view.width as f32, view.height as f32);
    let radius2 = radius_px * radius_px;
    let mut best: Option<(usize, f32, f32)> = None;
    for (index, point) in points.iter().enumerate() {
        if point.scalar < min_scalar {
            continue;
        }
        let clip = clip_from_data * Vec3::from(point.position).extend(1.0);
        if clip.w <= 1e-6 {
            continue;
        }
        let ndc = clip.xyz() / clip.w;
        if !(0.0..=1.0).contains(&ndc.z) {
            continue;
        }
        let screen = Vec2::new((ndc.x * 0.5 + 0.5) * w, (0.5 - ndc.y * 0.5) * h);
        let d2 = screen.distance_squared(px);
        if d2 > radius2 {
            continue;
        }
        // Nearest the camera wins; within a hair of the same depth, nearest the cursor.
        let better = match best {
            None => true,
            Some((_, depth, dist)) => ndc.z < depth - 1e-6 || (ndc.z <= depth + 1e-6 && d2 < dist),
        };
        if better {
            best = Some((index, ndc.z, d2));
        }
    }
    best.map(|(index, _, _)| index)
}

/// The voxel a ray stopped at.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VoxelHit {
    pub voxel: UVec3,
    /// The voxel's centre in data space.
    pub position: Vec3,
    pub density: f32,
    /// The mean hp of the points around the voxel ([`Field::hp_near`]); NaN when none is near.
    pub hp_mean: f32,
}

impl Field {
    /// The first voxel along the ray whose density is at least `threshold`, sampled every
    /// quarter voxel.
    pub fn pick(&self, origin: Vec3, dir: Vec3, threshold: f32) -> Option<VoxelHit> {
        let n = self.dims.x as usize * self.dims.y as usize * self.dims.z as usize;
        if n == 0 || self.density.len() != n || self.hp_mean.len() != n {
            return None;
        }
        let (t0, t1) = ray_box(origin, dir, self.box_min, self.box_max)?;
        let size = (self.box_max - self.box_min) / self.dims.as_vec3();
        let step = (size.min_element() * 0.25).max(1e-5);
        let mut t = t0 + step * 0.5;
        while t <= t1 {
            if let Some(v) = self.voxel_of(origin + dir * t) {
                let i = self.index(v);
                if self.density[i] >= threshold {
                    return Some(VoxelHit {
                        voxel: v,
                        position: self.box_min + (v.as_vec3() + 0.5) * size,
                        density: self.density[i],
                        hp_mean: self.hp_near(v),
                    });
                }
            }
            t += step;
        }
        None
    }
}

/// What the voxelizer writes as the mean hp of a voxel no point fell in.
pub const EMPTY_VOXEL_HP: f32 = 0.5;
/// How far at most (in voxels, each way) [`Field::hp_near`] looks for voxels holding points.
pub const HP_NEIGHBOURHOOD: i32 = 2;

impl Field {
    /// The mean hp of the points around voxel `v`: the density-weighted mean of `hp_mean` over
    /// the voxels holding points in the 3^3 block around `v` (5^3 if that has none, which on the
    /// demo happens for 2 % of the voxels above 0.1), NaN when none does.
    ///
    /// The density is smoothed and `hp_mean` is not, so the first voxel a ray finds above an
    /// isovalue is often one no point fell in (on the demo, 78 % of the voxels above 0.1 are),
    /// whose `hp_mean` is the empty default [`EMPTY_VOXEL_HP`]: reading that voxel alone made
    /// every hover say "0.50 (mixed)".
    pub fn hp_near(&self, v: UVec3) -> f32 {
        (1..=HP_NEIGHBOURHOOD)
            .map(|r| self.hp_within(v, r))
            .find(|hp| hp.is_finite())
            .unwrap_or(f32::NAN)
    }

    /// The density-weighted mean hp of the voxels holding points within `r` of `v`, NaN if none.
    fn hp_within(&self, v: UVec3, r: i32) -> f32 {
        let (mut sum, mut weight) = (0.0_f64, 0.0_f64);
        for dz in -r..=r {
            for dy in -r..=r {
                for dx in -r..=r {
                    let p = v.as_ivec3() + glam::IVec3::new(dx, dy, dz);
                    if p.min_element() < 0 || p.cmpge(self.dims.as_ivec3()).any() {
                        continue;
                    }
                    let i = self.index(p.as_uvec3());
                    let hp = self.hp_mean[i];
                    if hp == EMPTY_VOXEL_HP || !hp.is_finite() {
                        continue;
                    }
                    let w = f64::from(self.density[i].max(1e-6));
                    sum += f64::from(hp) * w;
                    weight += w;
                }
            }
        }
        if weight > 0.0 {
            (sum / weight) as f32
        } else {
            f32::NAN
        }
    }
}

/// The year under the cursor on a timeline at normalized `x`: the year of the song whose span
/// holds `x` (songs of one year sit side by side, and `--x-by order` places them by rank, so the
/// axis's linear map from x to year is wrong there); the axis's own value only when no song has
/// a span. None between songs.
pub fn timeline_year(axes: &Axes, songs: &[SongInfo], x: f32) -> Option<Reading> {
    let name = axis_name(&axes.x, "year");
    if songs.iter().any(|s| s.x_min.is_some() && s.x_max.is_some()) {
        let song = &songs[song_at(songs, x)?];
        return song.year.map(|year| Reading {
            name,
            value: year.to_string(),
        });
    }
    Some(reading_at(&axes.x, "year", axes.x.value_at(f64::from(x))))
}

/// Density at which a hover ray stops in the Volume view (the Surface view's stops at its
/// isovalue).
pub const VOLUME_PICK_DENSITY: f32 = 0.1;

/// The read-out of the Surface or the Volume view under the ray (`origin`, `dir`, data space)
/// and the x it reads at: the first voxel of `field` at or above `threshold`, in `axes`' units
/// ([`voxel_readings`]); where the ray meets none (or no grid is there yet), the first axis's
/// value where it enters the data box; nothing where it misses the box. The window's hover
/// (src/ui/hover.rs) and the web page's read-out both call it.
pub fn grid_readout(
    field: Option<&Field>,
    axes: &Axes,
    origin: Vec3,
    dir: Vec3,
    threshold: f32,
) -> (Vec<Reading>, Option<f32>) {
    if let Some(hit) = field.and_then(|f| f.pick(origin, dir, threshold)) {
        return (voxel_readings(axes, &hit), Some(hit.position.x));
    }
    box_readout(axes, origin, dir)
}

/// Where the ray enters the data box: the first axis's value there and its x (nothing where it
/// misses the box).
pub fn box_readout(axes: &Axes, origin: Vec3, dir: Vec3) -> (Vec<Reading>, Option<f32>) {
    match ray_box(origin, dir, Vec3::splat(-1.0), Vec3::ONE) {
        Some((t, _)) => {
            let p = origin + dir * t;
            let first = position_readings(axes, p);
            (
                first.into_iter().take(1).collect(),
                Some(p.x.clamp(-1.0, 1.0)),
            )
        }
        None => (Vec::new(), None),
    }
}

/// The read-out's last touches, by the data's mode: on a timeline the year at `x` comes from
/// the song spans ([`timeline_year`]), and is dropped between songs; a song's y is the level of
/// one STFT bin, not a loudness, and says so ("bin level", as the axis title does).
pub fn name_readings(
    readings: &mut Vec<Reading>,
    axes: &Axes,
    mode: DataMode,
    songs: &[SongInfo],
    x: Option<f32>,
) {
    match (mode, x) {
        (DataMode::Timeline, Some(x)) => {
            let year = timeline_year(axes, songs, x);
            let name = year.as_ref().map_or_else(
                || timeline_year(axes, &[], x).map(|r| r.name),
                |r| Some(r.name.clone()),
            );
            if let Some(at) = readings.iter().position(|r| Some(&r.name) == name.as_ref()) {
                match year {
                    Some(year) => readings[at] = year,
                    None => {
                        readings.remove(at);
                    }
                }
            }
        }
        (DataMode::Song, _) => {
            for reading in readings.iter_mut().filter(|r| r.name == "level") {
                reading.name = "bin level".into();
            }
        }
        _ => {}
    }
}

/// The timeline song whose span `[x_min, x_max]` (normalized) holds `x`.
pub fn song_at(songs: &[SongInfo], x: f32) -> Option<usize> {
    let x = f64::from(x);
    songs.iter().position(|s| match (s.x_min, s.x_max) {
        (Some(a), Some(b)) => x >= a.min(b) && x <= a.max(b),
        _ => false,
    })
}

/// One line of a read-out: what and how much.
#[derive(Clone, Debug, PartialEq)]
pub struct Reading {
    pub name: String,
    pub value: String,
}

fn axis_name(axis: &Axis, fallback: &str) -> String {
    if axis.label.is_empty() {
        fallback.to_string()
    } else {
        axis.label.clone()
    }
}

/// A position axis's value with more precision than a tick, and the nearest note for Hz.
fn reading_at(axis: &Axis, fallback: &str, value: f64) -> Reading {
    let mut text = axis.format_value(value);
    if axis.unit == "Hz"
        && let Some(note) = note_name(value)
    {
        text = format!("{text} ({note})");
    }
    Reading {
        name: axis_name(axis, fallback),
        value: text,
    }
}

/// The physical values at a data-space position: time or year, level, frequency or crest factor.
pub fn position_readings(axes: &Axes, position: Vec3) -> Vec<Reading> {
    vec![
        reading_at(&axes.x, "x", axes.x.value_at(f64::from(position.x))),
        reading_at(&axes.z, "z", axes.z.value_at(f64::from(position.z))),
        reading_at(&axes.y, "y", axes.y.value_at(f64::from(position.y))),
    ]
}

/// Everything about one point: its position's values, loudness (scalar) and hp.
pub fn point_readings(axes: &Axes, point: &Point) -> Vec<Reading> {
    let mut out = position_readings(axes, Vec3::from(point.position));
    out.push(Reading {
        name: axis_name(&axes.scalar, "loudness"),
        value: axes
            .scalar
            .format_value(axes.scalar.value_at_unit(f64::from(point.scalar))),
    });
    out.push(Reading {
        name: "hp".into(),
        value: format!("{:.2} ({})", point.hp, hp_word(point.hp)),
    });
    out
}

/// A voxel's position values, density and mean hp.
pub fn voxel_readings(axes: &Axes, hit: &VoxelHit) -> Vec<Reading> {
    let mut out = position_readings(axes, hit.position);
    out.push(Reading {
        name: "density".into(),
        value: format!("{:.3}", hit.density),
    });
    out.push(Reading {
        name: "mean hp".into(),
        value: if hit.hp_mean.is_finite() {
            format!("{:.2} ({})", hit.hp_mean, hp_word(hit.hp_mean))
        } else {
            "no points nearby".into()
        },
    });
    out
}

fn hp_word(hp: f32) -> &'static str {
    if hp < 0.35 {
        "percussive"
    } else if hp > 0.65 {
        "harmonic"
    } else {
        "mixed"
    }
}
