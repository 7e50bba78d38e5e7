//! Load benchmark: writes a 20-million-point loudscape file to the system temp folder, loads it
//! three times with `loudscape::data::cloud::load`, and prints the median wall time and the peak
//! resident memory (VmHWM from /proc/self/status, Linux only) against the file size.
//!
//! Run with `cargo run --release --example bench_load [POINTS]`.

use std::io::{BufWriter, Write};
use std::time::Instant;

use loudscape::data::cloud::{self, Point};

fn peak_rss_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

fn main() -> anyhow::Result<()> {
    let count: u64 = match std::env::args().nth(1) {
        Some(arg) => arg.parse()?,
        None => 20_000_000,
    };
    let path = std::env::temp_dir().join(format!("loudscape-bench-{}.ply", std::process::id()));
    let meta = serde_json::json!({
        "format_version": 1,
        "mode": "song",
        "point_count": count,
        "axes": {
            "x": {"label": "time", "unit": "s", "min": 0.0, "max": 240.0, "scale": "linear"},
            "y": {"label": "frequency", "unit": "Hz", "min": 20.0, "max": 20000.0, "scale": "log"},
            "z": {"label": "level", "unit": "dB", "min": -80.0, "max": 0.0, "scale": "linear"},
            "scalar": {"label": "level", "unit": "dB", "min": -80.0, "max": 0.0},
            "hp": {"label": "harmonic ratio", "unit": "", "min": 0.0, "max": 1.0}
        }
    });

    // Written in chunks so the writer does not raise the peak memory measured for loading.
    let started = Instant::now();
    {
        let mut writer = BufWriter::with_capacity(1 << 20, std::fs::File::create(&path)?);
        cloud::write_header(&mut writer, count, Some(&meta))?;
        let mut chunk = Vec::with_capacity(1 << 16);
        let mut i = 0u64;
        while i < count {
            chunk.clear();
            while chunk.len() < chunk.capacity() && i < count {
                let t = (i as f64 / count as f64) as f32;
                let h = (i.wrapping_mul(2_654_435_761) % 1_000_003) as f32 / 1_000_003.0;
                chunk.push(Point {
                    position: [t * 2.0 - 1.0, h * 2.0 - 1.0, (1.0 - h) * 2.0 - 1.0],
                    scalar: h,
                    hp: 1.0 - t,
                });
                i += 1;
            }
            cloud::write_points(&mut writer, &chunk)?;
        }
        writer.flush()?;
    }
    let file_size = std::fs::metadata(&path)?.len();
    println!(
        "wrote {count} points, {:.1} MB, in {:.2} s",
        file_size as f64 / 1e6,
        started.elapsed().as_secs_f64()
    );
    let rss_before = peak_rss_bytes();

    let mut times = Vec::new();
    for run in 1..=3 {
        let started = Instant::now();
        let loaded = cloud::load(&path)?;
        let seconds = started.elapsed().as_secs_f64();
        println!(
            "load {run}: {seconds:.3} s ({:.0} MB/s), {} points",
            file_size as f64 / 1e6 / seconds,
            loaded.len()
        );
        times.push(seconds);
        drop(loaded);
    }
    times.sort_by(f64::total_cmp);
    let median = times[1];
    println!(
        "median load time: {median:.3} s ({:.0} MB/s)",
        file_size as f64 / 1e6 / median
    );
    match (peak_rss_bytes(), rss_before) {
        (Some(peak), Some(before)) => println!(
            "peak RSS (VmHWM): {:.1} MB = {:.2}x the file size ({:.1} MB before loading)",
            peak as f64 / 1e6,
            peak as f64 / file_size as f64,
            before as f64 / 1e6
        ),
        _ => println!("peak RSS: not available (no /proc/self/status)"),
    }
    std::fs::remove_file(&path)?;
    Ok(())
}
