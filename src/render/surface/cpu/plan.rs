//! The two sweeps of a CPU extraction that both methods share: [`Plan::new`] counts each cell
//! row's vertices and indices (whose prefix sums give every row its place in the output, so the
//! result is the same whatever the number of threads), then [`Plan::write`] runs the method's row
//! writer over the rows on all threads, each thread writing its rows' share of the output
//! straight into the destination (mapped mesh buffers, through [`WriteOnly`]) in batches
//! from a small buffer that stays in cache.

use std::ops::Range;

use wgpu::WriteOnly;

use crate::render::surface::buffers::MeshVertex;
use crate::render::surface::cpu::grid::{CpuGrid, InsideBits, balanced_ranges};
use crate::render::surface::cpu::{Instant, Phases, for_each_part, recycle};

/// Vertices a thread gathers before it copies them out (and a quarter as many indices' worth
/// of bytes).
const BATCH: usize = 4096;

/// What a row writer is given: the rows' active cells and places in the output.
pub struct Rows<'a> {
    /// Each row's active cells, `cx << 8 | mask` in increasing cx, from `cell_start[row]`.
    cells: &'a [u32],
    cell_start: &'a [usize],
    /// First vertex of each cell row (and the total at the end).
    pub vertex_start: &'a [usize],
    pub cells_y: usize,
    pub cells_z: usize,
}

impl Rows<'_> {
    /// The active cells (cx, corner mask) of cell row (cy, cz), in increasing cx.
    #[inline]
    pub fn cells(&self, cy: usize, cz: usize) -> impl Iterator<Item = (usize, u32)> + '_ {
        let row = cy + self.cells_y * cz;
        self.cells[self.cell_start[row]..self.cell_start[row + 1]]
            .iter()
            .map(|&c| ((c >> 8) as usize, c & 0xff))
    }
}

/// The counted surface: each cell row's active cells and place in the output.
pub struct Plan {
    /// Cells along x.
    pub cells_x: usize,
    cells: Vec<u32>,
    cell_start: Vec<usize>,
    vertex_start: Vec<usize>,
    index_start: Vec<usize>,
    /// Active cells per row (to balance the threads).
    row_active: Vec<u32>,
    pub active_cells: u64,
    cells_y: usize,
    cells_z: usize,
}

impl Plan {
    /// Inside bits of `grid` at `iso`, then the active cells of every cell row and their
    /// output, `count(cx, cy, cz, mask)` ([vertices, indices]) each, on `threads` threads.
    pub fn new(
        grid: &CpuGrid,
        iso: f32,
        threads: usize,
        phases: &mut Phases,
        count: impl Fn(usize, usize, usize, u32) -> [u32; 2] + Sync,
    ) -> Self {
        let started = Instant::now();
        let bits = InsideBits::new(grid, iso, threads);
        phases.lap("inside bits", started);
        let started = Instant::now();
        let (cells_y, cells_z) = (grid.dims.y as usize + 1, grid.dims.z as usize + 1);
        let rows = cells_y * cells_z;
        let mut counts = recycle::COUNTS.filled(rows, [0u32; 3]);
        let per = rows.div_ceil(threads.max(1)).max(1);
        let parts: Vec<_> = counts.chunks_mut(per).enumerate().collect();
        let chunk_cells = for_each_part(parts, |(chunk, out)| {
            let mut cells = recycle::U32S.take();
            for (r, c) in out.iter_mut().enumerate() {
                let row = chunk * per + r;
                let (cy, cz) = (row % cells_y, row / cells_y);
                bits.row_cells(cy, cz, |cx, mask| {
                    let [v, i] = count(cx, cy, cz, mask);
                    c[0] += v;
                    c[1] += i;
                    c[2] += 1;
                    cells.push((cx as u32) << 8 | mask);
                });
            }
            cells
        });
        let mut cells = recycle::U32S.take();
        for part in chunk_cells {
            cells.extend_from_slice(&part);
            recycle::U32S.give(part);
        }
        let plan = Self::assemble(bits.cells_x(), cells_y, cells_z, &counts, cells);
        recycle::COUNTS.give(counts);
        phases.lap("classify", started);
        plan
    }

    /// The plan of the active cells `cells` (each row's in increasing cx, rows in order) whose
    /// rows count `counts` ([vertices, indices, active cells] each).
    fn assemble(
        cells_x: usize,
        cells_y: usize,
        cells_z: usize,
        counts: &[[u32; 3]],
        cells: Vec<u32>,
    ) -> Self {
        let starts = || {
            let mut v = recycle::USIZES.take();
            v.reserve(counts.len() + 1);
            v
        };
        let (mut vertex_start, mut index_start, mut cell_start) = (starts(), starts(), starts());
        let mut row_active = recycle::U32S.take();
        row_active.extend(counts.iter().map(|c| c[2]));
        let (mut v, mut i, mut active) = (0usize, 0usize, 0usize);
        for c in counts {
            vertex_start.push(v);
            index_start.push(i);
            cell_start.push(active);
            v += c[0] as usize;
            i += c[1] as usize;
            active += c[2] as usize;
        }
        vertex_start.push(v);
        index_start.push(i);
        cell_start.push(active);
        Self {
            cells_x,
            cells,
            cell_start,
            vertex_start,
            index_start,
            row_active,
            active_cells: active as u64,
            cells_y,
            cells_z,
        }
    }

    pub fn vertices(&self) -> usize {
        *self.vertex_start.last().unwrap_or(&0)
    }

    pub fn indices(&self) -> usize {
        *self.index_start.last().unwrap_or(&0)
    }

    /// Writes the surface: `vertices` and `indices` are exactly [`Plan::vertices`] vertex
    /// records and [`Plan::indices`] indices long; `row(state, rows, row, vertices, indices)`
    /// appends one cell row's output (in cell order), with a `state` per thread from
    /// `make_state`.
    pub fn write<S>(
        &self,
        threads: usize,
        vertices: WriteOnly<'_, [u8]>,
        indices: WriteOnly<'_, [u8]>,
        make_state: impl Fn() -> S + Sync,
        row: impl Fn(&mut S, &Rows<'_>, usize, &mut Vec<MeshVertex>, &mut Vec<u32>) + Sync,
    ) {
        let vertex_size = std::mem::size_of::<MeshVertex>();
        assert_eq!(
            vertices.len(),
            self.vertices() * vertex_size,
            "vertex output"
        );
        assert_eq!(indices.len(), self.indices() * 4, "index output");
        let rows = Rows {
            cells: &self.cells,
            cell_start: &self.cell_start,
            vertex_start: &self.vertex_start,
            cells_y: self.cells_y,
            cells_z: self.cells_z,
        };
        let ranges = balanced_ranges(self.row_active.len(), threads, |r| {
            u64::from(self.row_active[r])
        });
        let (mut vertex_rest, mut index_rest) = (vertices, indices);
        let mut shares = Vec::with_capacity(ranges.len());
        for range in ranges {
            let v_bytes = self.span(&self.vertex_start, &range) * vertex_size;
            let i_bytes = self.span(&self.index_start, &range) * 4;
            let (vertex_out, vertex_tail) = vertex_rest.split_at(v_bytes);
            let (index_out, index_tail) = index_rest.split_at(i_bytes);
            (vertex_rest, index_rest) = (vertex_tail, index_tail);
            shares.push((range, Share(vertex_out, index_out)));
        }
        let rows = &rows;
        for_each_part(shares, |(range, share)| {
            let (vertex_out, index_out) = share.into_parts();
            let mut state = make_state();
            let mut out = Batches::new(vertex_out, index_out);
            for r in range {
                row(&mut state, rows, r, &mut out.vertices, &mut out.indices);
                if out.vertices.len() >= BATCH || out.indices.len() >= 4 * BATCH {
                    out.flush();
                }
            }
            out.flush();
            stream_fence();
            out.assert_full();
        });
    }

    fn span(&self, starts: &[usize], range: &Range<usize>) -> usize {
        starts[range.end] - starts[range.start]
    }
}

impl Drop for Plan {
    fn drop(&mut self) {
        for v in [&mut self.cells, &mut self.row_active] {
            recycle::U32S.give(std::mem::take(v));
        }
        for v in [
            &mut self.cell_start,
            &mut self.vertex_start,
            &mut self.index_start,
        ] {
            recycle::USIZES.give(std::mem::take(v));
        }
    }
}

/// A thread's share of the output, sent to it. `WriteOnly<[u8]>` is an exclusive borrow of
/// bytes, sent like a `&mut [u8]`; wgpu 30 implements `Send` for `WriteOnly<T>` only where `T`
/// is sized, so the share travels wrapped.
struct Share<'a>(WriteOnly<'a, [u8]>, WriteOnly<'a, [u8]>);

// SAFETY: each `WriteOnly<'a, [u8]>` is a unique borrow of a byte range for 'a (wgpu's own
// `WriteOnly::split_at` made the ranges disjoint), which is `Send` as `&'a mut [u8]` is; the
// wrapper only moves the two to the one thread that writes them.
unsafe impl Send for Share<'_> {}

impl<'a> Share<'a> {
    fn into_parts(self) -> (WriteOnly<'a, [u8]>, WriteOnly<'a, [u8]>) {
        (self.0, self.1)
    }
}

/// A thread's output: batches gathered in cache, copied out in order.
struct Batches<'a> {
    vertex_out: WriteOnly<'a, [u8]>,
    index_out: WriteOnly<'a, [u8]>,
    vertex_at: usize,
    index_at: usize,
    vertices: Vec<MeshVertex>,
    indices: Vec<u32>,
}

impl Drop for Batches<'_> {
    fn drop(&mut self) {
        recycle::VERTICES.give(std::mem::take(&mut self.vertices));
        recycle::U32S.give(std::mem::take(&mut self.indices));
    }
}

impl<'a> Batches<'a> {
    fn new(vertex_out: WriteOnly<'a, [u8]>, index_out: WriteOnly<'a, [u8]>) -> Self {
        let mut batches = Self {
            vertex_out,
            index_out,
            vertex_at: 0,
            index_at: 0,
            vertices: recycle::VERTICES.take(),
            indices: recycle::U32S.take(),
        };
        batches.vertices.reserve(2 * BATCH);
        batches.indices.reserve(8 * BATCH);
        batches
    }

    fn flush(&mut self) {
        let bytes: &[u8] = bytemuck::cast_slice(&self.vertices);
        stream_copy(
            self.vertex_out
                .slice(self.vertex_at..self.vertex_at + bytes.len()),
            bytes,
        );
        self.vertex_at += bytes.len();
        self.vertices.clear();
        let bytes: &[u8] = bytemuck::cast_slice(&self.indices);
        stream_copy(
            self.index_out
                .slice(self.index_at..self.index_at + bytes.len()),
            bytes,
        );
        self.index_at += bytes.len();
        self.indices.clear();
    }

    /// Every byte of the thread's share was written (the counts and the writers agree).
    fn assert_full(&self) {
        assert_eq!(self.vertex_at, self.vertex_out.len(), "vertices written");
        assert_eq!(self.index_at, self.index_out.len(), "indices written");
    }
}

/// Copies `src` into `dst` (the same length). On x86-64 with streaming (non-temporal) stores:
/// the output is written once and read next by the device, so it goes to memory without first
/// being read into the cache as ordinary stores do (marching tetrahedra writes 27 MB at 128^3;
/// on two threads 8.4 -> 7.6 ms). [`stream_fence`] orders them before the thread's work is
/// handed back.
fn stream_copy(mut dst: WriteOnly<'_, [u8]>, src: &[u8]) {
    assert_eq!(dst.len(), src.len(), "copy lengths");
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{__m128i, _mm_loadu_si128, _mm_stream_si128};
        let to = dst.as_raw_element_ptr().as_ptr();
        let head = to.align_offset(16).min(src.len());
        // SAFETY: `to` is the start of `dst`, `src.len()` writable bytes that nothing else
        // reads or writes while `dst` is borrowed here; every store below is inside them, the
        // 16-byte streaming stores at 16-byte aligned addresses (after `head` bytes), and SSE2
        // is part of x86-64.
        unsafe {
            std::ptr::copy_nonoverlapping(src.as_ptr(), to, head);
            let mut at = head;
            while at + 16 <= src.len() {
                let value = _mm_loadu_si128(src.as_ptr().add(at).cast::<__m128i>());
                _mm_stream_si128(to.add(at).cast::<__m128i>(), value);
                at += 16;
            }
            std::ptr::copy_nonoverlapping(src.as_ptr().add(at), to.add(at), src.len() - at);
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    dst.copy_from_slice(src);
}

/// Orders the streaming stores of [`stream_copy`] before the stores that follow (a thread's
/// last act before its share is handed back).
fn stream_fence() {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: a store fence has no preconditions (SSE is part of x86-64).
    unsafe {
        std::arch::x86_64::_mm_sfence();
    }
}

#[cfg(test)]
mod tests {
    use glam::{UVec3, Vec3};

    use super::*;
    use crate::render::surface::SurfaceMethod;
    use crate::render::surface::cpu::grid::corner_step;
    use crate::render::surface::cpu::{CpuExtraction, dual_contour, marching_tets};
    use crate::render::surface::marching_tets::case_table;

    /// The plan found the slow way: every cell of every row, its eight corners read one by one
    /// (no inside bits, no skipped rows or words).
    fn brute_force(
        grid: &CpuGrid,
        iso: f32,
        count: impl Fn(usize, usize, usize, u32) -> [u32; 2],
    ) -> Plan {
        let cells = (grid.dims + 1).as_usizevec3();
        let (density, strides) = (grid.density(), grid.strides());
        let mut counts = Vec::new();
        let mut active = Vec::new();
        for cz in 0..cells.z {
            for cy in 0..cells.y {
                let mut row = [0u32; 3];
                for cx in 0..cells.x {
                    let origin = grid.cell_origin(cx, cy, cz);
                    let mask = (0..8u32).fold(0, |mask, k| {
                        mask | u32::from(density[origin + corner_step(strides, k)] > iso) << k
                    });
                    if mask != 0 && mask != 0xff {
                        let [v, i] = count(cx, cy, cz, mask);
                        row = [row[0] + v, row[1] + i, row[2] + 1];
                        active.push((cx as u32) << 8 | mask);
                    }
                }
                counts.push(row);
            }
        }
        Plan::assemble(cells.x, cells.y, cells.z, &counts, active)
    }

    /// A field from `f(x, y, z)` on a grid of `dims` in the box [-1, 1]^3.
    fn grid(dims: UVec3, mut f: impl FnMut(u32, u32, u32) -> f32) -> CpuGrid {
        let mut density = Vec::new();
        for z in 0..dims.z {
            for y in 0..dims.y {
                for x in 0..dims.x {
                    density.push(f(x, y, z));
                }
            }
        }
        let hp: Vec<f32> = (0..density.len()).map(|i| (i % 7) as f32 / 6.0).collect();
        CpuGrid::new(dims, Vec3::splat(-1.0), Vec3::ONE, &density, &hp)
    }

    /// Uniform numbers in [0, 1) from a fixed seed (xorshift).
    fn random(seed: u64) -> impl FnMut() -> f32 {
        let mut state = seed;
        move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 40) as f32 / (1u64 << 24) as f32
        }
    }

    /// The fast sweep (inside bits, rows and words without an inside sample skipped) finds
    /// exactly the active cells, masks and counts that reading every cell's corners finds, and
    /// both methods write the same bytes from the two plans, on random fields with empty rows,
    /// full rows and sparse specks (odd sizes, a row longer than a 64-cell word), and on the
    /// song-like field, at isovalues below, inside and above the fields' range.
    #[test]
    fn the_fast_sweep_finds_every_crossing_cell() {
        let mut noise = random(0x5eed_1234_abcd);
        let banded = grid(UVec3::new(70, 23, 17), |_, y, z| {
            let value = noise();
            if (y + z) % 3 == 0 {
                0.0 // rows with no inside sample, skipped
            } else if (y * z) % 7 == 1 {
                0.9 // rows inside end to end
            } else {
                value
            }
        });
        let mut noise = random(0x00dd_ba11);
        let specks = grid(UVec3::new(131, 9, 12), |_, _, _| {
            let (keep, value) = (noise(), noise());
            if keep < 0.02 { value } else { 0.0 }
        });
        let (song_density, song_hp) =
            crate::data::synthetic::song_like_field(UVec3::new(48, 41, 37));
        let song = CpuGrid::new(
            UVec3::new(48, 41, 37),
            Vec3::splat(-1.0),
            Vec3::ONE,
            &song_density,
            &song_hp,
        );
        let cases = case_table();
        let mut active = 0;
        for (name, grid, isos) in [
            ("banded", &banded, &[0.3, 0.5, 0.0, -0.1, 0.89, 0.95][..]),
            ("specks", &specks, &[0.2, 0.0][..]),
            ("song-like", &song, &[0.3, 0.6][..]),
        ] {
            for &iso in isos {
                for method in SurfaceMethod::ALL {
                    let slow = match method {
                        SurfaceMethod::MarchingTetrahedra => {
                            brute_force(grid, iso, |_, _, _, m| {
                                marching_tets::cell_counts(&cases, m)
                            })
                        }
                        SurfaceMethod::DualContouring => {
                            brute_force(grid, iso, dual_contour::cell_counts)
                        }
                    };
                    for threads in [1, 3] {
                        let extraction = CpuExtraction {
                            grid,
                            method,
                            iso,
                            threads,
                        };
                        let fast = extraction.plan(&mut Phases::default());
                        let at = format!("{name} at {iso}, {}, {threads} threads", method.name());
                        for row in 0..fast.row_active.len() {
                            let cells = |plan: &Plan| {
                                plan.cells[plan.cell_start[row]..plan.cell_start[row + 1]].to_vec()
                            };
                            assert_eq!(cells(&fast), cells(&slow), "{at}: cell row {row}");
                        }
                        assert_eq!(fast.vertex_start, slow.vertex_start, "{at}: vertices");
                        assert_eq!(fast.index_start, slow.index_start, "{at}: indices");
                        assert_eq!(fast.active_cells, slow.active_cells, "{at}: active cells");
                        let (fast_vertices, fast_indices) = extraction.mesh(&fast);
                        let (slow_vertices, slow_indices) = extraction.mesh(&slow);
                        assert!(
                            bytemuck::cast_slice::<_, u8>(&fast_vertices)
                                == bytemuck::cast_slice::<_, u8>(&slow_vertices),
                            "{at}: vertex bytes"
                        );
                        assert_eq!(fast_indices, slow_indices, "{at}: indices");
                        active += fast.active_cells;
                    }
                }
            }
        }
        assert!(active > 50_000, "only {active} active cells compared");
    }

    /// The streaming copy writes exactly the source, whatever the destination's alignment and
    /// the length (the unaligned head, the 16-byte body and the tail), and nothing around it.
    #[test]
    fn the_streaming_copy_writes_exactly_its_source() {
        let source: Vec<u8> = (0..200u32).map(|i| (i * 7 + 3) as u8).collect();
        for offset in 0..17 {
            for len in [0, 1, 15, 16, 17, 31, 32, 33, 100, 150] {
                let mut out = vec![0xAAu8; 200 + 40];
                stream_copy(
                    WriteOnly::from(&mut out[offset..offset + len]),
                    &source[..len],
                );
                stream_fence();
                assert_eq!(&out[offset..offset + len], &source[..len], "{offset} {len}");
                assert!(
                    out[..offset]
                        .iter()
                        .chain(&out[offset + len..])
                        .all(|&b| b == 0xAA),
                    "{offset} {len}: bytes outside written"
                );
            }
        }
    }
}
