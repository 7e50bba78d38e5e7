//! Running median of an odd window over many equal-length rows at once, on `u32` keys.
//!
//! The extractor's HPSS (preprocess/loudscape_extract/hpss.py) median-filters a magnitude
//! spectrogram along time and along frequency with a 31-long window. Non-negative float32
//! magnitudes sort as their bits read as `u32` do, and a median is one of the window's keys, so
//! filtering the bits gives the floats' medians bit for bit. The caller pads each row
//! symmetrically by half a window; for a padded row of length `len` this returns the
//! `len - size + 1` medians of the windows that lie fully inside it.
//!
//! Each row keeps its window sorted. A step removes the outgoing key (its first copy: the keys
//! from the first one at or above it shift down one place; the window being sorted and holding
//! the key, a comparison per position says so without a running flag) and inserts the incoming
//! one (`s'[j] = max(r[j-1], min(r[j], x))` over the shifted keys `r`), both in one
//! branch-free pass; the median is `s[size / 2]`. Rows are independent, so [`LANES`] of them run side by
//! side in the lanes of one vector (AVX2, chosen at run time, or whatever the compiler makes of
//! the portable code elsewhere). Filtering down the columns, consecutive columns are the lanes
//! and load as they lie; filtering along the rows, tiles of [`LANES`] rows are transposed first.

use std::panic::{AssertUnwindSafe, catch_unwind};

/// Rows filtered side by side, one per vector lane (8 x u32 fills an AVX2 register; 16 keep
/// two independent vectors in flight).
pub const LANES: usize = 16;

type Lane = [u32; LANES];

/// Success.
pub const OK: i32 = 0;
/// A pointer was null.
pub const ERR_NULL: i32 = 1;
/// The window size was even or zero.
pub const ERR_SIZE: i32 = 2;
/// A padded row was shorter than the window.
pub const ERR_SHORT: i32 = 3;
/// The array's element count does not fit in memory's address range.
pub const ERR_OVERFLOW: i32 = 4;
/// An unexpected failure inside the kernel (a panic, caught before it reached the caller).
pub const ERR_INTERNAL: i32 = 5;

/// Why a filter was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Error {
    /// The window size is even or zero.
    Size,
    /// A padded row is shorter than the window.
    Short,
    /// The element counts overflow, or a slice's length is not the shape's.
    Shape,
}

impl Error {
    fn code(self) -> i32 {
        match self {
            Error::Size => ERR_SIZE,
            Error::Short => ERR_SHORT,
            Error::Shape => ERR_OVERFLOW,
        }
    }
}

/// Checks a filter's shape: `rows` padded rows of `len` keys and window `size`; returns the medians
/// per row and the element counts of input and output.
fn check(rows: usize, len: usize, size: usize) -> Result<(usize, usize, usize), Error> {
    if size.is_multiple_of(2) {
        return Err(Error::Size);
    }
    if len < size {
        return Err(Error::Short);
    }
    let medians = len - size + 1;
    let input = rows.checked_mul(len).ok_or(Error::Shape)?;
    let output = rows.checked_mul(medians).ok_or(Error::Shape)?;
    // Slices may not exceed isize::MAX bytes.
    if input
        .checked_mul(4)
        .is_none_or(|bytes| bytes > isize::MAX as usize)
    {
        return Err(Error::Shape);
    }
    Ok((medians, input, output))
}

/// Running medians along each row of `input` (`rows` rows of `len` keys, row after row) into
/// `output` (`rows` rows of `len - size + 1` medians).
pub fn median_rows(
    input: &[u32],
    rows: usize,
    len: usize,
    size: usize,
    output: &mut [u32],
) -> Result<(), Error> {
    let (medians, n_in, n_out) = check(rows, len, size)?;
    if input.len() != n_in || output.len() != n_out {
        return Err(Error::Shape);
    }
    #[cfg(target_arch = "x86_64")]
    if simd() {
        // SAFETY: the CPU has AVX2.
        unsafe { rows_avx2(input, rows, len, size, medians, output) };
        return Ok(());
    }
    rows_portable(input, rows, len, size, medians, output);
    Ok(())
}

/// Running medians down each column of `input` (`len` rows of `columns` keys, row after row)
/// into `output` (`len - size + 1` rows of `columns` medians).
pub fn median_columns(
    input: &[u32],
    len: usize,
    columns: usize,
    size: usize,
    output: &mut [u32],
) -> Result<(), Error> {
    let (_, n_in, n_out) = check(columns, len, size)?;
    if input.len() != n_in || output.len() != n_out {
        return Err(Error::Shape);
    }
    #[cfg(target_arch = "x86_64")]
    if simd() {
        // SAFETY: the CPU has AVX2.
        unsafe { columns_avx2(input, len, columns, size, output) };
        return Ok(());
    }
    columns_portable(input, len, columns, size, output);
    Ok(())
}

/// Whether the vector path (AVX2) runs on this CPU.
pub fn simd() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("avx2")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn rows_avx2(
    input: &[u32],
    rows: usize,
    len: usize,
    size: usize,
    medians: usize,
    output: &mut [u32],
) {
    rows_kernel(input, rows, len, size, medians, output)
}

fn rows_portable(
    input: &[u32],
    rows: usize,
    len: usize,
    size: usize,
    medians: usize,
    output: &mut [u32],
) {
    rows_kernel(input, rows, len, size, medians, output)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn columns_avx2(input: &[u32], len: usize, columns: usize, size: usize, output: &mut [u32]) {
    columns_kernel(input, len, columns, size, output)
}

fn columns_portable(input: &[u32], len: usize, columns: usize, size: usize, output: &mut [u32]) {
    columns_kernel(input, len, columns, size, output)
}

/// Along the rows: each tile of [`LANES`] rows is transposed into `tile` (step after step,
/// lanes side by side), filtered into `medians_tile`, and transposed back. Rows past the end
/// of the last tile are zeros, filtered and dropped.
#[inline(always)]
fn rows_kernel(
    input: &[u32],
    rows: usize,
    len: usize,
    size: usize,
    medians: usize,
    output: &mut [u32],
) {
    let mut window = vec![[0u32; LANES]; size];
    let mut tile = vec![[0u32; LANES]; len];
    let mut medians_tile = vec![[0u32; LANES]; medians];
    for first in (0..rows).step_by(LANES) {
        let count = LANES.min(rows - first);
        for (lane, row) in input[first * len..(first + count) * len]
            .chunks_exact(len)
            .enumerate()
        {
            for (step, &key) in tile.iter_mut().zip(row) {
                step[lane] = key;
            }
        }
        if count < LANES {
            for step in tile.iter_mut() {
                step[count..].fill(0);
            }
        }
        filter_lanes(&tile, &mut window, &mut medians_tile);
        let out = &mut output[first * medians..(first + count) * medians];
        for (lane, row) in out.chunks_exact_mut(medians).enumerate() {
            for (median, step) in row.iter_mut().zip(&medians_tile) {
                *median = step[lane];
            }
        }
    }
}

/// Down the columns: [`LANES`] consecutive columns load as they lie; the last columns that do
/// not fill a group go through a zero-padded copy.
#[inline(always)]
fn columns_kernel(input: &[u32], len: usize, columns: usize, size: usize, output: &mut [u32]) {
    let medians = len - size + 1;
    let mut window = vec![[0u32; LANES]; size];
    let full = columns / LANES * LANES;
    for first in (0..full).step_by(LANES) {
        sort_steps(
            &mut window,
            |step| lane_at(input, step * columns + first),
            |index, median| output[index * columns + first..][..LANES].copy_from_slice(&median),
            len,
        );
    }
    if full < columns {
        let count = columns - full;
        let mut tile = vec![[0u32; LANES]; len];
        for (step, lane) in tile.iter_mut().enumerate() {
            lane[..count].copy_from_slice(&input[step * columns + full..][..count]);
        }
        let mut medians_tile = vec![[0u32; LANES]; medians];
        filter_lanes(&tile, &mut window, &mut medians_tile);
        for (index, lane) in medians_tile.iter().enumerate() {
            output[index * columns + full..][..count].copy_from_slice(&lane[..count]);
        }
    }
}

#[inline(always)]
fn lane_at(keys: &[u32], start: usize) -> Lane {
    let mut lane = [0u32; LANES];
    lane.copy_from_slice(&keys[start..start + LANES]);
    lane
}

/// Filters a transposed tile: `steps[k]` holds step `k` of every lane.
#[inline(always)]
fn filter_lanes(steps: &[Lane], window: &mut [Lane], medians: &mut [Lane]) {
    sort_steps(
        window,
        |step| steps[step],
        |index, median| medians[index] = median,
        steps.len(),
    );
}

/// The running median of `len` steps, `key(step)` giving every lane's key at a step, `emit`
/// receiving each full window's median. The window starts as `size` copies of `u32::MAX`, and
/// the first `size` steps remove one of them each, so one step serves the start as well.
#[inline(always)]
fn sort_steps(
    window: &mut [Lane],
    key: impl Fn(usize) -> Lane,
    mut emit: impl FnMut(usize, Lane),
    len: usize,
) {
    let size = window.len();
    let half = size / 2;
    window.fill([u32::MAX; LANES]);
    for step in 0..size {
        slide(window, &[u32::MAX; LANES], &key(step));
    }
    emit(0, window[half]);
    for step in size..len {
        slide(window, &key(step - size), &key(step));
        emit(step - size + 1, window[half]);
    }
}

/// One step of every lane's sorted window: remove `outgoing` (present in the window), insert
/// `incoming`. Branch-free: `r[j]` is the window with the outgoing key removed (`s[j]` below
/// the outgoing key; from its first copy on, the sorted window being at or above it there,
/// `s[j + 1]`, `u32::MAX` past the end), and the new window is `max(r[j - 1], min(r[j], x))`
/// with `r[-1] = 0`.
#[inline(always)]
fn slide(window: &mut [Lane], outgoing: &Lane, incoming: &Lane) {
    let Some(last) = window.len().checked_sub(1) else {
        return;
    };
    let mut previous = [0u32; LANES];
    let mut current = window[0];
    for j in 0..last {
        let next = window[j + 1];
        window[j] = place(&mut previous, &current, &next, outgoing, incoming);
        current = next;
    }
    window[last] = place(
        &mut previous,
        &current,
        &[u32::MAX; LANES],
        outgoing,
        incoming,
    );
}

/// One position of [`slide`]: the window's key there (`current`) and after it (`next`).
#[inline(always)]
fn place(
    previous: &mut Lane,
    current: &Lane,
    next: &Lane,
    outgoing: &Lane,
    incoming: &Lane,
) -> Lane {
    let mut sorted = [0u32; LANES];
    for l in 0..LANES {
        let shifted = if current[l] >= outgoing[l] {
            next[l]
        } else {
            current[l]
        };
        sorted[l] = previous[l].max(shifted.min(incoming[l]));
        previous[l] = shifted;
    }
    sorted
}

/// [`median_rows`] for C callers: `input` holds `rows * len` keys, `output` room for
/// `rows * (len - size + 1)`. Returns [`OK`] or an error code; never unwinds.
///
/// # Safety
/// `input` and `output` must point to that many valid, non-overlapping `u32`s.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn loudscape_median_rows(
    input: *const u32,
    rows: usize,
    len: usize,
    size: usize,
    output: *mut u32,
) -> i32 {
    // SAFETY: the caller's guarantee, passed on.
    unsafe {
        entry(input, rows, len, size, output, |input, output| {
            median_rows(input, rows, len, size, output)
        })
    }
}

/// [`median_columns`] for C callers: `input` holds `len * columns` keys, `output` room for
/// `(len - size + 1) * columns`. Returns [`OK`] or an error code; never unwinds.
///
/// # Safety
/// `input` and `output` must point to that many valid, non-overlapping `u32`s.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn loudscape_median_columns(
    input: *const u32,
    len: usize,
    columns: usize,
    size: usize,
    output: *mut u32,
) -> i32 {
    // SAFETY: the caller's guarantee, passed on.
    unsafe {
        entry(input, columns, len, size, output, |input, output| {
            median_columns(input, len, columns, size, output)
        })
    }
}

/// What both entry points do around their filter: the counts checked, null pointers refused,
/// the pointers made slices of the checked lengths, and the filter run without unwinding.
///
/// # Safety
/// `input` and `output` must point to as many valid, non-overlapping `u32`s as [`check`]
/// counts for `lanes`, `len` and `size`.
unsafe fn entry(
    input: *const u32,
    lanes: usize,
    len: usize,
    size: usize,
    output: *mut u32,
    filter: impl FnOnce(&[u32], &mut [u32]) -> Result<(), Error>,
) -> i32 {
    let (_, n_in, n_out) = match check(lanes, len, size) {
        Ok(counts) => counts,
        Err(error) => return error.code(),
    };
    if input.is_null() || output.is_null() {
        return ERR_NULL;
    }
    // SAFETY: the caller guarantees the counts checked above.
    let (input, output) = unsafe {
        (
            std::slice::from_raw_parts(input, n_in),
            std::slice::from_raw_parts_mut(output, n_out),
        )
    };
    guarded(|| filter(input, output))
}

/// 1 where the vector path (AVX2) runs on this CPU, else 0.
#[unsafe(no_mangle)]
pub extern "C" fn loudscape_median_simd() -> i32 {
    i32::from(simd())
}

fn guarded(filter: impl FnOnce() -> Result<(), Error>) -> i32 {
    match catch_unwind(AssertUnwindSafe(filter)) {
        Ok(Ok(())) => OK,
        Ok(Err(error)) => error.code(),
        Err(_) => ERR_INTERNAL,
    }
}

#[cfg(test)]
mod tests;
