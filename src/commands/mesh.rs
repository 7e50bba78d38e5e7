//! `loudscape mesh`: extracts an isosurface on the GPU and writes it as a mesh (.ply or .obj)
//! with per-vertex normals and hp colours.

use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::{Context, bail};
use loudscape::data::cloud::PointCloud;
use loudscape::data::field::Field;
use loudscape::render::colormap::HpColourMap;
use loudscape::render::gpu::context::GpuContext;
use loudscape::render::gpu::frame::FrameBinding;
use loudscape::render::grid::VoxelGrid;
use loudscape::render::grid::voxelize::{
    MAX_RESOLUTION, VoxelSettings, VoxelizePass, VoxelizeRequest, default_resolution,
};
use loudscape::render::surface::cpu_mesh::CpuMesh;
use loudscape::render::surface::pass::SurfacePass;
use loudscape::render::surface::state::ExtractedSurface;
use loudscape::render::surface::{SurfaceMethod, SurfaceSettings};

use crate::commands::args::{
    check_iso, check_not_input, check_output_folder, check_resolution, load_cloud,
};

#[derive(clap::Args, Debug)]
pub struct MeshArgs {
    /// The point cloud (.ply), an audio file (WAV, FLAC, Ogg, MP3...), extracted by loudscape-extract and cached, or a density field (.npy: float32 or float64, shape (nz, ny, nx),
    /// or (fields, nz, ny, nx) with the mean hp as field 1, as `loudscape voxelize` writes).
    pub input: PathBuf,
    /// Extraction method: mt (marching tetrahedra) or dc (dual contouring).
    #[arg(long, value_enum, ignore_case = true, default_value_t = SurfaceMethod::MarchingTetrahedra)]
    pub method: SurfaceMethod,
    /// Isovalue in [0, 1] of the normalized loudness density.
    #[arg(long, default_value_t = 0.5)]
    pub iso: f32,
    /// Grid resolution per axis for a point cloud (default: 128 for a song, 224 for a
    /// timeline); a .npy field is meshed at its own.
    #[arg(long)]
    pub res: Option<u32>,
    /// The mesh file to write: .ply (binary) or .obj.
    #[arg(short, long)]
    pub output: PathBuf,
}

/// The cloud's voxel grid, built by the GPU voxelizer with its mode's default smoothing.
pub fn voxel_grid(
    gpu: &GpuContext,
    frame: &FrameBinding,
    cloud: &PointCloud,
    res: u32,
) -> anyhow::Result<VoxelGrid> {
    let pass = VoxelizePass::new(&gpu.device, frame);
    let (grid, _) = pass
        .voxelize(
            &gpu.device,
            &gpu.queue,
            &VoxelizeRequest::new(
                &cloud.points,
                res,
                VoxelSettings::default().smoothing_for(cloud.meta.mode),
            ),
        )
        .with_context(|| format!("{}: voxelizing", cloud.path.display()))?;
    Ok(grid)
}

pub fn run(args: MeshArgs) -> anyhow::Result<()> {
    let method = args.method;
    let iso_value = check_iso(args.iso)?;
    let format = MeshFormat::from_path(&args.output)?;
    check_resolution(args.res)?;
    // Neither the input nor the box file read beside a .npy field may be written over.
    let field_meta = PathBuf::from(format!("{}.json", args.input.display()));
    check_not_input(&args.output, &[&args.input, &field_meta])?;
    check_output_folder(&args.output)?;
    let is_field = args
        .input
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("npy"));
    // Read and check the input before starting the GPU.
    enum Input {
        Field(Field),
        Cloud(Box<PointCloud>),
    }
    let input = if is_field {
        if args.res.is_some() {
            bail!(
                "{}: --res applies to point clouds; a .npy field is meshed at its own resolution",
                args.input.display()
            );
        }
        Input::Field(read_field(&args.input)?)
    } else {
        Input::Cloud(Box::new(load_cloud(&args.input)?))
    };
    let gpu = GpuContext::new_headless()?;
    let frame = FrameBinding::new(&gpu.device);
    let grid = match input {
        Input::Field(field) => VoxelGrid::from_fields(
            &gpu.device,
            field.dims,
            field.box_min,
            field.box_max,
            &field.density,
            &field.hp_mean,
        ),
        Input::Cloud(cloud) => {
            let res = args.res.unwrap_or(default_resolution(cloud.meta.mode));
            voxel_grid(&gpu, &frame, &cloud, res)?
        }
    };
    let dims = grid.dims;
    let pass = SurfacePass::new(&gpu.device, &frame);
    let surface = ExtractedSurface::new();
    let settings = SurfaceSettings {
        method,
        iso_value,
        lit: true,
    };
    let counts = pass
        .extract_blocking(&gpu.queue, &surface, &grid, &settings)
        .with_context(|| format!("{}: extracting the surface", args.input.display()))?;
    let mut mesh = pass
        .read_mesh(&gpu.queue, &surface)
        .with_context(|| format!("{}: reading the surface", args.input.display()))?;
    if method == SurfaceMethod::MarchingTetrahedra {
        mesh = mesh.welded();
    }
    let comment = format!(
        "loudscape isosurface of {} method={} iso={iso_value} grid={}x{}x{}",
        args.input
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default(),
        method.short_name(),
        dims.x,
        dims.y,
        dims.z
    );
    write_mesh(&mesh, format, &comment, &args.output)?;
    super::wrote(
        &args.output,
        &format!(
            "{} vertices, {} triangles; {} triangles extracted",
            mesh.positions.len(),
            mesh.triangle_count(),
            counts.triangles()
        ),
    );
    Ok(())
}

/// Reads a .npy density field (field 0; field 1, when present, is the mean hp, else 0.5).
/// The box comes from the `FIELD.npy.json` that `loudscape voxelize` writes beside it; without
/// one, voxel (i, j, k) is centred on the point (i, j, k), so the mesh is in voxel units.
pub fn read_field(path: &Path) -> anyhow::Result<Field> {
    let npy = super::npy::read(path)?;
    if npy.dims.min_element() < 2 || npy.dims.max_element() > MAX_RESOLUTION {
        bail!(
            "{}: the field is {}x{}x{} voxels; a surface needs at least 2 and at most \
             {MAX_RESOLUTION} along each axis",
            path.display(),
            npy.dims.x,
            npy.dims.y,
            npy.dims.z
        );
    }
    // The description beside it must be of this array (dims, dtype, fields).
    let (box_min, box_max) = super::npy::field_box(path, &npy)?;
    let mut fields = npy.fields.into_iter();
    let density = fields.next().expect("at least one field");
    let hp_mean = fields.next().unwrap_or_else(|| vec![0.5; density.len()]);
    for (name, values) in [("density", &density), ("hp", &hp_mean)] {
        if let Some(i) = values.iter().position(|v| !v.is_finite()) {
            let (x, y, z) = (
                i as u32 % npy.dims.x,
                i as u32 / npy.dims.x % npy.dims.y,
                i as u32 / (npy.dims.x * npy.dims.y),
            );
            bail!(
                "{}: the {name} is not finite at voxel (x {x}, y {y}, z {z})",
                path.display()
            );
        }
    }
    Ok(Field {
        dims: npy.dims,
        box_min,
        box_max,
        density,
        hp_mean,
    })
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MeshFormat {
    Ply,
    Obj,
}

impl MeshFormat {
    pub fn from_path(path: &Path) -> anyhow::Result<Self> {
        match path
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase())
            .as_deref()
        {
            Some("ply") => Ok(Self::Ply),
            Some("obj") => Ok(Self::Obj),
            _ => bail!("{}: the mesh file must end in .ply or .obj", path.display()),
        }
    }
}

/// Writes `mesh` through a temporary file beside `output`, renamed into place when complete.
pub fn write_mesh(
    mesh: &CpuMesh,
    format: MeshFormat,
    comment: &str,
    output: &Path,
) -> anyhow::Result<()> {
    super::write_atomically(output, |w| {
        match format {
            MeshFormat::Ply => write_ply(w, mesh, comment)?,
            MeshFormat::Obj => write_obj(w, mesh, comment)?,
        }
        Ok(())
    })
}

fn rgb8(hp: f32) -> [u8; 3] {
    HpColourMap::Classic.surface().sample_u8(hp)
}

fn write_ply(w: &mut impl Write, mesh: &CpuMesh, comment: &str) -> std::io::Result<()> {
    write!(
        w,
        "ply\nformat binary_little_endian 1.0\ncomment {comment}\nelement vertex {}\n\
         property float x\nproperty float y\nproperty float z\n\
         property float nx\nproperty float ny\nproperty float nz\n\
         property uchar red\nproperty uchar green\nproperty uchar blue\nproperty float hp\n\
         element face {}\nproperty list uchar uint vertex_indices\nend_header\n",
        mesh.positions.len(),
        mesh.triangle_count()
    )?;
    for ((p, n), &hp) in mesh.positions.iter().zip(&mesh.normals).zip(&mesh.hp) {
        for v in [p.x, p.y, p.z, n.x, n.y, n.z] {
            w.write_all(&v.to_le_bytes())?;
        }
        w.write_all(&rgb8(hp))?;
        w.write_all(&hp.to_le_bytes())?;
    }
    for tri in mesh.indices.chunks_exact(3) {
        w.write_all(&[3u8])?;
        for i in tri {
            w.write_all(&i.to_le_bytes())?;
        }
    }
    Ok(())
}

fn write_obj(w: &mut impl Write, mesh: &CpuMesh, comment: &str) -> std::io::Result<()> {
    writeln!(w, "# {comment}")?;
    writeln!(
        w,
        "# v x y z r g b (warm-to-cool hp colour), vn: unit normals"
    )?;
    for (p, &hp) in mesh.positions.iter().zip(&mesh.hp) {
        let c = HpColourMap::Classic.surface().sample(hp);
        writeln!(
            w,
            "v {} {} {} {:.4} {:.4} {:.4}",
            p.x, p.y, p.z, c[0], c[1], c[2]
        )?;
    }
    for n in &mesh.normals {
        writeln!(w, "vn {} {} {}", n.x, n.y, n.z)?;
    }
    for tri in mesh.indices.chunks_exact(3) {
        let [a, b, c] = [tri[0] + 1, tri[1] + 1, tri[2] + 1];
        writeln!(w, "f {a}//{a} {b}//{b} {c}//{c}")?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;
    use loudscape::data::cloud::DataMode;
    use loudscape::data::cloud::Point;

    /// A blob of points in the stand-in grid, meshed on the GPU and written both ways.
    #[test]
    fn a_cloud_meshes_and_exports_as_ply_and_obj() {
        let mut points = Vec::new();
        for i in 0..40 {
            for j in 0..40 {
                for k in 0..40 {
                    let p = Vec3::new(i as f32, j as f32, k as f32) / 19.5 - 1.0;
                    let scalar = (1.0 - p.length()).max(0.0);
                    points.push(Point {
                        position: p.to_array(),
                        scalar,
                        hp: (p.x + 1.0) * 0.5,
                    });
                }
            }
        }
        let cloud = PointCloud::synthetic(points, DataMode::Song);
        let gpu = match GpuContext::new_headless() {
            Ok(gpu) => gpu,
            Err(e) => panic!("GPU tests need an adapter (lavapipe will do): {e}"),
        };
        let frame = FrameBinding::new(&gpu.device);
        let grid = voxel_grid(&gpu, &frame, &cloud, 64).expect("voxelize");
        let pass = SurfacePass::new(&gpu.device, &frame);
        let surface = ExtractedSurface::new();
        let settings = SurfaceSettings {
            method: SurfaceMethod::MarchingTetrahedra,
            iso_value: 0.3,
            lit: true,
        };
        pass.extract_blocking(&gpu.queue, &surface, &grid, &settings)
            .expect("extract");
        let mesh = pass.read_mesh(&gpu.queue, &surface).expect("read").welded();
        assert!(mesh.triangle_count() > 100);
        let dir = std::env::temp_dir().join(format!("loudscape-mesh-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        let ply = dir.join("blob.ply");
        write_mesh(&mesh, MeshFormat::Ply, "test", &ply).expect("ply");
        let bytes = std::fs::read(&ply).expect("read ply");
        let header_end = bytes
            .windows(11)
            .position(|w| w == b"end_header\n")
            .expect("header")
            + 11;
        let header = String::from_utf8_lossy(&bytes[..header_end]);
        assert!(header.contains(&format!("element vertex {}", mesh.positions.len())));
        assert!(header.contains(&format!("element face {}", mesh.triangle_count())));
        let expected = header_end + mesh.positions.len() * 31 + mesh.triangle_count() * 13;
        assert_eq!(bytes.len(), expected);
        let obj = dir.join("blob.obj");
        write_mesh(&mesh, MeshFormat::Obj, "test", &obj).expect("obj");
        let text = std::fs::read_to_string(&obj).expect("read obj");
        assert_eq!(
            text.lines().filter(|l| l.starts_with("f ")).count(),
            mesh.triangle_count()
        );
        assert!(!dir.join("blob.obj.tmp").exists());
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn bad_arguments_are_one_line_errors() {
        assert_eq!(SurfaceMethod::parse("mc"), None);
        assert_eq!(
            SurfaceMethod::parse("DC"),
            Some(SurfaceMethod::DualContouring)
        );
        assert_eq!(
            SurfaceMethod::parse("dual-contouring"),
            Some(SurfaceMethod::DualContouring)
        );
        assert!(check_iso(f32::NAN).is_err());
        assert!(check_iso(1.5).is_err());
        assert!(MeshFormat::from_path(Path::new("a.stl")).is_err());
    }
}
