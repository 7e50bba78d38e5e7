//! The kernel against a sort of every window.

use super::*;

/// Every window of every row sorted, its middle key taken.
fn naive_rows(input: &[u32], rows: usize, len: usize, size: usize) -> Vec<u32> {
    let mut out = Vec::new();
    for row in input.chunks_exact(len).take(rows) {
        for window in row.windows(size) {
            let mut sorted = window.to_vec();
            sorted.sort_unstable();
            out.push(sorted[size / 2]);
        }
    }
    out
}

fn transpose(keys: &[u32], rows: usize, columns: usize) -> Vec<u32> {
    let mut out = vec![0; keys.len()];
    for r in 0..rows {
        for c in 0..columns {
            out[c * rows + r] = keys[r * columns + c];
        }
    }
    out
}

/// A small xorshift generator: keys from a few distinct values (ties and runs) or any u32.
struct Keys(u64);

impl Keys {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }

    fn fill(&mut self, count: usize, distinct: u64) -> Vec<u32> {
        (0..count)
            .map(|_| match distinct {
                0 => self.next() as u32,
                d => ((self.next() % d) as u32).wrapping_mul(0x1000_0001),
            })
            .collect()
    }
}

fn check_both(input: &[u32], rows: usize, len: usize, size: usize) {
    let expected = naive_rows(input, rows, len, size);
    let medians = len - size + 1;
    let mut out = vec![0; rows * medians];
    median_rows(input, rows, len, size, &mut out).unwrap();
    assert_eq!(out, expected, "rows {rows} len {len} size {size}");
    // The same rows as columns.
    let columns_in = transpose(input, rows, len);
    let mut out = vec![0; rows * medians];
    median_columns(&columns_in, len, rows, size, &mut out).unwrap();
    assert_eq!(
        out,
        transpose(&expected, rows, medians),
        "columns {rows} len {len} size {size}"
    );
    // The portable path too, where the vector one ran above.
    let mut out = vec![0; rows * medians];
    rows_portable(input, rows, len, size, medians, &mut out);
    assert_eq!(out, expected);
    let mut out = vec![0; rows * medians];
    columns_portable(&columns_in, len, rows, size, &mut out);
    assert_eq!(out, transpose(&expected, rows, medians));
}

#[test]
fn equals_a_sort_of_every_window() {
    let mut keys = Keys(0x9E37_79B9_7F4A_7C15);
    for &size in &[1, 3, 5, 31, 33] {
        for &rows in &[1, 7, LANES - 1, LANES, LANES + 1, 2 * LANES + 3] {
            for &len in &[size, size + 1, size + 40, 3 * size + 7] {
                for &distinct in &[0, 2, 3, 17] {
                    let input = keys.fill(rows * len, distinct);
                    check_both(&input, rows, len, size);
                }
            }
        }
    }
}

#[test]
fn extreme_keys() {
    // Zeros, the largest key (the window's own start value) and runs of each.
    let len = 80;
    let rows = 5;
    let mut input = vec![0u32; rows * len];
    for (i, key) in input.iter_mut().enumerate() {
        *key = match (i / 7) % 4 {
            0 => 0,
            1 => u32::MAX,
            2 => 0x7F80_0000,
            _ => i as u32,
        };
    }
    for size in [1, 3, 31] {
        check_both(&input, rows, len, size);
    }
    let all_max = vec![u32::MAX; 3 * 40];
    check_both(&all_max, 3, 40, 31);
}

#[test]
fn refuses_bad_shapes() {
    let input = [0u32; 10];
    let mut out = [0u32; 10];
    assert_eq!(
        median_rows(&input, 1, 10, 4, &mut out[..7]),
        Err(Error::Size)
    );
    assert_eq!(median_rows(&input, 1, 10, 0, &mut out), Err(Error::Size));
    assert_eq!(median_rows(&input, 1, 10, 11, &mut out), Err(Error::Short));
    assert_eq!(median_rows(&input, 1, 10, 3, &mut out), Err(Error::Shape));
    assert_eq!(
        median_columns(&input, 10, 2, 3, &mut out[..8]),
        Err(Error::Shape)
    );
    assert_eq!(median_rows(&input, 1, 10, 3, &mut out[..8]), Ok(()));
    assert_eq!(median_rows(&[], 0, 5, 3, &mut []), Ok(()));
    // Through the C entry points: error codes, no unwinding.
    unsafe {
        assert_eq!(
            loudscape_median_rows(std::ptr::null(), 1, 10, 3, out.as_mut_ptr()),
            ERR_NULL
        );
        assert_eq!(
            loudscape_median_rows(input.as_ptr(), 1, 10, 2, out.as_mut_ptr()),
            ERR_SIZE
        );
        assert_eq!(
            loudscape_median_columns(input.as_ptr(), 2, 5, 3, out.as_mut_ptr()),
            ERR_SHORT
        );
        assert_eq!(
            loudscape_median_rows(input.as_ptr(), usize::MAX, 10, 3, out.as_mut_ptr()),
            ERR_OVERFLOW
        );
        assert_eq!(
            loudscape_median_columns(input.as_ptr(), 5, 2, 3, out.as_mut_ptr()),
            OK
        );
    }
    let expected = naive_rows(&transpose(&input, 5, 2), 2, 5, 3);
    assert_eq!(&out[..6], &transpose(&expected, 2, 3)[..]);
}
