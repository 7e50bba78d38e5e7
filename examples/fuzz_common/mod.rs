//! What the fuzzers share (examples/fuzz_ply.rs, examples/fuzz_formats.rs): a counting
//! allocator, so that each input's peak memory is known, and the per-input limits that make an
//! amplification (a small input that takes much memory or time) a finding like a crash; their
//! command-line options and where a PLY header ends.
#![allow(dead_code)]

use std::alloc::{GlobalAlloc, Layout, System};
use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

/// The system allocator, counting the bytes live and the peak since [`Limits::start`].
pub struct Counting;

static LIVE: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);

// SAFETY: every call goes to the system allocator unchanged; only counters are added.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        // SAFETY: the caller's contract is passed on as it is.
        let p = unsafe { System.alloc(layout) };
        if !p.is_null() {
            let live = LIVE.fetch_add(layout.size(), Ordering::Relaxed) + layout.size();
            PEAK.fetch_max(live, Ordering::Relaxed);
        }
        p
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: as above.
        unsafe { System.dealloc(ptr, layout) };
        LIVE.fetch_sub(layout.size(), Ordering::Relaxed);
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        // SAFETY: as above.
        let p = unsafe { System.realloc(ptr, layout, new_size) };
        if !p.is_null() {
            if new_size >= layout.size() {
                let grown = new_size - layout.size();
                let live = LIVE.fetch_add(grown, Ordering::Relaxed) + grown;
                PEAK.fetch_max(live, Ordering::Relaxed);
            } else {
                LIVE.fetch_sub(layout.size() - new_size, Ordering::Relaxed);
            }
        }
        p
    }
}

/// The most one input may take: `base` bytes plus `per_byte` times its length, and `time`.
#[derive(Clone, Copy, Debug)]
pub struct Limits {
    pub base: usize,
    pub per_byte: usize,
    pub time: Duration,
}

impl Limits {
    /// 32 MiB + 64 bytes per input byte, and 2 s (10 s in the debug build, which is slower).
    pub fn default_for_build() -> Limits {
        Limits {
            base: 32 << 20,
            per_byte: 64,
            time: Duration::from_secs(if cfg!(debug_assertions) { 10 } else { 2 }),
        }
    }

    /// Marks the start of an input: the peak is counted from what is live now.
    pub fn start(&self) -> Watch {
        let live = LIVE.load(Ordering::Relaxed);
        PEAK.store(live, Ordering::Relaxed);
        Watch {
            live,
            started: Instant::now(),
        }
    }
}

/// One input's measure: its peak memory above what was live before, and its time.
pub struct Watch {
    live: usize,
    started: Instant,
}

impl Watch {
    /// `Err` naming the amplification when the input of `len` bytes went over `limits`.
    pub fn check(&self, limits: &Limits, len: usize) -> Result<(), String> {
        let peak = PEAK.load(Ordering::Relaxed).saturating_sub(self.live);
        let elapsed = self.started.elapsed();
        let allowed = limits.base + limits.per_byte.saturating_mul(len);
        if peak > allowed {
            return Err(format!(
                "amplification: {len} bytes of input took {peak} bytes of memory (limit {allowed})"
            ));
        }
        if elapsed > limits.time {
            return Err(format!(
                "slow input: {len} bytes took {:.2} s (limit {:.1} s)",
                elapsed.as_secs_f64(),
                limits.time.as_secs_f64()
            ));
        }
        Ok(())
    }
}

/// xorshift64*: small, fast and reproducible from a seed.
pub struct Rng(pub u64);

impl Rng {
    pub fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }
    pub fn below(&mut self, n: usize) -> usize {
        if n == 0 {
            0
        } else {
            (self.next() % n as u64) as usize
        }
    }
    pub fn chance(&mut self, one_in: usize) -> bool {
        self.below(one_in) == 0
    }
    pub fn pick<'a, T>(&mut self, items: &'a [T]) -> &'a T {
        &items[self.below(items.len())]
    }
}

/// A fuzzer's command line: `--inputs N` and/or `--seconds S` (100,000 inputs when neither is
/// given), `--seed N`, `--crashes DIR` (fuzz-crashes/), and `--only TARGET` where the fuzzer has
/// targets.
pub struct Options {
    pub inputs: Option<u64>,
    pub seconds: Option<f64>,
    pub seed: u64,
    pub only: Option<String>,
    pub crashes: PathBuf,
}

/// The options of the fuzzer `name` (examples/NAME.rs) from its command line; `targets` are the
/// values `--only` takes (none: no `--only`). An unknown option ends the process with status 2.
pub fn options(name: &str, seed: u64, targets: &[&str]) -> Options {
    let mut options = Options {
        inputs: None,
        seconds: None,
        seed,
        only: None,
        crashes: PathBuf::from("fuzz-crashes"),
    };
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut i = 0;
    while i < args.len() {
        let value = args.get(i + 1).cloned().unwrap_or_default();
        match args[i].as_str() {
            "--inputs" => options.inputs = value.parse().ok(),
            "--seconds" => options.seconds = value.parse().ok(),
            "--seed" => options.seed = value.parse().unwrap_or(options.seed),
            "--only" if targets.contains(&value.as_str()) => options.only = Some(value),
            "--crashes" => options.crashes = PathBuf::from(value),
            other => {
                eprintln!("{name}: unknown option {other}; see examples/{name}.rs");
                std::process::exit(2);
            }
        }
        i += 2;
    }
    if options.inputs.is_none() && options.seconds.is_none() {
        options.inputs = Some(100_000);
    }
    options.seed |= 1;
    options
}

/// The seed files: the PLY files of tests/fixtures/format and data/, in name order.
pub fn seed_files() -> Vec<PathBuf> {
    let mut paths: Vec<PathBuf> = Vec::new();
    for dir in ["tests/fixtures/format", "data"] {
        if let Ok(entries) = std::fs::read_dir(dir) {
            paths.extend(
                entries
                    .flatten()
                    .map(|e| e.path())
                    .filter(|p| p.extension().is_some_and(|e| e == "ply")),
            );
        }
    }
    paths.sort();
    paths
}

/// Where a PLY header ends (just past `end_header\n`), if it does.
pub fn header_end(bytes: &[u8]) -> Option<usize> {
    const END: &[u8] = b"end_header\n";
    bytes
        .windows(END.len())
        .position(|w| w == END)
        .map(|p| p + END.len())
}
