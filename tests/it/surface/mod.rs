//! Isosurfaces on the GPU (lavapipe where there is no GPU), read back and checked against
//! analytic answers: sphere area, closed 2-manifolds of the right genus, dual-contouring vertices
//! inside their cells, outward normals, degenerate isovalues, buffer growth, golden images; and
//! the CPU engine (used where the device is the CPU) held to the GPU passes' surface. Golden
//! images, the coarse level of detail and the CPU engine have modules of their own.

use crate::common;

use std::collections::HashMap;

use glam::{UVec3, Vec3};
use loudscape::data::cloud::{DataMode, PointCloud};
use loudscape::data::synthetic::song_like_field;
use loudscape::render::gpu::context::GpuContext;
use loudscape::render::gpu::frame::FrameBinding;
use loudscape::render::grid::VoxelGrid;
use loudscape::render::scene::{RenderSettings, Renderer, SceneData, ViewKind};
use loudscape::render::surface::cpu::SurfaceEngine;
use loudscape::render::surface::cpu_mesh::CpuMesh;
use loudscape::render::surface::pass::SurfacePass;
use loudscape::render::surface::state::ExtractedSurface;
use loudscape::render::surface::{SurfaceMethod, SurfaceSettings};
use loudscape::view::camera::Camera;
use loudscape::view::frame_view::FrameView;

const MT: SurfaceMethod = SurfaceMethod::MarchingTetrahedra;
const DC: SurfaceMethod = SurfaceMethod::DualContouring;

/// A grid over [-1, 1]^3 sampling `field` at voxel centres; hp follows x.
fn grid_from(gpu: &GpuContext, n: u32, field: impl Fn(Vec3) -> f32) -> VoxelGrid {
    let dims = UVec3::splat(n);
    let size = 2.0 / n as f32;
    let mut density = Vec::new();
    let mut hp = Vec::new();
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                let p = Vec3::new(i as f32, j as f32, k as f32) * size + (size * 0.5 - 1.0);
                density.push(field(p).clamp(0.0, 1.0));
                hp.push((p.x + 1.0) * 0.5);
            }
        }
    }
    unit_box_grid(gpu, dims, &density, &hp)
}

/// A grid of `dims` samples over [-1, 1]^3 from its density and hp fields.
fn unit_box_grid(gpu: &GpuContext, dims: UVec3, density: &[f32], hp: &[f32]) -> VoxelGrid {
    VoxelGrid::from_fields(&gpu.device, dims, Vec3::splat(-1.0), Vec3::ONE, density, hp)
}

const SPHERE_RADIUS: f32 = 0.6;

/// 0.5 on a sphere, rising inward, falling outward, linear over about eight voxels at 128^3.
fn sphere(p: Vec3) -> f32 {
    0.5 - (p.length() - SPHERE_RADIUS) * 4.0
}

const TORUS_MAJOR: f32 = 0.5;
const TORUS_MINOR: f32 = 0.2;

fn torus(p: Vec3) -> f32 {
    let ring = Vec3::new(p.x, 0.0, p.z).length() - TORUS_MAJOR;
    let distance = (ring * ring + p.y * p.y).sqrt() - TORUS_MINOR;
    0.5 - distance * 4.0
}

fn extract(
    gpu: &GpuContext,
    pass: &SurfacePass,
    grid: &VoxelGrid,
    method: SurfaceMethod,
    iso_value: f32,
) -> CpuMesh {
    let settings = SurfaceSettings {
        method,
        iso_value,
        lit: true,
    };
    let surface = ExtractedSurface::new();
    let counts = pass
        .extract_blocking(&gpu.queue, &surface, grid, &settings)
        .expect("extraction");
    assert!(counts.fits(), "{counts:?}");
    pass.read_mesh(&gpu.queue, &surface).expect("read back")
}

/// The GPU passes, whatever the device (these tests check the shaders; the CPU engine is held
/// to them by `cpu_engine_extracts_the_gpu_surface_triangle_for_triangle`).
fn surface_pass(gpu: &GpuContext) -> SurfacePass {
    engine_pass(gpu, SurfaceEngine::Gpu)
}

fn engine_pass(gpu: &GpuContext, engine: SurfaceEngine) -> SurfacePass {
    let frame = FrameBinding::new(&gpu.device);
    SurfacePass::new(&gpu.device, &frame).with_engine(engine)
}

/// The window runs whichever engine suits the device (the CPU on lavapipe): its paths are
/// tested on both.
const ENGINES: [SurfaceEngine; 2] = [SurfaceEngine::Gpu, SurfaceEngine::Cpu];

/// Every undirected edge of the welded mesh is in exactly two triangles, the two use it in
/// opposite directions (consistent orientation); returns V - E + F.
fn closed_manifold_euler(mesh: &CpuMesh) -> i64 {
    let welded = mesh.welded();
    let mut edges: HashMap<(u32, u32), (u32, u32)> = HashMap::new();
    for tri in welded.indices.chunks_exact(3) {
        for (a, b) in [(tri[0], tri[1]), (tri[1], tri[2]), (tri[2], tri[0])] {
            let entry = edges.entry((a.min(b), a.max(b))).or_default();
            if a < b {
                entry.0 += 1;
            } else {
                entry.1 += 1;
            }
        }
    }
    for (edge, (forward, backward)) in &edges {
        assert_eq!(
            (*forward, *backward),
            (1, 1),
            "edge {edge:?} is used {forward} times forward and {backward} backward"
        );
    }
    let used: std::collections::HashSet<u32> = welded.indices.iter().copied().collect();
    used.len() as i64 - edges.len() as i64 + welded.triangle_count() as i64
}

#[test]
fn sphere_area_within_two_percent_for_both_methods() {
    let gpu = common::gpu();
    let pass = surface_pass(&gpu);
    let grid = grid_from(&gpu, 128, sphere);
    let expected = 4.0 * std::f64::consts::PI * f64::from(SPHERE_RADIUS).powi(2);
    for method in SurfaceMethod::ALL {
        let mesh = extract(&gpu, &pass, &grid, method, 0.5);
        let area = mesh.area();
        let error = (area - expected).abs() / expected;
        println!(
            "{}: {} triangles, area {area:.5} vs {expected:.5} ({:.3}%)",
            method.name(),
            mesh.triangle_count(),
            error * 100.0
        );
        assert!(
            error < 0.02,
            "{}: area off by {:.2}%",
            method.name(),
            error * 100.0
        );
    }
}

#[test]
fn marching_tets_sphere_is_a_closed_manifold_of_genus_zero() {
    let gpu = common::gpu();
    let pass = surface_pass(&gpu);
    let grid = grid_from(&gpu, 48, sphere);
    let mesh = extract(&gpu, &pass, &grid, MT, 0.5);
    assert!(mesh.triangle_count() > 1000);
    assert_eq!(closed_manifold_euler(&mesh), 2);
}

#[test]
fn marching_tets_torus_is_a_closed_manifold_of_genus_one() {
    let gpu = common::gpu();
    let pass = surface_pass(&gpu);
    let grid = grid_from(&gpu, 48, torus);
    let mesh = extract(&gpu, &pass, &grid, MT, 0.5);
    assert_eq!(closed_manifold_euler(&mesh), 0);
}

#[test]
fn marching_tets_closes_surfaces_cut_by_the_grid_border() {
    // A slab filling the grid's lower half: the border closes it into a box.
    let gpu = common::gpu();
    let pass = surface_pass(&gpu);
    let grid = grid_from(&gpu, 24, |p| 0.5 - p.y * 3.0);
    let mesh = extract(&gpu, &pass, &grid, MT, 0.5);
    assert_eq!(closed_manifold_euler(&mesh), 2);
}

#[test]
fn dual_contour_vertices_lie_inside_straddling_cells() {
    let gpu = common::gpu();
    let pass = surface_pass(&gpu);
    let n = 40;
    let field = |p: Vec3| torus(p) + 0.08 * (p.x * 9.0).sin() * (p.z * 7.0).cos();
    let grid = grid_from(&gpu, n, field);
    let values = grid
        .read_field(&gpu.device, &gpu.queue, &grid.density)
        .expect("density");
    let iso = 0.5;
    let sample = |q: [i32; 3]| -> f32 {
        if q.iter().any(|&c| c < 0 || c >= n as i32) {
            return 0.0;
        }
        values[(q[0] + n as i32 * (q[1] + n as i32 * q[2])) as usize]
    };
    let straddles = |c: [i32; 3]| -> bool {
        let mut inside = 0;
        for k in 0..8 {
            let q = [c[0] + (k & 1), c[1] + ((k >> 1) & 1), c[2] + ((k >> 2) & 1)];
            inside += i32::from(sample(q) > iso);
        }
        inside != 0 && inside != 8
    };
    let mut straddling = 0;
    for z in -1..n as i32 {
        for y in -1..n as i32 {
            for x in -1..n as i32 {
                straddling += usize::from(straddles([x, y, z]));
            }
        }
    }
    let mesh = extract(&gpu, &pass, &grid, DC, iso);
    assert_eq!(
        mesh.positions.len(),
        straddling,
        "one vertex per straddling cell"
    );
    let voxel = grid.voxel_size();
    for p in &mesh.positions {
        // Grid coordinates of the vertex; its cell is the floor, or a neighbour when it sits on
        // a cell face.
        let g = (*p - grid.box_min) / voxel - 0.5;
        let eps = 1e-3;
        let options = |v: f32| {
            let lo = (v - eps).floor() as i32;
            let hi = (v + eps).floor() as i32;
            lo..=hi
        };
        let found =
            options(g.x).any(|x| options(g.y).any(|y| options(g.z).any(|z| straddles([x, y, z]))));
        assert!(
            found,
            "vertex {p} (grid {g}) is not inside a straddling cell"
        );
    }
}

#[test]
fn normals_and_faces_point_outward_for_both_methods() {
    let gpu = common::gpu();
    let pass = surface_pass(&gpu);
    let grid = grid_from(&gpu, 48, sphere);
    for method in SurfaceMethod::ALL {
        let mesh = extract(&gpu, &pass, &grid, method, 0.5);
        for (p, n) in mesh.positions.iter().zip(&mesh.normals) {
            assert!((n.length() - 1.0).abs() < 1e-3, "normal {n} is not unit");
            assert!(
                n.dot(p.normalize()) > 0.9,
                "{}: normal {n} at {p} does not point outward",
                method.name()
            );
        }
        for t in 0..mesh.triangle_count() {
            let [a, b, c] = mesh.triangle(t);
            let face = (b - a).cross(c - a);
            if face.length() > 1e-9 {
                assert!(
                    face.dot(a + b + c) > 0.0,
                    "{}: triangle {t} faces inward",
                    method.name()
                );
            }
        }
    }
}

#[test]
fn isovalues_at_and_beyond_the_field_range_never_fail() {
    let gpu = common::gpu();
    let pass = surface_pass(&gpu);
    let grid = grid_from(&gpu, 32, sphere);
    for method in SurfaceMethod::ALL {
        for iso in [1.0, 1.5, -0.5, f32::MAX, f32::NAN] {
            let mesh = extract(&gpu, &pass, &grid, method, iso);
            assert_eq!(mesh.triangle_count(), 0, "{} at {iso}", method.name());
        }
        // At 0 every voxel with any density is inside: the surface wraps the field's support,
        // here the whole grid (closed by its border).
        let mesh = extract(&gpu, &pass, &grid, method, 0.0);
        assert!(mesh.triangle_count() > 0, "{} at 0", method.name());
    }
    // An empty field gives an empty surface at every isovalue.
    let empty = grid_from(&gpu, 16, |_| 0.0);
    for method in SurfaceMethod::ALL {
        for iso in [0.0, 0.5, 1.0] {
            assert_eq!(
                extract(&gpu, &pass, &empty, method, iso).triangle_count(),
                0
            );
        }
    }
}

#[test]
fn buffers_grow_until_the_surface_fits() {
    let gpu = common::gpu();
    let frame = FrameBinding::new(&gpu.device);
    let grid = grid_from(&gpu, 40, torus);
    let reference = extract(&gpu, &surface_pass(&gpu), &grid, DC, 0.5);
    let reference_mt = extract(&gpu, &surface_pass(&gpu), &grid, MT, 0.5);
    for ((method, triangles), engine) in [
        (MT, reference_mt.triangle_count()),
        (DC, reference.triangle_count()),
    ]
    .into_iter()
    .flat_map(|case| ENGINES.map(|engine| (case, engine)))
    {
        let small = || SurfacePass::with_capacity(&gpu.device, &frame, 64, 96).with_engine(engine);
        // Blocking path.
        let small_blocking = small();
        let mesh = extract(&gpu, &small_blocking, &grid, method, 0.5);
        assert_eq!(mesh.triangle_count(), triangles);

        // Interactive path: extracted on the background thread (which grows its buffers until
        // the surface fits); frames go on meanwhile and the result is installed when ready.
        let small = small();
        let settings = SurfaceSettings {
            method,
            iso_value: 0.5,
            lit: true,
        };
        let surface = ExtractedSurface::new();
        let mut frames = 0;
        loop {
            small.prepare(&gpu.queue, &surface, Some(&grid), &settings);
            // The frame's submission (its style write; the worker extracts).
            gpu.queue.submit([]);
            frames += 1;
            if !surface.needs_another_frame() {
                break;
            }
            assert!(
                frames < 12_000,
                "{}: the surface never settled",
                method.name()
            );
            std::thread::sleep(std::time::Duration::from_millis(5));
        }
        let counts = surface.counts().expect("counts");
        assert!(counts.fits(), "{counts:?}");
        assert_eq!(counts.triangles() as usize, triangles);
        let mesh = small.read_mesh(&gpu.queue, &surface).expect("read");
        assert_eq!(mesh.triangle_count(), triangles);
    }
}

/// The mesh's triangles as sorted records of their corners' position, normal and hp bits, each
/// rotated to start at its smallest corner (winding kept), independent of vertex order.
fn triangle_set(mesh: &CpuMesh) -> Vec<[[u32; 7]; 3]> {
    let corner = |i: u32| {
        let (p, n) = (mesh.positions[i as usize], mesh.normals[i as usize]);
        [p.x, p.y, p.z, n.x, n.y, n.z, mesh.hp[i as usize]].map(f32::to_bits)
    };
    let mut triangles: Vec<[[u32; 7]; 3]> = mesh
        .indices
        .chunks_exact(3)
        .map(|t| {
            let mut c = [corner(t[0]), corner(t[1]), corner(t[2])];
            let first = (0..3).min_by_key(|&k| c[k]).unwrap();
            c.rotate_left(first);
            c
        })
        .collect();
    triangles.sort_unstable();
    triangles
}

/// The window's worker extracts in slices, one submission per pass, so frames can run between
/// them; the mesh is the same, vertex for vertex and index for index, as one submission's, for
/// both methods, also when the buffers must grow (the sphere's area is checked against the
/// analytic one above, so this is the CPU-reference-checked surface).
#[test]
fn sliced_extraction_equals_one_submission() {
    let gpu = common::gpu();
    let frame = FrameBinding::new(&gpu.device);
    for (grid, iso_value) in [
        (grid_from(&gpu, 64, sphere), 0.5),
        (grid_from(&gpu, 40, torus), 0.35),
    ] {
        for method in [MT, DC] {
            let settings = SurfaceSettings {
                method,
                iso_value,
                lit: true,
            };
            let whole = extract(&gpu, &surface_pass(&gpu), &grid, method, iso_value);
            assert!(whole.triangle_count() > 100, "{}", method.name());
            for pass in [
                surface_pass(&gpu),
                SurfacePass::with_capacity(&gpu.device, &frame, 64, 96)
                    .with_engine(SurfaceEngine::Gpu),
            ] {
                let surface = ExtractedSurface::new();
                let (counts, submissions) = pass
                    .extract_in_slices(&gpu.queue, &surface, &grid, &settings)
                    .expect("sliced extraction");
                assert!(counts.fits(), "{counts:?}");
                // Six passes, six submissions per try (more when the buffers grew).
                assert!(submissions >= 6, "{submissions} submissions");
                assert_eq!(submissions % 6, 0, "{submissions} submissions");
                let sliced = pass.read_mesh(&gpu.queue, &surface).expect("read back");
                // The active list is filled by atomics, so vertex order differs from run to run:
                // compare the triangles, each as its corners' data in winding order.
                assert_eq!(sliced.positions.len(), whole.positions.len());
                assert_eq!(
                    triangle_set(&sliced),
                    triangle_set(&whole),
                    "{}",
                    method.name()
                );
            }
        }
    }
}

/// One surface extracted from several grids and isovalues in turn, as the window does: the
/// GPU passes keep each grid's per-word density ranges for the next isovalue, and every
/// extraction is still the one a fresh surface gives, also after the grid changes to another of
/// the same size (a sphere, then a torus, then the sphere again) or of another size.
#[test]
fn one_surface_follows_grid_and_isovalue_changes() {
    let gpu = common::gpu();
    let sphere_grid = grid_from(&gpu, 40, sphere);
    let torus_grid = grid_from(&gpu, 40, torus);
    let lumpy_dims = UVec3::new(37, 22, 29);
    let (density, hp) = lumpy_fields(lumpy_dims);
    let lumpy = unit_box_grid(&gpu, lumpy_dims, &density, &hp);
    let steps = [
        (&sphere_grid, 0.5),
        (&sphere_grid, 0.2),
        (&torus_grid, 0.35),
        (&torus_grid, 0.6),
        (&sphere_grid, 0.93),
        (&lumpy, 0.3),
        (&torus_grid, 0.35),
    ];
    let pass = surface_pass(&gpu);
    for method in [MT, DC] {
        let surface = ExtractedSurface::new();
        for (step, &(grid, iso_value)) in steps.iter().enumerate() {
            let settings = SurfaceSettings {
                method,
                iso_value,
                lit: true,
            };
            let counts = pass
                .extract_blocking(&gpu.queue, &surface, grid, &settings)
                .expect("extraction");
            assert!(counts.fits(), "{counts:?}");
            let mesh = pass.read_mesh(&gpu.queue, &surface).expect("read back");
            let fresh = extract(&gpu, &pass, grid, method, iso_value);
            assert!(
                fresh.triangle_count() > 100,
                "{} step {step}",
                method.name()
            );
            assert_eq!(
                triangle_set(&mesh),
                triangle_set(&fresh),
                "{} step {step}",
                method.name()
            );
        }
    }
}

/// The window's path: an isovalue changed on every frame (a dragged slider) never waits for the
/// GPU, the last mesh stays drawable meanwhile, and once the requests stop the surface shown is
/// the one of the last isovalue, equal to a blocking extraction of it.
#[test]
fn interactive_isovalue_sweep_ends_on_the_last_value() {
    let gpu = common::gpu();
    let grid = grid_from(&gpu, 48, torus);
    for (method, engine) in [MT, DC].into_iter().flat_map(|m| ENGINES.map(|e| (m, e))) {
        let pass = engine_pass(&gpu, engine);
        let surface = ExtractedSurface::new();
        let frame = |iso_value: f32| {
            let settings = SurfaceSettings {
                method,
                iso_value,
                lit: true,
            };
            pass.prepare(&gpu.queue, &surface, Some(&grid), &settings);
            // The frame's submission (its style write; the worker extracts).
            gpu.queue.submit([]);
        };
        let sweep: Vec<f32> = (0..=16).map(|i| 0.3 + 0.02 * i as f32).collect();
        let last = *sweep.last().unwrap();
        let reference = extract(&gpu, &engine_pass(&gpu, engine), &grid, method, last);
        let mut busy_frames = 0;
        for &iso in &sweep {
            frame(iso);
            busy_frames += usize::from(surface.is_extracting());
        }
        assert!(busy_frames > 0, "the sweep never ran in the background");
        let mut frames = 0;
        while surface.needs_another_frame() {
            frame(last);
            frames += 1;
            assert!(
                frames < 12_000,
                "{}: the sweep never settled",
                method.name()
            );
            std::thread::sleep(std::time::Duration::from_millis(5));
        }
        assert_eq!(surface.shown_iso_value(), Some(last), "{}", method.name());
        let mesh = pass.read_mesh(&gpu.queue, &surface).expect("read");
        assert_eq!(
            mesh.triangle_count(),
            reference.triangle_count(),
            "{}",
            method.name()
        );
        assert!(mesh.triangle_count() > 0);
    }
}

/// A field with structure on every scale, empty blocks (density 0, hp 0.5 as where no point
/// fell) and hp that varies independently of the density.
fn lumpy_fields(dims: UVec3) -> (Vec<f32>, Vec<f32>) {
    let (mut density, mut hp) = (Vec::new(), Vec::new());
    for k in 0..dims.z {
        for j in 0..dims.y {
            for i in 0..dims.x {
                let (x, y, z) = (i as f32, j as f32, k as f32);
                let d = ((x * 0.37).sin() * (y * 0.23).cos() + (z * 0.51).sin()).max(0.0) * 0.6;
                let empty = (i / 3 + j / 2 + k) % 5 == 0;
                density.push(if empty { 0.0 } else { d.min(1.0) });
                hp.push(if empty || d == 0.0 {
                    0.5
                } else {
                    (0.5 + 0.5 * (x * 0.9 + z * 0.3).sin()).clamp(0.0, 1.0)
                });
            }
        }
    }
    (density, hp)
}

mod cpu_engine;
mod golden;
mod lod;
