//! `loudscape voxelize`: builds a cloud's voxel grid on the GPU (the same pass the volume and
//! surface views use) and writes its density and mean-hp fields.
//!
//! `.npy`: one float32 array of shape (2, N, N, N), C order, indexed [field, z, y, x]: field 0 is
//! the normalized loudness density, field 1 the mean hp; x (time) varies fastest, as in the
//! GPU's layout. `.nrrd`: two 3D files, `NAME.nrrd` (density) and `NAME_hp.nrrd` (mean hp), with
//! the voxel spacing and origin in data units, which ParaView and 3D Slicer open. Either way a
//! `OUTPUT.json` beside it records the box, the resolution and the normalization. Files are
//! written to a temporary name and renamed into place.

use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::{Context, bail};
use glam::{UVec3, Vec3};
use loudscape::render::gpu::context::GpuContext;
use loudscape::render::gpu::frame::FrameBinding;
use loudscape::render::grid::voxelize::{
    VoxelizePass, VoxelizeRequest, default_resolution, default_smoothing,
};
use loudscape::render::grid::voxelize_cpu::PERCENTILE;

use crate::commands::args::{
    check_not_input, check_output_folder, check_resolution, check_smoothing, load_cloud,
};

#[derive(clap::Args, Debug)]
pub struct VoxelizeArgs {
    /// The point cloud (.ply), or an audio file (WAV, FLAC, Ogg, MP3...), extracted by loudscape-extract and cached.
    pub input: PathBuf,
    /// Voxels per side (64 to 384); by default 128 for a song, 224 for a timeline.
    #[arg(long)]
    pub res: Option<u32>,
    /// Gaussian smoothing, sigma in voxels (0 turns it off); by default 1 for a song, 4 for a
    /// timeline.
    #[arg(long)]
    pub smooth: Option<f32>,
    /// Where to write: a .npy file, or a .nrrd file (plus NAME_hp.nrrd).
    #[arg(short, long)]
    pub output: PathBuf,
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum Format {
    Npy,
    Nrrd,
}

fn format_of(path: &Path) -> anyhow::Result<Format> {
    match path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .as_deref()
    {
        Some("npy") => Ok(Format::Npy),
        Some("nrrd") => Ok(Format::Nrrd),
        _ => bail!("{}: the output must end in .npy or .nrrd", path.display()),
    }
}

pub fn run(args: VoxelizeArgs) -> anyhow::Result<()> {
    let format = format_of(&args.output)?;
    let meta_path = PathBuf::from(format!("{}.json", args.output.display()));
    let mut outputs = vec![args.output.clone(), meta_path.clone()];
    if format == Format::Nrrd {
        outputs.push(hp_nrrd_path(&args.output));
    }
    for output in &outputs {
        check_not_input(output, &[&args.input])?;
    }
    check_output_folder(&args.output)?;
    check_resolution(args.res)?;
    if let Some(sigma) = args.smooth {
        check_smoothing(sigma)?;
    }
    let cloud = load_cloud(&args.input)?;
    let resolution = args.res.unwrap_or(default_resolution(cloud.meta.mode));
    let sigma = args.smooth.unwrap_or(default_smoothing(cloud.meta.mode));
    let gpu = GpuContext::new_headless()?;
    let frame = FrameBinding::new(&gpu.device);
    let pass = VoxelizePass::new(&gpu.device, &frame);
    let (grid, stats) = pass
        .voxelize(
            &gpu.device,
            &gpu.queue,
            &VoxelizeRequest::new(&cloud.points, resolution, sigma),
        )
        .with_context(|| format!("{}", args.input.display()))?;
    let density = grid.read_field(&gpu.device, &gpu.queue, &grid.density)?;
    let hp_mean = grid.read_field(&gpu.device, &gpu.queue, &grid.hp_mean)?;
    let meta = serde_json::json!({
        "source": args.input.display().to_string(),
        "dims": [grid.dims.x, grid.dims.y, grid.dims.z],
        "dtype": "<f4",
        "box_min": grid.box_min.to_array(),
        "box_max": grid.box_max.to_array(),
        "voxel_centre": "box_min + (index + 0.5) * (box_max - box_min) / dims",
        "npy_axes": ["field", "z", "y", "x"],
        "fields": ["density", "hp_mean"],
        "smoothing_sigma_voxels": sigma,
        "normalization": format!(
            "density = min(loudness sum / reference_sum, 1); reference_sum is the {}th percentile of the positive sums",
            PERCENTILE * 100.0
        ),
        "reference_sum": stats.reference_sum,
        "nonempty_voxels": stats.nonempty,
        "points": cloud.points.len(),
    });
    let meta_text = serde_json::to_string_pretty(&meta)?;
    // The array(s) and the description appear together or not at all: all written and fsynced
    // under temporary names, then renamed.
    let written: Vec<PathBuf> = match format {
        Format::Npy => vec![args.output.clone(), meta_path],
        Format::Nrrd => vec![args.output.clone(), hp_nrrd_path(&args.output), meta_path],
    };
    let targets: Vec<&Path> = written.iter().map(PathBuf::as_path).collect();
    let spacing = grid.voxel_size();
    let origin = grid.box_min + spacing * 0.5;
    loudscape::files::write_together(&targets, |i, out| -> anyhow::Result<()> {
        match (format, i) {
            (_, i) if i + 1 == targets.len() => out.write_all(meta_text.as_bytes())?,
            (Format::Npy, _) => super::npy::write(out, &[&density, &hp_mean], grid.dims)?,
            (Format::Nrrd, 0) => write_nrrd(
                out,
                &density,
                grid.dims,
                origin,
                spacing,
                "normalized loudness density",
            )?,
            (Format::Nrrd, _) => write_nrrd(
                out,
                &hp_mean,
                grid.dims,
                origin,
                spacing,
                "mean hp (0 percussive, 1 harmonic)",
            )?,
        }
        Ok(())
    })
    .map_err(|e| super::write_error(&args.output, e))?;
    let detail = format!(
        "{} points into {r}x{r}x{r}, {} voxels non-empty",
        cloud.points.len(),
        stats.nonempty,
        r = resolution
    );
    for path in written {
        super::wrote(&path, &detail);
    }
    Ok(())
}

/// `grid.nrrd` -> `grid_hp.nrrd`.
fn hp_nrrd_path(path: &Path) -> PathBuf {
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "grid".into());
    path.with_file_name(format!("{stem}_hp.nrrd"))
}

/// NRRD 4: one float field, raw little-endian, x fastest, with spacing and origin.
pub fn write_nrrd(
    out: &mut impl Write,
    field: &[f32],
    dims: UVec3,
    origin: Vec3,
    spacing: Vec3,
    what: &str,
) -> anyhow::Result<()> {
    write!(
        out,
        "NRRD0004\n# loudscape voxel grid: {what}\ntype: float\ndimension: 3\n\
         sizes: {} {} {}\nspace dimension: 3\n\
         space directions: ({},0,0) (0,{},0) (0,0,{})\nspace origin: ({},{},{})\n\
         kinds: domain domain domain\nendian: little\nencoding: raw\n\n",
        dims.x, dims.y, dims.z, spacing.x, spacing.y, spacing.z, origin.x, origin.y, origin.z
    )?;
    for v in field {
        out.write_all(&v.to_le_bytes())?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn npy_header_is_aligned_and_describes_the_array() {
        let dims = UVec3::new(2, 3, 4);
        let density: Vec<f32> = (0..24).map(|i| i as f32).collect();
        let hp = vec![0.5f32; 24];
        let mut bytes = Vec::new();
        crate::commands::npy::write(&mut bytes, &[&density, &hp], dims).unwrap();
        let header_len = u16::from_le_bytes([bytes[8], bytes[9]]) as usize;
        assert_eq!((10 + header_len) % 64, 0);
        let header = std::str::from_utf8(&bytes[10..10 + header_len]).unwrap();
        assert!(header.contains("'shape': (2, 4, 3, 2)"), "{header}");
        assert!(header.ends_with('\n'));
        assert_eq!(bytes.len(), 10 + header_len + 48 * 4);
        let first = 10 + header_len;
        assert_eq!(
            f32::from_le_bytes(bytes[first + 4..first + 8].try_into().unwrap()),
            1.0
        );
    }

    #[test]
    fn nrrd_has_a_header_then_raw_floats() {
        let mut bytes = Vec::new();
        let field = [1.0f32; 8];
        write_nrrd(
            &mut bytes,
            &field,
            UVec3::splat(2),
            Vec3::ZERO,
            Vec3::ONE,
            "density",
        )
        .unwrap();
        let text = String::from_utf8_lossy(&bytes);
        let end = text.find("\n\n").unwrap() + 2;
        assert!(text.starts_with("NRRD0004\n") && text.contains("sizes: 2 2 2\n"));
        assert_eq!(bytes.len() - end, 32);
        assert_eq!(
            hp_nrrd_path(Path::new("a/grid.nrrd")),
            Path::new("a/grid_hp.nrrd")
        );
        assert!(format_of(Path::new("x.vtk")).is_err());
    }
}
