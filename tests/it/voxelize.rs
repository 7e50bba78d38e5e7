//! GPU voxelization against a CPU reference (f64), normalization, degenerate clouds and limits.

use crate::common;

use loudscape::data::cloud::Point;
use loudscape::render::gpu::context::GpuContext;
use loudscape::render::gpu::frame::FrameBinding;
use loudscape::render::grid::reference::ReferenceGrid;
use loudscape::render::grid::voxelize::{
    FIXED_POINT_SCALE, HP_FIXED_POINT_SCALE, VoxelStats, VoxelizeError, VoxelizePass,
    VoxelizeRequest,
};
use loudscape::render::grid::voxelize_cpu::{
    HISTOGRAM_BINS_PER_OCTAVE, grid_box, reference_sum, voxel_of, voxels_per_unit,
};

struct Built {
    density: Vec<f32>,
    hp_mean: Vec<f32>,
    stats: VoxelStats,
}

/// The grid of `points` built by the compute passes (`on_cpu` false) or by the CPU engine a
/// device that is the CPU uses (true), whatever this device is.
fn build(gpu: &GpuContext, points: &[Point], resolution: u32, sigma: f32, on_cpu: bool) -> Built {
    build_request(
        gpu,
        &VoxelizeRequest::new(points, resolution, sigma),
        on_cpu,
    )
}

/// The grid of `points` by both engines, which must agree ([`assert_engines_agree`]): the
/// compute passes' grid.
fn build_both(gpu: &GpuContext, points: &[Point], resolution: u32, sigma: f32) -> Built {
    let passes = build(gpu, points, resolution, sigma, false);
    let cpu = build(gpu, points, resolution, sigma, true);
    assert_engines_agree(&passes, &cpu, sigma > 0.0);
    passes
}

/// The CPU engine builds the compute passes' grid: unsmoothed the same f32 operations on the
/// same exact sums (equal to a few units in the last place of the division); smoothed, the
/// Gaussian's f32 sums may be fused or ordered otherwise by the shader compiler (1e-5).
fn assert_engines_agree(passes: &Built, cpu: &Built, smoothed: bool) {
    let tolerance = if smoothed { 1e-5 } else { 1e-6 };
    assert_eq!(passes.density.len(), cpu.density.len());
    for (i, (a, b)) in passes.density.iter().zip(&cpu.density).enumerate() {
        assert!(
            (a - b).abs() <= tolerance,
            "voxel {i}: density {a} by the compute passes, {b} by the CPU engine"
        );
    }
    for (i, (a, b)) in passes.hp_mean.iter().zip(&cpu.hp_mean).enumerate() {
        assert!(
            (a - b).abs() <= 1e-6,
            "voxel {i}: hp {a} by the compute passes, {b} by the CPU engine"
        );
    }
    assert_eq!(
        passes.stats.nonempty, cpu.stats.nonempty,
        "non-empty voxels"
    );
    let (a, b) = (passes.stats.reference_sum, cpu.stats.reference_sum);
    assert!(
        (a - b).abs() <= a.abs() * 1e-5,
        "reference sums {a} and {b}"
    );
    // A smoothed value within float rounding of the reference may clamp in one engine only.
    let clamped = passes.stats.clamped.abs_diff(cpu.stats.clamped);
    assert!(
        clamped <= if smoothed { 2 } else { 0 },
        "clamped voxels {} and {}",
        passes.stats.clamped,
        cpu.stats.clamped
    );
}

fn build_request(gpu: &GpuContext, request: &VoxelizeRequest, on_cpu: bool) -> Built {
    let frame = FrameBinding::new(&gpu.device);
    let pass = VoxelizePass::new(&gpu.device, &frame).with_cpu_engine(on_cpu);
    let (grid, stats) = pass
        .voxelize(&gpu.device, &gpu.queue, request)
        .expect("voxelize");
    Built {
        density: grid
            .read_field(&gpu.device, &gpu.queue, &grid.density)
            .expect("read density"),
        hp_mean: grid
            .read_field(&gpu.device, &gpu.queue, &grid.hp_mean)
            .expect("read hp"),
        stats,
    }
}

/// A small deterministic generator (xorshift) so the clouds are the same on every run.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f32 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 40) as f32 / (1u64 << 24) as f32
    }
}

fn random_cloud(seed: u64, count: usize) -> Vec<Point> {
    let mut rng = Rng(seed.wrapping_mul(0x2545_f491_4f6c_dd1d) | 1);
    let mut points: Vec<Point> = (0..count)
        .map(|_| {
            // Clustered so that voxels hold many points (and sums carry).
            let c = (rng.next() * 4.0).floor() * 0.4 - 0.6;
            Point {
                position: [
                    c + (rng.next() - 0.5) * 0.5,
                    (rng.next() * 2.0 - 1.0) * 0.7,
                    rng.next() * 2.0 - 1.0,
                ],
                scalar: rng.next(),
                hp: rng.next(),
            }
        })
        .collect();
    // The cloud's own extremes: points exactly on its bounding box faces and corners.
    for corner in [
        [-1.0, -1.0, -1.0],
        [1.0, 1.0, 1.0],
        [1.0, -1.0, 0.0],
        [-1.0, 0.0, 1.0],
    ] {
        points.push(Point {
            position: corner,
            scalar: 1.0,
            hp: 0.0,
        });
    }
    points
}

/// Points exactly on voxel faces of the grid `points` will get (the box depends only on the
/// extremes, which these points do not move).
fn on_voxel_faces(points: &[Point], resolution: u32) -> Vec<Point> {
    let (min, max) = grid_box(points);
    let size = (max - min) / resolution as f32;
    (0..resolution)
        .step_by(7)
        .map(|k| {
            let p = min + size * k as f32;
            Point {
                position: [p.x.max(-1.0), p.y.max(-1.0), p.z.max(-1.0)],
                scalar: 0.5,
                hp: 1.0,
            }
        })
        .collect()
}

/// Both engines (the compute passes and the CPU engine of CPU devices) agree with the f64
/// reference: same voxels, sums within the fixed-point rounding, and the reference sum is the
/// CPU's histogram percentile.
fn assert_matches_reference(points: &[Point], resolution: u32, sigma: f32) {
    let gpu = common::gpu();
    for on_cpu in [false, true] {
        eprintln!("engine: {}", if on_cpu { "cpu" } else { "gpu" });
        assert_engine_matches_reference(&gpu, points, resolution, sigma, on_cpu);
    }
}

fn assert_engine_matches_reference(
    gpu: &GpuContext,
    points: &[Point],
    resolution: u32,
    sigma: f32,
    on_cpu: bool,
) {
    let built = build(gpu, points, resolution, sigma, on_cpu);
    let mut reference = ReferenceGrid::build(points, resolution);
    reference.smooth(sigma);
    let cpu_reference = reference_sum(reference.sums.iter().map(|&s| s as f32));
    let gpu_reference = built.stats.reference_sum;
    let bins_apart = (gpu_reference / cpu_reference).log2().abs() * HISTOGRAM_BINS_PER_OCTAVE;
    assert!(
        bins_apart < 1.01,
        "reference sums differ: GPU {gpu_reference}, CPU {cpu_reference}"
    );
    let nonempty = reference.sums.iter().filter(|&&s| s > 0.0).count() as u32;
    assert_eq!(built.stats.nonempty, nonempty, "non-empty voxels");
    let quantum = 0.5 / f64::from(FIXED_POINT_SCALE);
    let mut worst = 0.0f64;
    for (i, (&gpu_density, &sum)) in built.density.iter().zip(&reference.sums).enumerate() {
        let expected = (sum / f64::from(gpu_reference)).min(1.0);
        // Fixed-point rounding (half a unit per point) plus f32 arithmetic.
        let count = f64::from(reference.counts[i].max(1));
        let tolerance = (count * quantum) / f64::from(gpu_reference) + 2e-6 + expected * 2e-6;
        let error = (f64::from(gpu_density) - expected).abs();
        worst = worst.max(error / tolerance);
        assert!(
            error <= tolerance,
            "voxel {i}: GPU density {gpu_density}, CPU {expected} (sum {sum})"
        );
        let hp_error = (f64::from(built.hp_mean[i]) - reference.hp_mean[i]).abs();
        assert!(
            hp_error <= 0.5 / f64::from(HP_FIXED_POINT_SCALE) + 2e-6,
            "voxel {i}: GPU hp {}, CPU {}",
            built.hp_mean[i],
            reference.hp_mean[i]
        );
    }
    eprintln!("worst error / tolerance: {worst:.3}");
}

#[test]
fn gpu_voxelization_matches_cpu_reference_on_random_clouds() {
    for (seed, count, resolution) in [(1, 5_000, 64), (2, 60_000, 64), (3, 200_000, 96)] {
        let mut points = random_cloud(seed, count);
        points.extend(on_voxel_faces(&points, resolution));
        assert_matches_reference(&points, resolution, 0.0);
    }
}

#[test]
fn gpu_smoothing_matches_cpu_reference() {
    let points = random_cloud(4, 30_000);
    assert_matches_reference(&points, 64, 1.2);
}

#[test]
fn normalization_uses_a_high_percentile_so_one_hot_voxel_does_not_flatten_the_field() {
    let gpu = common::gpu();
    let mut points = random_cloud(5, 50_000);
    // One voxel with a thousand times the loudness of any other.
    points.extend((0..20_000).map(|_| Point {
        position: [0.1, 0.1, 0.1],
        scalar: 1.0,
        hp: 0.5,
    }));
    let built = build_both(&gpu, &points, 64, 0.0);
    let reference = ReferenceGrid::build(&points, 64);
    let mut sums: Vec<f64> = reference
        .sums
        .iter()
        .copied()
        .filter(|&s| s > 0.0)
        .collect();
    sums.sort_by(f64::total_cmp);
    let rank = ((0.99 * sums.len() as f64).ceil() as usize).max(1);
    let exact = sums[rank - 1] as f32;
    let r = built.stats.reference_sum;
    // The reference is the exact 99th percentile rounded up to its histogram bin's edge.
    assert!(r >= exact && r <= exact * 2f32.powf(1.0 / HISTOGRAM_BINS_PER_OCTAVE) * 1.0001);
    // The hot voxel saturates; the rest keeps its spread; at most 1 % clamp.
    assert_eq!(built.density.iter().cloned().fold(0.0, f32::max), 1.0);
    let mut nonempty: Vec<f32> = built.density.iter().copied().filter(|&d| d > 0.0).collect();
    nonempty.sort_by(f32::total_cmp);
    let median = nonempty[nonempty.len() / 2];
    assert!(
        median > 0.2,
        "median non-empty density {median} is flattened"
    );
    assert!(built.stats.clamped as usize <= nonempty.len() / 100 + 1);
}

#[test]
fn degenerate_clouds_give_sensible_grids() {
    let gpu = common::gpu();
    // Empty: all zero, hp 0.5.
    let empty = build_both(&gpu, &[], 64, 0.7);
    assert!(empty.density.iter().all(|&d| d == 0.0));
    assert!(empty.hp_mean.iter().all(|&h| h == 0.5));
    assert_eq!(empty.stats.nonempty, 0);

    // One point: one voxel at density 1, in the middle of a small box.
    let one = [Point {
        position: [0.25, -0.5, 1.0],
        scalar: 0.3,
        hp: 0.9,
    }];
    let (min, max) = grid_box(&one);
    assert!((max - min).min_element() > 0.0);
    let built = build_both(&gpu, &one, 64, 0.0);
    let lit: Vec<usize> = (0..built.density.len())
        .filter(|&i| built.density[i] > 0.0)
        .collect();
    assert_eq!(lit.len(), 1);
    assert_eq!(built.density[lit[0]], 1.0);
    assert!((built.hp_mean[lit[0]] - 0.9).abs() < 1e-5);

    // All points identical: the same, with the mean hp. Enough points that both fixed-point
    // sums carry into their high words many times.
    let same: Vec<Point> = (0..300_000)
        .map(|i| Point {
            position: [-1.0, 1.0, 0.0],
            scalar: 1.0,
            hp: if i % 2 == 0 { 0.0 } else { 1.0 },
        })
        .collect();
    let built = build_both(&gpu, &same, 64, 0.0);
    let lit: Vec<usize> = (0..built.density.len())
        .filter(|&i| built.density[i] > 0.0)
        .collect();
    assert_eq!(lit.len(), 1);
    assert!((built.hp_mean[lit[0]] - 0.5).abs() < 1e-5);

    // A flat cloud (all at one level): the box still has depth and the points sit mid-box.
    let flat: Vec<Point> = (0..4096)
        .map(|i| Point {
            position: [
                (i % 64) as f32 / 31.5 - 1.0,
                0.3,
                (i / 64) as f32 / 31.5 - 1.0,
            ],
            scalar: ((i % 7) as f32) / 6.0,
            hp: 0.2,
        })
        .collect();
    let (min, max) = grid_box(&flat);
    assert!(max.y - min.y > 0.05 && (min.y + max.y) * 0.5 - 0.3 < 1e-6);
    let built = build_both(&gpu, &flat, 64, 0.0);
    assert!(built.density.iter().all(|d| (0.0..=1.0).contains(d)));
    assert!(built.density.iter().any(|&d| d > 0.5));

    // Values at and past the range edges: clamped into [0, 1], nothing lost.
    let edges = [
        Point {
            position: [-1.0, -1.0, -1.0],
            scalar: 0.0,
            hp: 0.0,
        },
        Point {
            position: [1.0, 1.0, 1.0],
            scalar: 1.0,
            hp: 1.0,
        },
        Point {
            position: [1.0, -1.0, 1.0],
            scalar: 1.5,
            hp: -0.2,
        },
    ];
    let built = build_both(&gpu, &edges, 64, 0.0);
    let reference = ReferenceGrid::build(&edges, 64);
    assert_eq!(reference.counts.iter().sum::<u32>(), 3);
    assert!(built.density.iter().all(|d| (0.0..=1.0).contains(d)));
    assert!(built.hp_mean.iter().all(|h| (0.0..=1.0).contains(h)));
    assert_eq!(
        built.stats.nonempty, 2,
        "the scalar-0 point adds no loudness"
    );
}

/// More than 2^24 points, most of them in one voxel (the old 24-bit count wrapped there): the
/// count, the hp mean and the loudness sum stay exact, and the CPU reference agrees.
#[test]
fn clouds_over_2_pow_24_points_voxelize_exactly() {
    // 17 * 2^20 = 17,825,792 points in one voxel, hp alternating 0.25 and 0.5: the mean is 0.375
    // and every sum is exact in the fixed point and in f32.
    let crowded = 17usize << 20;
    assert!(crowded > 1 << 24);
    let mut points: Vec<Point> = (0..crowded)
        .map(|i| Point {
            position: [-0.5, -0.5, -0.5],
            scalar: 0.5,
            hp: if i % 2 == 0 { 0.25 } else { 0.5 },
        })
        .collect();
    points.extend(std::iter::repeat_n(
        Point {
            position: [0.5, 0.5, 0.5],
            scalar: 1.0,
            hp: 1.0,
        },
        1000,
    ));
    for corner in [[-1.0; 3], [1.0; 3]] {
        points.push(Point {
            position: corner,
            scalar: 1.0,
            hp: 0.0,
        });
    }
    let resolution = 64;
    let gpu = common::gpu();
    let built = build_both(&gpu, &points, resolution, 0.0);
    let (min, max) = grid_box(&points);
    let dims = glam::UVec3::splat(resolution);
    let per_unit = voxels_per_unit(dims, min, max);
    let index = |p: [f32; 3]| {
        let v = voxel_of(glam::Vec3::from_array(p), min, per_unit, dims);
        (v.x + dims.x * (v.y + dims.y * v.z)) as usize
    };
    let (a, b) = (index([-0.5; 3]), index([0.5; 3]));
    assert_eq!(built.stats.nonempty, 4);
    assert_eq!(built.hp_mean[a], 0.375, "hp mean of the crowded voxel");
    assert_eq!(built.hp_mean[b], 1.0);
    assert_eq!(built.hp_mean[index([-1.0; 3])], 0.0);
    // The crowded voxel holds the largest sum (8,912,896), beyond the histogram's top bin
    // (2^22.6): the reference is that bin's upper edge, as on the CPU, and the voxel clamps to 1.
    let reference = ReferenceGrid::build(&points, resolution);
    assert_eq!(reference.counts[a] as usize, crowded);
    assert_eq!(reference.sums[a], (crowded / 2) as f64);
    let cpu_reference = reference_sum(reference.sums.iter().map(|&s| s as f32));
    assert_eq!(built.stats.reference_sum, cpu_reference);
    assert_eq!(built.density[a], 1.0);
    assert_eq!(built.density[b], 1000.0 / cpu_reference);
    assert_matches_reference(&points, resolution, 0.0);
}

#[test]
fn grids_beyond_the_limits_are_refused_with_a_clear_message() {
    let gpu = common::gpu();
    for bad in [0, 63, 385, 4096] {
        let err = VoxelizePass::check_resolution(&gpu.device, bad).expect_err("out of range");
        assert!(err.to_string().contains("64 to 384"), "{err}");
    }
    // A device that allows 64 MiB per buffer cannot hold 256^3 64-bit sums (128 MiB).
    let limits = wgpu::Limits {
        max_storage_buffer_binding_size: 64 << 20,
        max_buffer_size: 64 << 20,
        ..gpu.adapter.limits()
    };
    let (device, _queue) =
        pollster::block_on(gpu.adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("test::small_device"),
            required_limits: limits,
            ..Default::default()
        }))
        .expect("device with small limits");
    match VoxelizePass::check_resolution(&device, 256) {
        Err(VoxelizeError::TooLarge { largest, .. }) => assert_eq!(largest, 203),
        other => panic!("expected TooLarge, got {other:?}"),
    }
    assert!(VoxelizePass::check_resolution(&device, 200).is_ok());
    let frame = FrameBinding::new(&device);
    let pass = VoxelizePass::new(&device, &frame);
    let err = pass
        .prepare(&device, &VoxelizeRequest::new(&[], 300, 0.0))
        .err()
        .expect("too large");
    assert!(
        err.to_string()
            .contains("choose a resolution of 203 or less"),
        "{err}"
    );
}

/// One check for every source: the smoothing and the point count are refused before anything
/// is uploaded or bound, from the host as from the device (where the counts are the chunks').
#[test]
fn requests_are_checked_once_whatever_their_source() {
    let gpu = common::gpu();
    let frame = FrameBinding::new(&gpu.device);
    let pass = VoxelizePass::new(&gpu.device, &frame);
    let err = pass
        .prepare(&gpu.device, &VoxelizeRequest::new(&[], 64, 10.5))
        .err()
        .expect("sigma out of range");
    assert!(matches!(err, VoxelizeError::Smoothing(_)), "{err}");
    let buffer = gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("test::one_point"),
        size: 20,
        usage: wgpu::BufferUsages::STORAGE,
        mapped_at_creation: false,
    });
    let bounds = (glam::Vec3::ZERO, glam::Vec3::ONE);
    let claimed = VoxelizeRequest::on_device([(&buffer, u32::MAX), (&buffer, 1)], bounds, 64, 0.0);
    match pass.prepare(&gpu.device, &claimed) {
        Err(VoxelizeError::TooManyPoints(n)) => assert_eq!(n, u32::MAX as usize + 1),
        Err(other) => panic!("expected TooManyPoints, got {other}"),
        Ok(_) => panic!("expected TooManyPoints, got a job"),
    }
}

/// The grid box: the one given, else the points' own (host points: their padded bounding box;
/// device points: their padded bounds; no points: the data cube).
#[test]
fn a_request_builds_in_the_given_box_or_the_points_own() {
    use glam::Vec3;
    let points = [[0.0, 0.1, 0.2], [0.5, -0.3, 0.9]].map(|position| Point {
        position,
        scalar: 0.5,
        hp: 0.5,
    });
    let own = grid_box(&points);
    assert_eq!(VoxelizeRequest::new(&points, 64, 0.0).resolved_box(), own);
    let given = (Vec3::splat(-2.0), Vec3::splat(2.0));
    let request = VoxelizeRequest::new(&points, 64, 0.0).in_box(Some(given));
    assert_eq!(request.resolved_box(), given);
    let bounds = (Vec3::new(0.0, -0.3, 0.2), Vec3::new(0.5, 0.1, 0.9));
    let gpu = common::gpu();
    let buffer = gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("test::two_points"),
        size: 40,
        usage: wgpu::BufferUsages::STORAGE,
        mapped_at_creation: false,
    });
    let on_device = VoxelizeRequest::on_device([(&buffer, 2)], bounds, 64, 0.0);
    assert_eq!(on_device.resolved_box(), own);
    let none = VoxelizeRequest::on_device([(&buffer, 0)], bounds, 64, 0.0);
    assert_eq!(none.resolved_box(), (Vec3::splat(-1.0), Vec3::splat(1.0)));
}

/// The CPU engine of CPU devices builds the compute passes' grid on the song's own shapes: the
/// demo song on the log frequency axis (remapped z, the points the axis leaves out skipped), a
/// resolution that is no multiple of four (padded fields), with and without smoothing, and from
/// the points on the device with their host copy, as the window asks.
#[test]
fn the_cpu_engine_builds_the_compute_passes_grid() {
    use loudscape::data::freq_axis::{FreqAxis, FreqMapping};
    use loudscape::render::grid::voxelize_cpu::grid_box_mapped;
    let gpu = common::gpu();
    let cloud = common::demo_song();
    let mapping = FreqMapping::new(&cloud.meta, FreqAxis::Log).expect("a song");
    for (resolution, sigma) in [(65, 0.0), (65, 1.5), (128, 1.0)] {
        let request = VoxelizeRequest::new(&cloud.points, resolution, sigma)
            .mapped(Some(&mapping))
            .in_box(Some(grid_box_mapped(&cloud.points, Some(&mapping))));
        let passes = build_request(&gpu, &request, false);
        let cpu = build_request(&gpu, &request, true);
        assert_engines_agree(&passes, &cpu, sigma > 0.0);
        assert!(passes.stats.nonempty > 1000, "the song fills voxels");
    }
    // The window's request: the points on the device, their host copy beside them.
    let frame = FrameBinding::new(&gpu.device);
    let points = loudscape::render::points::PointsPass::new(&gpu.device, &frame);
    let on_device =
        loudscape::render::points::PointsGpu::upload(&gpu.device, &points, &cloud.points, 1 << 20);
    let bounds = (cloud.bounds.min, cloud.bounds.max);
    let request = VoxelizeRequest::on_device(on_device.chunk_buffers(), bounds, 96, 1.0);
    assert!(request.host_points().is_none(), "no host copy given");
    let with_host = VoxelizeRequest::on_device(on_device.chunk_buffers(), bounds, 96, 1.0)
        .with_host(&cloud.points);
    assert_eq!(
        with_host.host_points().map(<[Point]>::len),
        Some(cloud.points.len())
    );
    let short = VoxelizeRequest::on_device(on_device.chunk_buffers(), bounds, 96, 1.0)
        .with_host(&cloud.points[1..]);
    assert!(
        short.host_points().is_none(),
        "a host copy of other points is not used"
    );
    assert_engines_agree(
        &build_request(&gpu, &request, false),
        &build_request(&gpu, &with_host, true),
        true,
    );
}

/// An A/B compare's grids built on the CPU (the web page's compare): in one box (the union of
/// the two clouds' grid boxes) and on one scale. B is A quieter by half (every scalar halved)
/// and shifted along x: on one scale its densities are half A's shifted ones (each grid on its
/// own scale would make them equal), and A's grid is A's own in that box.
#[test]
fn compare_grids_share_one_box_and_one_scale() {
    use loudscape::render::grid::voxelize_host::{build, build_on_one_scale};
    let dims = glam::UVec3::splat(24);
    let a: Vec<Point> = random_cloud(38, 4000)
        .into_iter()
        .map(|p| Point {
            position: [p.position[0] * 0.5 - 0.4, p.position[1], p.position[2]],
            ..p
        })
        .collect();
    let b: Vec<Point> = a
        .iter()
        .map(|p| Point {
            position: [p.position[0] + 0.8, p.position[1], p.position[2]],
            scalar: p.scalar * 0.5,
            ..*p
        })
        .collect();
    let (box_a_min, box_a_max) = grid_box(&a);
    let ([grid_a, grid_b], (box_min, box_max)) = build_on_one_scale(&a, &b, dims, 0.0);
    let (box_b_min, box_b_max) = grid_box(&b);
    assert_eq!(box_min, box_a_min.min(box_b_min));
    assert_eq!(box_max, box_a_max.max(box_b_max));
    let alone = build(&a, None, dims, (box_min, box_max), 0.0);
    assert_eq!(
        grid_a.density, alone.density,
        "A is on its own (the larger) scale"
    );
    assert_eq!(grid_a.hp_mean, alone.hp_mean);

    let a_sum: f64 = grid_a.density.iter().map(|&d| f64::from(d)).sum();
    let b_sum: f64 = grid_b.density.iter().map(|&d| f64::from(d)).sum();
    let ratio = b_sum / a_sum;
    println!("B's densities sum to {ratio:.3} of A's");
    assert!(
        (ratio - 0.5).abs() < 0.05,
        "B's densities sum to {ratio} of A's, not half"
    );
    let b_alone = build(&b, None, dims, (box_min, box_max), 0.0);
    let b_own: f64 = b_alone.density.iter().map(|&d| f64::from(d)).sum();
    println!("on its own scale: {:.3} of A's", b_own / a_sum);
    assert!(
        (b_own / a_sum - 1.0).abs() < 0.1,
        "each on its own scale they look equal"
    );
}
