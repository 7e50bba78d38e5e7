//! The grid as the CPU extraction reads it ([`CpuGrid`]), and the sweep over its cells that both
//! methods share: which samples are inside ([`InsideBits`], 64 to a word) and, row by row, the
//! cells whose corners straddle the isovalue with their corner masks ([`InsideBits::row_cells`]).
//! As in flying edges' first pass, a sample row whose largest value (kept with the grid, so
//! found once per grid rather than once per isovalue) is not above the isovalue is skipped by
//! both, and so is a cell row whose four corner rows are all such rows.
//!
//! Reads: a grid's density and hp_mean as `f32` slices in the GPU layout (`i + dims.x * (j +
//! dims.y * k)`). Writes: a copy padded by [`PAD`] samples on every side (density 0, hp 0.5, as
//! the GPU passes read samples outside the grid), so that every corner and central-difference
//! neighbour of every cell is an index without a bounds test.
//!
//! Words: a *cell* is named by its lowest sample; cells run from -1 to dims - 1 on each axis
//! (surfaces close at the grid's border), which is cell index `c + 1` (0 ..= dims) here. A *cell
//! row* is the cells of one (y, z) along x.

use glam::{IVec3, Mat4, UVec3, Vec3, Vec3A, Vec4};

use crate::render::surface::buffers::MeshVertex;

/// Samples of padding on each side: a cell's corners reach one sample past the grid and their
/// central differences one more.
pub const PAD: usize = 2;

/// A grid on the CPU, padded by [`PAD`] on each side.
pub struct CpuGrid {
    pub dims: UVec3,
    pub box_min: Vec3,
    pub voxel_size: Vec3,
    /// Padded sizes along x and y (the z stride is `sx * sy`).
    sx: usize,
    sy: usize,
    sz: usize,
    density: Vec<f32>,
    hp: Vec<f32>,
    /// The largest density of each padded row (y, z) at `y + sy * z`, padding included: a row
    /// whose largest sample is not above the isovalue has no inside sample, so the sweeps skip
    /// it (flying edges' first pass, computed once per grid rather than once per isovalue).
    row_max: Vec<f32>,
}

impl CpuGrid {
    /// A padded copy of the fields `density` and `hp_mean` (each `dims` voxels, GPU layout).
    pub fn new(
        dims: UVec3,
        box_min: Vec3,
        box_max: Vec3,
        density: &[f32],
        hp_mean: &[f32],
    ) -> Self {
        let n = dims.as_usizevec3();
        assert_eq!(density.len(), n.x * n.y * n.z, "density has dims voxels");
        assert_eq!(hp_mean.len(), density.len(), "hp_mean has dims voxels");
        let (sx, sy, sz) = (n.x + 2 * PAD, n.y + 2 * PAD, n.z + 2 * PAD);
        let mut padded_density = vec![0.0f32; sx * sy * sz];
        let mut padded_hp = vec![0.5f32; sx * sy * sz];
        for z in 0..n.z {
            for y in 0..n.y {
                let from = n.x * (y + n.y * z);
                let to = PAD + sx * (y + PAD + sy * (z + PAD));
                padded_density[to..to + n.x].copy_from_slice(&density[from..from + n.x]);
                padded_hp[to..to + n.x].copy_from_slice(&hp_mean[from..from + n.x]);
            }
        }
        // `f32::max` passes over NaN, which is never inside either (`v > iso` is false).
        let row_max = padded_density
            .chunks_exact(sx)
            .map(|row| row.iter().fold(f32::NEG_INFINITY, |m, &v| m.max(v)))
            .collect();
        Self {
            dims,
            box_min,
            voxel_size: (box_max - box_min) / dims.as_vec3(),
            sx,
            sy,
            sz,
            density: padded_density,
            hp: padded_hp,
            row_max,
        }
    }

    /// Bytes held (both padded fields and the row maxima).
    pub fn bytes(&self) -> usize {
        (self.density.len() + self.hp.len() + self.row_max.len()) * 4
    }

    /// Index steps of one sample along x, y and z.
    pub fn strides(&self) -> [usize; 3] {
        [1, self.sx, self.sx * self.sy]
    }

    /// The padded index of the lowest sample of cell (cx, cy, cz) (cell indices, 0 ..= dims).
    pub fn cell_origin(&self, cx: usize, cy: usize, cz: usize) -> usize {
        // Cell index c is the cell whose lowest sample is c - 1, padded sample c - 1 + PAD.
        (cx + PAD - 1) + self.sx * ((cy + PAD - 1) + self.sy * (cz + PAD - 1))
    }

    pub fn density(&self) -> &[f32] {
        &self.density
    }

    pub fn hp(&self) -> &[f32] {
        &self.hp
    }

    /// The data-space position of grid point `grid` (sample units, unpadded: sample p's centre
    /// is at p).
    pub fn data_position(&self, grid: Vec3) -> Vec3 {
        self.box_min + (grid + 0.5) * self.voxel_size
    }

    /// The unpadded lowest sample of cell (cx, cy, cz).
    pub fn cell_sample(cx: usize, cy: usize, cz: usize) -> IVec3 {
        IVec3::new(cx as i32 - 1, cy as i32 - 1, cz as i32 - 1)
    }

    /// The central-difference gradient (grid units) at padded index `i`: six loads and no
    /// branch, where [`CpuGrid::corner_gradient`] of a corner not known when compiling picks
    /// its three loads by branches on the corner's bits (the same differences of the same
    /// samples, so the same values).
    #[inline]
    pub fn gradient(&self, i: usize) -> Vec3A {
        let d = &self.density;
        let [_, sy, sz] = self.strides();
        Vec3A::new(
            0.5 * (d[i + 1] - d[i - 1]),
            0.5 * (d[i + sy] - d[i - sy]),
            0.5 * (d[i + sz] - d[i - sz]),
        )
    }

    /// The eight corner values of the cell whose lowest sample is at padded index `origin`.
    #[inline]
    pub fn corners(&self, origin: usize) -> [f32; 8] {
        let strides = self.strides();
        std::array::from_fn(|k| self.density[origin + corner_step(strides, k as u32)])
    }

    /// [`CpuGrid::gradient`] at corner k of the cell at `origin` whose corner values are
    /// `values`: along each axis the neighbour inside the cell is a corner, so only the three
    /// beyond it are loaded (the same differences of the same samples, so the same values).
    #[inline]
    pub fn corner_gradient(&self, origin: usize, values: &[f32; 8], k: u32) -> Vec3 {
        let strides = self.strides();
        let at = origin + corner_step(strides, k);
        let d = &self.density;
        let axis = |a: u32| {
            let inside = values[(k ^ (1 << a)) as usize];
            if (k >> a) & 1 == 1 {
                0.5 * (d[at + strides[a as usize]] - inside)
            } else {
                0.5 * (inside - d[at - strides[a as usize]])
            }
        };
        Vec3::new(axis(0), axis(1), axis(2))
    }

    /// Unit normal in data space pointing toward lower density from a grid-unit gradient; zero
    /// when the gradient vanishes (as `outward_normal` in shaders/surface/extraction.wgsl).
    #[inline]
    pub fn outward_normal(&self, grid_gradient: Vec3) -> Vec3 {
        self.outward_normal_a(grid_gradient.into()).into()
    }

    /// [`CpuGrid::outward_normal`] in SIMD lanes: each lane's operations are the scalar ones,
    /// and the length sums x², y², z² in the same order, so the values are the same.
    #[inline]
    pub fn outward_normal_a(&self, grid_gradient: Vec3A) -> Vec3A {
        let g = grid_gradient / Vec3A::from(self.voxel_size);
        let len = g.length();
        if len < 1e-20 {
            return Vec3A::ZERO;
        }
        -g / len
    }

    /// Turns each vertex's gradient (grid units, in `normal`) into its outward unit normal, four
    /// vertices at a time in SIMD lanes (the operations of [`CpuGrid::outward_normal_a`], lane
    /// for lane, so the same values, without one vertex's divisions and square root waiting on
    /// another's); a vertex without a gradient takes `fallback(vertex)` (the vertex as written,
    /// its pad holding what the caller needs to find it). Every pad is then zero.
    pub fn outward_normals(
        &self,
        vertices: &mut [MeshVertex],
        fallback: impl Fn(&MeshVertex) -> [f32; 3],
    ) {
        let size = self.voxel_size;
        let (sx, sy, sz) = (
            Vec4::splat(size.x),
            Vec4::splat(size.y),
            Vec4::splat(size.z),
        );
        let mut groups = vertices.chunks_exact_mut(4);
        for group in &mut groups {
            let lanes = Mat4::from_cols_array_2d(&std::array::from_fn(|i| {
                let n = group[i].normal;
                [n[0], n[1], n[2], 0.0]
            }))
            .transpose();
            let (x, y, z) = (lanes.x_axis / sx, lanes.y_axis / sy, lanes.z_axis / sz);
            let length = sqrt_lanes(x * x + y * y + z * z);
            let normals = Mat4::from_cols(-x / length, -y / length, -z / length, Vec4::ZERO)
                .transpose()
                .to_cols_array_2d();
            let flat = length.cmplt(Vec4::splat(1e-20)).bitmask();
            for (i, vertex) in group.iter_mut().enumerate() {
                vertex.normal = if flat & (1 << i) != 0 {
                    fallback(vertex)
                } else {
                    [normals[i][0], normals[i][1], normals[i][2]]
                };
                vertex.pad = 0.0;
            }
        }
        for vertex in groups.into_remainder() {
            let normal = self.outward_normal_a(Vec3A::from(vertex.normal));
            vertex.normal = if normal == Vec3A::ZERO {
                fallback(vertex)
            } else {
                normal.to_array()
            };
            vertex.pad = 0.0;
        }
    }

    /// Padded rows (y, z).
    fn rows(&self) -> usize {
        self.sy * self.sz
    }
}

/// The hp of a set of samples, weighted by their density (as `weighted_hp` in
/// shaders/surface/extraction.wgsl).
#[inline]
pub fn weighted_hp(sum_weighted: f32, sum_weights: f32) -> f32 {
    if sum_weights <= 1e-12 {
        return 0.5;
    }
    (sum_weighted / sum_weights).clamp(0.0, 1.0)
}

/// The square root of each lane (IEEE, as `f32::sqrt`): one instruction where glam keeps Vec4 in
/// an SSE register.
#[inline]
fn sqrt_lanes(v: Vec4) -> Vec4 {
    #[cfg(all(target_arch = "x86_64", target_feature = "sse2"))]
    {
        // SAFETY: SSE2 is enabled at compile time (cfg above).
        return Vec4::from(unsafe { std::arch::x86_64::_mm_sqrt_ps(v.into()) });
    }
    #[allow(unreachable_code)]
    Vec4::new(v.x.sqrt(), v.y.sqrt(), v.z.sqrt(), v.w.sqrt())
}

/// Cube corner k (bit 0: x, bit 1: y, bit 2: z) as an offset from the cell's lowest sample, in
/// SIMD lanes, from a table: worked out, each was three conversions of an integer to a float
/// (edges' corners are not known when compiling).
#[inline]
pub fn corner_offset_a(k: u32) -> Vec3A {
    const OFFSETS: [Vec3A; 8] = {
        let mut table = [Vec3A::ZERO; 8];
        let mut k = 0;
        while k < 8 {
            table[k] = Vec3A::new((k & 1) as f32, ((k >> 1) & 1) as f32, ((k >> 2) & 1) as f32);
            k += 1;
        }
        table
    };
    OFFSETS[k as usize & 7]
}

/// The padded index step from a cell's lowest sample to its corner k.
#[inline]
pub fn corner_step(strides: [usize; 3], k: u32) -> usize {
    (k as usize & 1) * strides[0]
        + ((k as usize >> 1) & 1) * strides[1]
        + ((k as usize >> 2) & 1) * strides[2]
}

/// Which padded samples are inside (density > iso), 64 along x to a word, row (y, z) of the
/// padded grid at word `words * (y + sy * z)`.
pub struct InsideBits {
    bits: Vec<u64>,
    /// Whether padded row (y, z) has an inside sample (at `y + sy * z`).
    occupied: Vec<bool>,
    words: usize,
    sy: usize,
    /// Cells along x (dims.x + 1).
    cells_x: usize,
}

impl Drop for InsideBits {
    fn drop(&mut self) {
        super::recycle::WORDS.give(std::mem::take(&mut self.bits));
    }
}

impl InsideBits {
    /// The inside bits of `grid` at `iso`, computed on `threads` threads.
    pub fn new(grid: &CpuGrid, iso: f32, threads: usize) -> Self {
        let words = grid.sx.div_ceil(64);
        let rows = grid.rows();
        let mut bits = super::recycle::WORDS.filled(words * rows, 0);
        let occupied: Vec<bool> = grid.row_max.iter().map(|&m| m > iso).collect();
        let per = rows.div_ceil(threads.max(1)).max(1);
        let parts: Vec<_> = bits.chunks_mut(per * words).enumerate().collect();
        let occupied_rows = &occupied;
        super::for_each_part(parts, |(chunk, out)| {
            let first_row = chunk * per;
            for (r, row_bits) in out.chunks_mut(words).enumerate() {
                if !occupied_rows[first_row + r] {
                    // No sample above the isovalue: the bits stay zero.
                    continue;
                }
                let start = (first_row + r) * grid.sx;
                let samples = &grid.density[start..start + grid.sx];
                for (word, chunk) in row_bits.iter_mut().zip(samples.chunks(64)) {
                    *word = chunk
                        .iter()
                        .enumerate()
                        .fold(0u64, |w, (i, &v)| w | (u64::from(v > iso) << i));
                }
            }
        });
        Self {
            bits,
            occupied,
            words,
            sy: grid.sy,
            cells_x: grid.dims.x as usize + 1,
        }
    }

    /// Cells along x.
    pub fn cells_x(&self) -> usize {
        self.cells_x
    }

    /// Calls `f(cx, mask)` for each cell of cell row (cy, cz), in increasing cx, whose corners
    /// straddle the isovalue; mask bit k: corner k inside.
    #[inline]
    pub fn row_cells(&self, cy: usize, cz: usize, mut f: impl FnMut(usize, u32)) {
        // Corner row k (bit 0: +y, bit 1: +z) of cell row (cy, cz) is padded sample row
        // (cy + PAD - 1 + (k & 1), cz + PAD - 1 + (k >> 1)).
        let index = |k: usize| (cy + PAD - 1 + (k & 1)) + self.sy * (cz + PAD - 1 + (k >> 1));
        if !(0..4).any(|k| self.occupied[index(k)]) {
            // All four corner rows outside: no cell of the row straddles the isovalue.
            return;
        }
        let row = |k: usize| &self.bits[self.words * index(k)..][..self.words];
        let rows = [row(0), row(1), row(2), row(3)];
        for w in 0..self.cells_x.div_ceil(64) {
            // Cell index cx = 64w + j has its corners at padded samples cx + PAD - 1 (dx = 0)
            // and cx + PAD (dx = 1): bit j of the word shifted by PAD - 1 and PAD.
            let mut r = [0u64; 8];
            for (k, samples) in rows.iter().enumerate() {
                let lo = samples[w];
                let hi = samples.get(w + 1).copied().unwrap_or(0);
                r[2 * k] = (lo >> (PAD - 1)) | (hi << (65 - PAD));
                r[2 * k + 1] = (lo >> PAD) | (hi << (64 - PAD));
            }
            let (mut any, mut all) = (0u64, u64::MAX);
            for word in r {
                any |= word;
                all &= word;
            }
            let count = self.cells_x - 64 * w;
            let valid = if count >= 64 {
                u64::MAX
            } else {
                (1u64 << count) - 1
            };
            let mut todo = any & !all & valid;
            while todo != 0 {
                let j = todo.trailing_zeros();
                todo &= todo - 1;
                // Corner row k's corners dx = 0 and 1 are bits j and j + 1 of r[2k] (r[2k + 1]
                // is r[2k] a sample on): mask bits 2k and 2k + 1, two at a time but for the
                // last cell of a word, whose dx = 1 corners are in the next word.
                let mask = if j < 63 {
                    (((r[0] >> j) & 3)
                        | ((r[2] >> j) & 3) << 2
                        | ((r[4] >> j) & 3) << 4
                        | ((r[6] >> j) & 3) << 6) as u32
                } else {
                    r.iter().enumerate().fold(0u32, |mask, (k, word)| {
                        mask | (((word >> j) & 1) as u32) << k
                    })
                };
                f(64 * w + j as usize, mask);
            }
        }
    }
}

/// Splits `0..n` into at most `parts` contiguous ranges of about equal `weight(i)` sums.
pub fn balanced_ranges(
    n: usize,
    parts: usize,
    weight: impl Fn(usize) -> u64,
) -> Vec<std::ops::Range<usize>> {
    let total: u64 = (0..n).map(&weight).sum();
    let parts = parts.max(1);
    let mut ranges = Vec::with_capacity(parts);
    let (mut start, mut acc) = (0usize, 0u64);
    for i in 0..n {
        acc += weight(i);
        let goal = total * (ranges.len() as u64 + 1) / parts as u64;
        if acc >= goal && ranges.len() + 1 < parts {
            ranges.push(start..i + 1);
            start = i + 1;
        }
    }
    ranges.push(start..n);
    ranges
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(dims: UVec3, f: impl Fn(u32, u32, u32) -> f32) -> CpuGrid {
        let mut density = Vec::new();
        for z in 0..dims.z {
            for y in 0..dims.y {
                for x in 0..dims.x {
                    density.push(f(x, y, z));
                }
            }
        }
        let hp = vec![0.25; density.len()];
        CpuGrid::new(dims, Vec3::splat(-1.0), Vec3::splat(1.0), &density, &hp)
    }

    #[test]
    fn row_cells_match_a_direct_count_of_corners() {
        // 70 along x crosses a word of cells; an irregular field sets every kind of mask.
        let dims = UVec3::new(70, 5, 4);
        let g = grid(dims, |x, y, z| {
            ((x * 7 + y * 13 + z * 29) % 11) as f32 / 10.0
        });
        let iso = 0.45;
        let bits = InsideBits::new(&g, iso, 2);
        let d = g.density();
        let strides = g.strides();
        for cz in 0..=dims.z as usize {
            for cy in 0..=dims.y as usize {
                let mut seen = Vec::new();
                bits.row_cells(cy, cz, |cx, mask| seen.push((cx, mask)));
                let mut expected = Vec::new();
                for cx in 0..=dims.x as usize {
                    let origin = g.cell_origin(cx, cy, cz);
                    let mask = (0..8u32).fold(0, |m, k| {
                        m | (u32::from(d[origin + corner_step(strides, k)] > iso) << k)
                    });
                    if mask != 0 && mask != 0xff {
                        expected.push((cx, mask));
                    }
                }
                assert_eq!(seen, expected, "cell row ({cy}, {cz})");
            }
        }
    }

    #[test]
    fn corner_gradients_are_the_central_differences() {
        let dims = UVec3::new(9, 7, 6);
        let g = grid(dims, |x, y, z| {
            ((x * 7 + y * 13 + z * 29) % 11) as f32 / 10.0
        });
        let strides = g.strides();
        for (cx, cy, cz) in [(0, 0, 0), (3, 2, 1), (9, 7, 6), (5, 0, 6)] {
            let origin = g.cell_origin(cx, cy, cz);
            let values = g.corners(origin);
            for k in 0..8 {
                assert_eq!(
                    g.corner_gradient(origin, &values, k),
                    Vec3::from(g.gradient(origin + corner_step(strides, k))),
                    "cell ({cx}, {cy}, {cz}) corner {k}"
                );
            }
        }
    }

    /// The normals made four at a time are, bit for bit, those of one vertex at a time
    /// ([`CpuGrid::outward_normal_a`]), in full groups and in the remainder, on voxels that are
    /// not cubes; exactly the vertices without a gradient take the fallback, given the vertex as
    /// written; every pad ends zero and nothing else changes.
    #[test]
    fn normals_in_lanes_are_the_scalar_normals() {
        let g = CpuGrid::new(
            UVec3::new(3, 4, 5),
            Vec3::new(-1.0, 0.0, 2.0),
            Vec3::new(2.0, 0.5, 7.0),
            &[0.0; 60],
            &[0.5; 60],
        );
        let gradients = [
            Vec3A::new(0.3, -0.7, 0.11),
            Vec3A::ZERO,
            Vec3A::new(-1e-9, 2e-9, 0.0),
            Vec3A::new(5.0, 0.0, -3.5),
            Vec3A::new(1e-30, 0.0, 0.0),
            Vec3A::new(-0.25, 0.5, 0.125),
            Vec3A::ZERO,
        ];
        let fallback = |v: &MeshVertex| [v.pad, -v.pad, 7.0];
        let mut vertices: Vec<MeshVertex> = gradients
            .iter()
            .enumerate()
            .map(|(i, gradient)| MeshVertex {
                position: [i as f32; 3],
                hp: 0.25,
                normal: gradient.to_array(),
                pad: i as f32 + 1.0,
            })
            .collect();
        let expected: Vec<[f32; 3]> = vertices
            .iter()
            .map(|v| {
                let n = g.outward_normal_a(Vec3A::from(v.normal));
                if n == Vec3A::ZERO {
                    fallback(v)
                } else {
                    n.to_array()
                }
            })
            .collect();
        g.outward_normals(&mut vertices, fallback);
        for (i, (v, n)) in vertices.iter().zip(&expected).enumerate() {
            assert_eq!(
                v.normal.map(f32::to_bits),
                n.map(f32::to_bits),
                "vertex {i}"
            );
            assert_eq!(v.pad, 0.0, "vertex {i}'s pad");
            assert_eq!((v.position, v.hp), ([i as f32; 3], 0.25), "vertex {i}");
        }
        let fell_back: Vec<usize> = (0..7).filter(|&i| expected[i][2] == 7.0).collect();
        assert_eq!(fell_back, vec![1, 4, 6], "the vertices without a gradient");
    }

    #[test]
    fn padding_reads_as_empty_outside_the_grid() {
        let g = grid(UVec3::new(3, 3, 3), |_, _, _| 1.0);
        let [_, sy, sz] = g.strides();
        // Two padding samples before the first voxel on each axis.
        let first = PAD + sy * PAD + sz * PAD;
        assert_eq!(g.density()[first], 1.0);
        assert_eq!(g.density()[first - 1], 0.0);
        assert_eq!(g.hp()[first - 1], 0.5);
        assert_eq!(g.hp()[first], 0.25);
    }

    #[test]
    fn balanced_ranges_cover_everything_once() {
        let ranges = balanced_ranges(10, 3, |i| if i < 5 { 10 } else { 1 });
        assert_eq!(ranges.first().unwrap().start, 0);
        assert_eq!(ranges.last().unwrap().end, 10);
        for pair in ranges.windows(2) {
            assert_eq!(pair[0].end, pair[1].start);
        }
        assert!(ranges.len() <= 3);
        assert_eq!(balanced_ranges(0, 4, |_| 1), vec![0..0]);
    }
}
