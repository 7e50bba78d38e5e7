//! Vectors an extraction gives back for the next one to take ([`Recycled`]), so that the next
//! isovalue's counts, cell lists and output batches are written into memory the process already
//! has. Freshly allocated, each of those pages was zeroed by the kernel on first touch: about
//! 450 page faults per extraction at 128^3, a fifth of a marching tetrahedra extraction's time
//! on two threads (freed, the allocator handed the pages back to the system).
//!
//! Reads and writes nothing but its own pools, one per element type, each keeping at most
//! [`KEPT`] vectors of at most [`KEPT_BYTES`] bytes.

use std::sync::Mutex;

use crate::render::surface::buffers::MeshVertex;

/// Vectors kept per pool: enough for every thread's share (16) and the plan's own.
const KEPT: usize = 24;

/// The largest vector kept, in bytes: a larger one (a grid far past 256^3) goes back to the
/// system.
const KEPT_BYTES: usize = 64 << 20;

/// A pool of emptied vectors of `T`.
pub struct Recycled<T> {
    kept: Mutex<Vec<Vec<T>>>,
}

impl<T> Recycled<T> {
    const fn new() -> Self {
        Self {
            kept: Mutex::new(Vec::new()),
        }
    }

    /// An empty vector, with the capacity of the largest one kept (none: a new one).
    pub fn take(&self) -> Vec<T> {
        let mut kept = self.kept.lock().unwrap_or_else(|e| e.into_inner());
        let largest = (0..kept.len()).max_by_key(|&i| kept[i].capacity());
        largest.map_or_else(Vec::new, |i| kept.swap_remove(i))
    }

    /// A vector of `len` copies of `value`, in a kept vector's memory where one is kept.
    pub fn filled(&self, len: usize, value: T) -> Vec<T>
    where
        T: Clone,
    {
        let mut v = self.take();
        v.resize(len, value);
        v
    }

    /// Keeps `v`, emptied, for a later [`Recycled::take`] (unless the pool is full or it is too
    /// large).
    pub fn give(&self, mut v: Vec<T>) {
        if v.capacity() == 0 || v.capacity() * std::mem::size_of::<T>() > KEPT_BYTES {
            return;
        }
        v.clear();
        let mut kept = self.kept.lock().unwrap_or_else(|e| e.into_inner());
        if kept.len() < KEPT {
            kept.push(v);
        }
    }
}

/// Cell lists and per-row counts.
pub static U32S: Recycled<u32> = Recycled::new();
/// Row starts.
pub static USIZES: Recycled<usize> = Recycled::new();
/// Inside bits.
pub static WORDS: Recycled<u64> = Recycled::new();
/// Rows' [vertices, indices, active cells].
pub static COUNTS: Recycled<[u32; 3]> = Recycled::new();
/// Output batches.
pub static VERTICES: Recycled<MeshVertex> = Recycled::new();

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_given_vector_comes_back_empty_with_its_memory() {
        let pool: Recycled<u16> = Recycled::new();
        assert_eq!(
            pool.take().capacity(),
            0,
            "an empty pool gives a new vector"
        );
        let mut v = Vec::with_capacity(1000);
        v.extend([1u16, 2, 3]);
        let at = v.as_ptr();
        pool.give(v);
        pool.give(Vec::with_capacity(10));
        let back = pool.take();
        assert!(back.is_empty());
        assert_eq!(back.as_ptr(), at, "the largest kept vector is taken first");
        assert_eq!(pool.filled(4, 7), vec![7; 4]);
        for _ in 0..2 * KEPT {
            pool.give(Vec::with_capacity(8));
        }
        assert_eq!(
            pool.kept.lock().unwrap().len(),
            KEPT,
            "the pool keeps at most KEPT"
        );
        let _ = pool.take();
        pool.give(Vec::with_capacity(KEPT_BYTES));
        assert!(
            pool.kept
                .lock()
                .unwrap()
                .iter()
                .all(|v| v.capacity() < KEPT_BYTES),
            "a vector past KEPT_BYTES is not kept"
        );
    }
}
