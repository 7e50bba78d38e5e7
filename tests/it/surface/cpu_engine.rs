//! The CPU engine (used where the device is the CPU) held to the GPU passes' surface, triangle
//! for triangle, and its writes through the queue where buffers cannot be mapped.

use super::*;

/// The CPU engine (render/surface/cpu/) extracts the same surface as the GPU passes: the same
/// vertices and the same triangles with the same winding (matched vertex for vertex; positions,
/// normals and hp equal up to float rounding, as fused multiply-adds may differ), on
/// fields with every kind of cell (a sphere, a torus, a slab cut by the border, a lumpy field
/// with empty blocks on odd dims, the song-like benchmark field), at isovalues inside, at and
/// beyond the field's range, and through buffers that must grow. Every property the tests above
/// prove of the GPU's surface thereby holds for the CPU's.
#[test]
fn cpu_engine_extracts_the_gpu_surface_triangle_for_triangle() {
    let gpu = common::gpu();
    // On a CPU adapter (lavapipe) this runs the path the app takes there: the mesh written
    // into mapped mesh buffers.
    if gpu.adapter.get_info().device_type == wgpu::DeviceType::Cpu {
        assert!(
            gpu.device
                .features()
                .contains(wgpu::Features::MAPPABLE_PRIMARY_BUFFERS)
        );
    }
    let frame = FrameBinding::new(&gpu.device);
    let lumpy_dims = UVec3::new(37, 22, 29);
    let (density, hp) = lumpy_fields(lumpy_dims);
    let lumpy = VoxelGrid::from_fields(
        &gpu.device,
        lumpy_dims,
        Vec3::new(-1.0, -0.5, -2.0),
        Vec3::new(1.0, 0.7, 1.5),
        &density,
        &hp,
    );
    let song_dims = UVec3::splat(48);
    let (song_density, song_hp) = song_like_field(song_dims);
    let song = unit_box_grid(&gpu, song_dims, &song_density, &song_hp);
    let cases = [
        (grid_from(&gpu, 40, sphere), vec![0.5, 0.2, 0.93]),
        (grid_from(&gpu, 40, torus), vec![0.35]),
        (grid_from(&gpu, 24, |p| 0.5 - p.y * 3.0), vec![0.5]),
        (lumpy, vec![0.05, 0.3, 0.59, 0.0, 1.0, -0.1]),
        (song, vec![0.3, 0.6]),
    ];
    let (gpu_pass, cpu_pass) = (surface_pass(&gpu), engine_pass(&gpu, SurfaceEngine::Cpu));
    let small_cpu =
        SurfacePass::with_capacity(&gpu.device, &frame, 64, 96).with_engine(SurfaceEngine::Cpu);
    let mut compared = 0;
    let mut worst = Difference::default();
    for (grid, isos) in &cases {
        for &iso in isos {
            for method in [MT, DC] {
                let expected = extract(&gpu, &gpu_pass, grid, method, iso);
                for pass in [&cpu_pass, &small_cpu] {
                    let mesh = extract(&gpu, pass, grid, method, iso);
                    assert_eq!(
                        mesh.positions.len(),
                        expected.positions.len(),
                        "{} at {iso}: vertices",
                        method.name()
                    );
                    let error = same_surface(&mesh, &expected);
                    assert!(
                        error.position <= 1e-4 && error.normal <= 1e-5 && error.hp <= 1e-6,
                        "{} at {iso}: {error:?}",
                        method.name()
                    );
                    worst = worst.max(error);
                }
                compared += expected.triangle_count();
            }
        }
    }
    assert!(compared > 100_000, "only {compared} triangles compared");
    println!("largest difference between the engines: {worst:?}");
}

/// The largest differences between matched vertices of two meshes: position (in voxels of a
/// 2-unit box over 40 samples, so data units / 0.05), normal, hp.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Difference {
    position: f32,
    normal: f32,
    hp: f32,
}

impl Difference {
    fn max(self, other: Self) -> Self {
        Self {
            position: self.position.max(other.position),
            normal: self.normal.max(other.normal),
            hp: self.hp.max(other.hp),
        }
    }
}

/// Asserts that `a` and `b` are the same surface up to rounding: every vertex of `a` matches a
/// vertex of `b` (the nearest in position, normal and hp, preferring one not matched yet;
/// vertices of `b` equal in every value count as one, as they are where several edges meet at a
/// corner the isovalue crosses exactly), and under that matching the triangles, with their
/// winding, are the same set. Returns the largest difference between matched vertices.
fn same_surface(a: &CpuMesh, b: &CpuMesh) -> Difference {
    assert_eq!(a.positions.len(), b.positions.len(), "vertices");
    assert_eq!(a.indices.len(), b.indices.len(), "indices");
    let cell = 1e-3f32;
    let bucket = |p: Vec3| (p / cell).floor().as_ivec3();
    let mut buckets: HashMap<glam::IVec3, Vec<u32>> = HashMap::new();
    for (i, &p) in b.positions.iter().enumerate() {
        buckets.entry(bucket(p)).or_default().push(i as u32);
    }
    let mut used = vec![false; b.positions.len()];
    let mut to_b = vec![0u32; a.positions.len()];
    // One representative of each set of vertices of `b` equal in every value.
    let mut first_of: HashMap<[u32; 7], u32> = HashMap::new();
    let representative: Vec<u32> = (0..b.positions.len())
        .map(|j| {
            let (p, n) = (b.positions[j], b.normals[j]);
            let key = [p.x, p.y, p.z, n.x, n.y, n.z, b.hp[j]].map(f32::to_bits);
            *first_of.entry(key).or_insert(j as u32)
        })
        .collect();
    let mut worst = Difference::default();
    for (i, &p) in a.positions.iter().enumerate() {
        let home = bucket(p);
        let mut best: Option<(f32, u32)> = None;
        for dz in -1..=1 {
            for dy in -1..=1 {
                for dx in -1..=1 {
                    let Some(list) = buckets.get(&(home + glam::IVec3::new(dx, dy, dz))) else {
                        continue;
                    };
                    for &j in list {
                        let d = (b.positions[j as usize] - p).length()
                            + (b.normals[j as usize] - a.normals[i]).length()
                            + (b.hp[j as usize] - a.hp[i]).abs()
                            + if used[j as usize] { 1e-3 } else { 0.0 };
                        if best.is_none_or(|(e, _)| d < e) {
                            best = Some((d, j));
                        }
                    }
                }
            }
        }
        let (_, j) = best.unwrap_or_else(|| panic!("vertex {i} at {p} has no match"));
        used[j as usize] = true;
        to_b[i] = representative[j as usize];
        let j = j as usize;
        worst = worst.max(Difference {
            position: (b.positions[j] - p).abs().max_element() / 0.05,
            normal: (b.normals[j] - a.normals[i]).abs().max_element(),
            hp: (b.hp[j] - a.hp[i]).abs(),
        });
    }
    let canonical = |t: [u32; 3]| {
        let first = (0..3).min_by_key(|&k| t[k]).unwrap();
        let mut t = t;
        t.rotate_left(first);
        t
    };
    let mut ta: Vec<[u32; 3]> = a
        .indices
        .chunks_exact(3)
        .map(|t| {
            canonical([
                to_b[t[0] as usize],
                to_b[t[1] as usize],
                to_b[t[2] as usize],
            ])
        })
        .collect();
    let mut tb: Vec<[u32; 3]> = b
        .indices
        .chunks_exact(3)
        .map(|t| {
            canonical(
                t.iter()
                    .map(|&j| representative[j as usize])
                    .collect::<Vec<_>>()
                    .try_into()
                    .unwrap(),
            )
        })
        .collect();
    ta.sort_unstable();
    tb.sort_unstable();
    let differing = ta.iter().zip(&tb).filter(|(x, y)| x != y).count();
    assert_eq!(differing, 0, "{differing} of {} triangles differ", ta.len());
    worst
}

/// Where the mesh buffers cannot be mapped (a device without mappable primary buffers: the CPU
/// engine pinned on a GPU), the CPU engine builds the mesh in memory and writes it through the
/// queue: the same surface as the GPU passes, through buffers that must grow.
#[test]
fn cpu_engine_writes_through_the_queue_where_buffers_cannot_be_mapped() {
    let gpu = common::gpu();
    let plain = {
        let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
        desc.backends = wgpu::Backends::from_env().unwrap_or(wgpu::Backends::PRIMARY);
        let instance = wgpu::Instance::new(desc);
        let adapter = pollster::block_on(
            instance.request_adapter(&wgpu::RequestAdapterOptions::default()),
        )
        .expect(
            "no GPU adapter found: the GPU tests need one (mesa-vulkan-drivers gives lavapipe)",
        );
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            required_limits: adapter.limits(),
            ..Default::default()
        }))
        .expect("the adapter found refused a device");
        GpuContext {
            adapter,
            device,
            queue,
        }
    };
    assert!(
        !plain
            .device
            .features()
            .contains(wgpu::Features::MAPPABLE_PRIMARY_BUFFERS)
    );
    let frame = FrameBinding::new(&plain.device);
    for method in [MT, DC] {
        let expected = extract(
            &gpu,
            &surface_pass(&gpu),
            &grid_from(&gpu, 40, torus),
            method,
            0.35,
        );
        for pass in [
            SurfacePass::new(&plain.device, &frame),
            SurfacePass::with_capacity(&plain.device, &frame, 64, 96),
        ] {
            let pass = pass.with_engine(SurfaceEngine::Cpu);
            let mesh = extract(&plain, &pass, &grid_from(&plain, 40, torus), method, 0.35);
            let error = same_surface(&mesh, &expected);
            assert!(error.position <= 1e-4, "{}: {error:?}", method.name());
        }
    }
}
