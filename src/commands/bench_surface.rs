//! The isosurface part of `loudscape bench`: median extraction times of marching tetrahedra and
//! dual contouring on a song-like field at 128^3 (song mode) and 224^3 (timeline mode), with
//! triangle counts and surface areas. Optionally writes each field as a .npy file so
//! bench/bench_surface.py can run scikit-image on exactly the same data.
//!
//! .npy layout: float32 little endian, C order, shape (nz, ny, nx), so `field[k, j, i]` is voxel
//! (i, j, k) of the grid (x fastest, as in the GPU buffers); voxel centres at
//! -1 + (index + 0.5) * 2 / n on each axis.

use std::path::Path;
use std::time::Instant;

use glam::{UVec3, Vec3};
use loudscape::data::synthetic::song_like_field;
use loudscape::render::gpu::context::GpuContext;
use loudscape::render::gpu::frame::FrameBinding;
use loudscape::render::grid::VoxelGrid;
use loudscape::render::surface::buffers::MeshVertex;
use loudscape::render::surface::cpu::grid::CpuGrid;
use loudscape::render::surface::cpu::{CpuExtraction, Phases, SurfaceEngine, default_threads};
use loudscape::render::surface::pass::SurfacePass;
use loudscape::render::surface::state::ExtractedSurface;
use loudscape::render::surface::{SurfaceMethod, SurfaceSettings};

/// One measured extraction.
#[derive(Clone, Debug)]
pub struct SurfaceTiming {
    pub field: String,
    pub method: SurfaceMethod,
    pub engine: SurfaceEngine,
    pub median_ms: f64,
    pub triangles: u32,
}

/// Runs the isosurface benchmarks `runs` times each, on both engines (the GPU passes and the
/// CPU extraction), and prints one line per result.
pub fn run(
    runs: usize,
    iso_value: f32,
    fields_dir: Option<&Path>,
) -> anyhow::Result<Vec<SurfaceTiming>> {
    let runs = runs.max(1);
    let gpu = GpuContext::new_headless()?;
    println!(
        "isosurfaces on {} (iso {iso_value}, {runs} runs each)",
        gpu.describe()
    );
    let frame = FrameBinding::new(&gpu.device);
    let preferred = SurfaceEngine::preferred(&gpu.device);
    let gpu_pass = SurfacePass::new(&gpu.device, &frame).with_engine(SurfaceEngine::Gpu);
    let cpu_pass = SurfacePass::new(&gpu.device, &frame).with_engine(SurfaceEngine::Cpu);
    // A third pass object times each dispatch apart (which adds pass boundaries), so the
    // wall-clock figures come from the untimed one.
    let mut timed_pass = SurfacePass::new(&gpu.device, &frame).with_engine(SurfaceEngine::Gpu);
    let timed = timed_pass.enable_pass_timing(&gpu.queue);
    println!(
        "  the app extracts with: {} ({})",
        preferred.name(),
        match preferred {
            SurfaceEngine::Cpu => "this adapter is a CPU",
            SurfaceEngine::Gpu => "this adapter is a GPU",
        }
    );
    println!(
        "  times: engine gpu: submit to read-back of the counts{}; engine cpu ({} threads): \
         extraction and upload into the GPU buffers, waited for (the grid is read back once per \
         grid, timed apart), per phase: wall clock; engine cpu threads=1: the same extraction \
         on one thread into memory (no upload), as VTK's flying edges runs",
        if timed {
            ", per pass: GPU timestamps, in separate runs with each pass on its own"
        } else {
            " (no timestamp queries on this adapter: no per-pass times)"
        },
        default_threads()
    );
    let mut results = Vec::new();
    for (name, n) in [("song_128", 128u32), ("timeline_224", 224u32)] {
        let dims = UVec3::splat(n);
        let (density, hp) = song_like_field(dims);
        if let Some(dir) = fields_dir {
            let path = dir.join(format!("{name}.npy"));
            super::write_atomically(&path, |out| Ok(super::npy::write(out, &[&density], dims)?))?;
            super::wrote(&path, &format!("{n}x{n}x{n} density field"));
        }
        let grid = VoxelGrid::from_fields(
            &gpu.device,
            dims,
            Vec3::splat(-1.0),
            Vec3::ONE,
            &density,
            &hp,
        );
        for method in SurfaceMethod::ALL {
            let settings = SurfaceSettings {
                method,
                iso_value,
                lit: true,
            };
            for (engine, pass) in [
                (SurfaceEngine::Gpu, &gpu_pass),
                (SurfaceEngine::Cpu, &cpu_pass),
            ] {
                let surface = ExtractedSurface::new();
                // Warm-up: compiles pipelines, grows the buffers to fit, reads the grid back
                // for the CPU.
                let start = Instant::now();
                let counts = match pass.extract_blocking(&gpu.queue, &surface, &grid, &settings) {
                    Ok(counts) => counts,
                    Err(e) => {
                        println!("surface {name} {} error: {e}", method.short_name());
                        continue;
                    }
                };
                let first_ms = start.elapsed().as_secs_f64() * 1e3;
                let first_grid_ms = phase(&pass.cpu_phases(), "grid");
                let mut times = Vec::with_capacity(runs);
                let mut phases: Vec<(&str, Vec<f64>)> = Vec::new();
                for _ in 0..runs {
                    let start = Instant::now();
                    pass.extract_blocking(&gpu.queue, &surface, &grid, &settings)?;
                    times.push(start.elapsed().as_secs_f64() * 1e3);
                    if engine == SurfaceEngine::Cpu {
                        let laps = pass.cpu_phases().times;
                        phases.resize_with(laps.len(), || ("", Vec::new()));
                        for ((name, times), (lap, ms)) in phases.iter_mut().zip(laps) {
                            *name = lap;
                            times.push(ms);
                        }
                    }
                }
                // Per pass on the GPU: the timed pass object, warmed up like the untimed one.
                if engine == SurfaceEngine::Gpu && timed {
                    let timed_surface = ExtractedSurface::new();
                    timed_pass.extract_blocking(&gpu.queue, &timed_surface, &grid, &settings)?;
                    for _ in 0..runs {
                        timed_pass.extract_blocking(
                            &gpu.queue,
                            &timed_surface,
                            &grid,
                            &settings,
                        )?;
                        let passes = timed_pass.pass_times_ms(method)?.unwrap_or_default();
                        phases.resize_with(passes.len(), || ("", Vec::new()));
                        for ((name, times), (pass_name, ms)) in phases.iter_mut().zip(passes) {
                            *name = pass_name;
                            times.push(ms);
                        }
                    }
                }
                let median_ms = median(&mut times);
                let area = pass.read_mesh(&gpu.queue, &surface)?.area();
                println!(
                    "surface {name} {} engine={} median_ms={median_ms:.2} triangles={} \
                     area={area:.5}",
                    method.short_name(),
                    engine.name(),
                    counts.triangles()
                );
                let laps: Vec<String> = phases
                    .iter_mut()
                    .map(|(name, ms)| format!("{name} {:.2}", median(ms)))
                    .collect();
                match engine {
                    SurfaceEngine::Gpu if !laps.is_empty() => {
                        println!("  per pass (ms, median): {}", laps.join(", "));
                    }
                    SurfaceEngine::Cpu => println!(
                        "  per phase (ms, median): {}; first extraction {first_ms:.1} ms, of \
                         which reading the grid back {first_grid_ms:.1} ms",
                        laps.join(", ")
                    ),
                    SurfaceEngine::Gpu => {}
                }
                if engine == SurfaceEngine::Cpu {
                    let cpu_grid = CpuGrid::new(dims, Vec3::splat(-1.0), Vec3::ONE, &density, &hp);
                    let (median_ms, laps) = one_thread(&cpu_grid, method, iso_value, runs);
                    println!(
                        "surface {name} {} engine=cpu threads=1 median_ms={median_ms:.2}",
                        method.short_name()
                    );
                    println!("  per phase (ms, median): {laps}");
                }
                if engine == preferred {
                    results.push(SurfaceTiming {
                        field: name.to_string(),
                        method,
                        engine,
                        median_ms,
                        triangles: counts.triangles(),
                    });
                }
            }
        }
    }
    Ok(results)
}

/// The median time (ms) of `runs` extractions of `grid` on one thread into memory (the
/// output allocated and touched once beforehand, as the mapped buffers are), and the median of
/// each phase.
fn one_thread(grid: &CpuGrid, method: SurfaceMethod, iso: f32, runs: usize) -> (f64, String) {
    let extraction = CpuExtraction {
        grid,
        method,
        iso,
        threads: 1,
    };
    let plan = extraction.plan(&mut Phases::default());
    let mut vertices = vec![bytemuck::Zeroable::zeroed(); plan.vertices()];
    let mut indices = vec![0u32; plan.indices()];
    let mut times = Vec::with_capacity(runs);
    let mut phases: Vec<(&str, Vec<f64>)> = Vec::new();
    for _ in 0..runs {
        let start = Instant::now();
        let mut laps = Phases::default();
        let plan = extraction.plan(&mut laps);
        let written = Instant::now();
        extraction.write(
            &plan,
            wgpu::WriteOnly::from(bytemuck::cast_slice_mut::<MeshVertex, u8>(&mut vertices)),
            wgpu::WriteOnly::from(bytemuck::cast_slice_mut::<u32, u8>(&mut indices)),
        );
        laps.lap("vertices and triangles", written);
        times.push(start.elapsed().as_secs_f64() * 1e3);
        phases.resize_with(laps.times.len(), || ("", Vec::new()));
        for ((name, times), (lap, ms)) in phases.iter_mut().zip(laps.times) {
            *name = lap;
            times.push(ms);
        }
    }
    let laps: Vec<String> = phases
        .iter_mut()
        .map(|(name, ms)| format!("{name} {:.2}", median(ms)))
        .collect();
    (median(&mut times), laps.join(", "))
}

/// The time of phase `name` in `phases` (0 when it is not there).
fn phase(phases: &Phases, name: &str) -> f64 {
    phases
        .times
        .iter()
        .find(|(n, _)| *n == name)
        .map_or(0.0, |(_, ms)| *ms)
}

/// The paper's figures (Metal, paper section 5) beside ours.
pub fn print_paper_comparison(results: &[SurfaceTiming]) {
    let paper = |field: &str, method: SurfaceMethod| match (field, method) {
        ("song_128", SurfaceMethod::MarchingTetrahedra) => Some(13.4),
        ("song_128", SurfaceMethod::DualContouring) => Some(16.2),
        ("timeline_224", SurfaceMethod::MarchingTetrahedra) => Some(14.7),
        ("timeline_224", SurfaceMethod::DualContouring) => Some(17.2),
        _ => None,
    };
    for r in results {
        if let Some(ms) = paper(&r.field, r.method) {
            println!(
                "  {} {}: {:.2} ms here ({} engine), {ms} ms in the paper (Metal): {:.2}x, {} \
                 triangles",
                r.field,
                r.method.name(),
                r.median_ms,
                r.engine.name(),
                r.median_ms / ms,
                r.triangles
            );
        }
    }
}

/// The median of `values` (sorts them).
fn median(values: &mut [f64]) -> f64 {
    values.sort_by(f64::total_cmp);
    values[values.len() / 2]
}
