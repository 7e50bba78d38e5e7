//! Fuzzing the PLY loader, its metadata parser and the code that reads a loaded cloud (axes,
//! ticks, hover read-outs): a std-only mutation harness, no nightly toolchain needed.
//!
//! Seeds are the format fixtures (tests/fixtures/format/*.ply) and data/*.ply, cut to their first
//! 64 points so each input is small, plus a few generic PLYs made here (ascii and binary, big
//! endian too). Each input is one seed with one to four mutations: bytes flipped, set to edge
//! values, inserted or deleted; header lines deleted, duplicated, swapped or cut; the vertex count
//! changed; a float of the body set to NaN, infinity or just outside its range; the file cut
//! short; or a value of the `loudscape-meta` JSON replaced (edge numbers, equal ends, wrong
//! types, long strings, keys removed), the JSON written back as one comment line.
//!
//! Every input is loaded with `loudscape::data::cloud::load_from_bytes`. A panic is a crash: the
//! input is saved under `fuzz-crashes/` (or `--crashes DIR`) and counted. A cloud that loads must
//! satisfy the format's invariants (docs/FORMAT.md): finite coordinates, x, y, z in [-1, 1] and
//! scalar, hp in [0, 1] (with the reader's rounding slack), bounds that hold every point, axes
//! that map values; and its axes' ticks, labels and read-outs must come out without a panic and
//! in range. A broken invariant counts as a crash too, and so does an amplification: an input
//! that takes more memory than 32 MiB plus 64 bytes per input byte, or more than 2 s (10 s in the
//! debug build), while it loads and is checked (examples/fuzz_common/mod.rs).
//!
//! Run: `cargo run --release --example fuzz_ply -- [--inputs N | --seconds S] [--seed K]`
//! (`make fuzz N=...` in release; `make test` runs a few seconds of it in the debug build, with
//! overflow checks). Exit status 1 when anything crashed.

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use loudscape::data::axes::Axis;
use loudscape::data::cloud::{self, FORMAT_VERSION, POINT_BYTES, PointCloud, RANGE_EPSILON};
use loudscape::view::pick;
use serde_json::Value;

/// Set while an input is loaded and checked: panics there are crashes, elsewhere bugs of the
/// harness, reported as usual.
static IN_LOAD: AtomicBool = AtomicBool::new(false);

#[path = "fuzz_common/mod.rs"]
mod fuzz_common;
use fuzz_common::{Counting, Limits, Rng, header_end};

/// Every allocation counted: an input's peak memory is checked against [`Limits`].
#[global_allocator]
static ALLOCATOR: Counting = Counting;

/// A file cut to its first `keep` points, the vertex count (and the meta's point_count) updated.
fn shortened(bytes: &[u8], keep: usize) -> Option<Vec<u8>> {
    let end = header_end(bytes)?;
    let header = std::str::from_utf8(&bytes[..end]).ok()?;
    let count: usize = header
        .lines()
        .find_map(|l| l.strip_prefix("element vertex "))?
        .trim()
        .parse()
        .ok()?;
    let keep = keep.min(count);
    let mut out = String::new();
    for line in header.lines() {
        if line.starts_with("element vertex ") {
            out.push_str(&format!("element vertex {keep}\n"));
        } else {
            let line = line.replace(
                &format!("\"point_count\":{count}"),
                &format!("\"point_count\":{keep}"),
            );
            out.push_str(&line);
            out.push('\n');
        }
    }
    let mut file = out.into_bytes();
    let body = &bytes[end..];
    file.extend_from_slice(&body[..(keep * POINT_BYTES).min(body.len())]);
    Some(file)
}

fn seeds() -> Vec<Vec<u8>> {
    let paths = fuzz_common::seed_files();
    let mut seeds: Vec<Vec<u8>> = paths
        .iter()
        .filter_map(|p| std::fs::read(p).ok())
        .filter_map(|bytes| shortened(&bytes, 64))
        .collect();
    let ascii = "ply\nformat ascii 1.0\ncomment made by fuzz_ply\nelement vertex 3\n\
                 property float x\nproperty float y\nproperty double z\nproperty uchar red\n\
                 element face 1\nproperty list uchar int vertex_indices\nend_header\n\
                 0 0 0 255\n1.5 -2 3e3 0\n-7 4 0.25 12\n3 0 1 2\n";
    seeds.push(ascii.as_bytes().to_vec());
    for (format, to_bytes) in [
        (
            "binary_little_endian",
            f32::to_le_bytes as fn(f32) -> [u8; 4],
        ),
        ("binary_big_endian", f32::to_be_bytes as fn(f32) -> [u8; 4]),
    ] {
        let mut file = format!(
            "ply\nformat {format} 1.0\nelement vertex 4\nproperty float x\nproperty float y\n\
             property float z\nend_header\n"
        )
        .into_bytes();
        for v in [0.0, 0.0, 0.0, 1.0, 2.0, 3.0, -1e30, 5.0, 5.0, 7.0, 7.0, 7.0] {
            file.extend_from_slice(&to_bytes(v));
        }
        seeds.push(file);
    }
    seeds
}

/// The meta JSON of a file (v1: one `loudscape-meta` line; v2: its numbered parts joined).
fn meta_json(header: &str) -> Option<String> {
    let mut parts = String::new();
    for line in header.lines() {
        if let Some(json) = line.strip_prefix("comment loudscape-meta ") {
            return Some(json.to_owned());
        }
        if let Some(rest) = line.strip_prefix("comment loudscape-meta-v2 ") {
            let (_, json) = rest.split_once(' ')?;
            parts.push_str(json);
        }
    }
    (!parts.is_empty()).then_some(parts)
}

const EDGE_NUMBERS: [f64; 16] = [
    0.0,
    -0.0,
    1.0,
    -1.0,
    1e38,
    -1e38,
    3.4e38,
    1e308,
    -1e308,
    f64::MAX,
    f64::MIN_POSITIVE,
    5e-324,
    1e-30,
    4294967296.0,
    -2147483649.0,
    1e15,
];

/// A replacement for a JSON value: an edge number, another type, a long or odd string.
fn odd_value(rng: &mut Rng, old: &Value) -> Value {
    match rng.below(10) {
        0 => Value::Null,
        1 => Value::Bool(rng.chance(2)),
        2 => Value::String("x".repeat(rng.below(5000))),
        3 => Value::String("\u{0}\n\"\\ é 漢 \u{fffd}".into()),
        4 => Value::Array(vec![old.clone(); rng.below(4)]),
        5 => serde_json::json!({ "min": 1, "max": 1 }),
        6 => Value::from(u64::MAX - rng.below(3) as u64),
        7 => Value::from(-(rng.below(1 << 20) as i64)),
        _ => serde_json::Number::from_f64(*rng.pick(&EDGE_NUMBERS))
            .map(Value::Number)
            .unwrap_or(Value::Null),
    }
}

/// Changes one value somewhere in `value` (depth first, at random).
fn mutate_json(rng: &mut Rng, value: &mut Value, depth: usize) {
    match value {
        Value::Object(map) if !map.is_empty() && depth < 8 => {
            let keys: Vec<String> = map.keys().cloned().collect();
            let key = rng.pick(&keys).clone();
            match rng.below(8) {
                0 => {
                    map.remove(&key);
                }
                1 => {
                    let old = map[&key].clone();
                    map.insert(key, odd_value(rng, &old));
                }
                2 if key == "axes" || map.contains_key("min") => {
                    // Equal ends, or ends at the edges of f64.
                    if let (Some(min), true) = (map.get("min").cloned(), map.contains_key("max")) {
                        map.insert("max".into(), min);
                    }
                }
                _ => mutate_json(rng, map.get_mut(&key).expect("key"), depth + 1),
            }
        }
        Value::Array(items) if !items.is_empty() && depth < 8 => match rng.below(5) {
            0 => {
                items.remove(rng.below(items.len()));
            }
            1 => {
                let item = items[rng.below(items.len())].clone();
                items.push(item);
            }
            _ => {
                let i = rng.below(items.len());
                mutate_json(rng, &mut items[i], depth + 1);
            }
        },
        other => *other = odd_value(rng, other),
    }
}

/// One mutation of `bytes`, in place.
fn mutate(rng: &mut Rng, bytes: &mut Vec<u8>) {
    let end = header_end(bytes);
    match rng.below(9) {
        // Bytes: flipped, set to edge values, inserted, deleted.
        0 if !bytes.is_empty() => {
            let i = rng.below(bytes.len());
            bytes[i] ^= 1 << rng.below(8);
        }
        1 if !bytes.is_empty() => {
            let i = rng.below(bytes.len());
            bytes[i] = *rng.pick(&[0u8, 0xff, b'\n', b' ', b'-', b'9', b'{', b'"', 0x80, b'\r']);
        }
        2 => {
            let i = rng.below(bytes.len() + 1);
            let run = rng.below(16) + 1;
            let byte = rng.next() as u8;
            bytes.splice(i..i, std::iter::repeat_n(byte, run));
        }
        3 if !bytes.is_empty() => {
            let i = rng.below(bytes.len());
            let j = (i + rng.below(64) + 1).min(bytes.len());
            bytes.drain(i..j);
        }
        // Header lines: deleted, duplicated, swapped, the vertex count changed.
        4 | 5 => {
            let Some(end) = end else { return };
            let Ok(header) = std::str::from_utf8(&bytes[..end]) else {
                return;
            };
            let mut lines: Vec<String> = header.lines().map(str::to_owned).collect();
            let i = rng.below(lines.len());
            match rng.below(5) {
                0 => {
                    lines.remove(i);
                }
                1 => {
                    let line = lines[i].clone();
                    lines.insert(i, line);
                }
                2 => {
                    let j = rng.below(lines.len());
                    lines.swap(i, j);
                }
                3 => {
                    let cut = rng.below(lines[i].len() + 1);
                    let cut = lines[i].floor_char_boundary(cut);
                    lines[i].truncate(cut);
                }
                _ => {
                    if let Some(line) = lines.iter_mut().find(|l| l.starts_with("element vertex")) {
                        let n: i64 = line[14..].trim().parse().unwrap_or(0);
                        let new = *rng.pick(&[
                            0,
                            1,
                            n.saturating_sub(1),
                            n.saturating_add(1),
                            n.saturating_mul(2),
                            -1,
                            i64::from(u32::MAX),
                            i64::MAX,
                        ]);
                        *line = format!("element vertex {new}");
                    }
                }
            }
            let mut out = lines.join("\n").into_bytes();
            out.push(b'\n');
            out.extend_from_slice(&bytes[end..]);
            *bytes = out;
        }
        // The metadata: one JSON value changed, written back as one line.
        6 | 7 => {
            let Some(end) = end else { return };
            let Ok(header) = std::str::from_utf8(&bytes[..end]) else {
                return;
            };
            let Some(json) = meta_json(header) else {
                return;
            };
            let Ok(mut value) = serde_json::from_str::<Value>(&json) else {
                return;
            };
            if let Some(object) = value.as_object_mut()
                && rng.chance(2)
            {
                // This build's version, so the mutation reaches the parser's later checks.
                object.insert("format_version".into(), Value::from(FORMAT_VERSION));
            }
            mutate_json(rng, &mut value, 0);
            let mut out = String::new();
            let mut placed = false;
            for line in header.lines() {
                if line.starts_with("comment loudscape-meta") {
                    if !placed {
                        out.push_str("comment loudscape-meta ");
                        out.push_str(&value.to_string().replace('\n', "\\n"));
                        out.push('\n');
                        placed = true;
                    }
                } else {
                    out.push_str(line);
                    out.push('\n');
                }
            }
            let mut file = out.into_bytes();
            file.extend_from_slice(&bytes[end..]);
            *bytes = file;
        }
        // The body: a float at or just past the edges; or the file cut short.
        _ => {
            let Some(end) = end else { return };
            if rng.chance(3) {
                let cut = end + rng.below(bytes.len() - end + 1);
                bytes.truncate(cut);
                return;
            }
            let floats = (bytes.len() - end) / 4;
            if floats == 0 {
                return;
            }
            let at = end + 4 * rng.below(floats);
            let v = *rng.pick(&[
                f32::NAN,
                f32::INFINITY,
                -f32::INFINITY,
                1.0 + 2.0 * RANGE_EPSILON,
                -1.0 - 2.0 * RANGE_EPSILON,
                1.0,
                -1.0,
                0.0,
                f32::MAX,
                f32::MIN_POSITIVE,
            ]);
            bytes[at..at + 4].copy_from_slice(&v.to_le_bytes());
        }
    }
}

/// What a loaded cloud must satisfy; `Err` names the broken invariant.
fn check_cloud(cloud: &PointCloud) -> Result<(), String> {
    let slack = RANGE_EPSILON;
    for (i, p) in cloud.points.iter().enumerate() {
        let [x, y, z] = p.position;
        for (name, v, lo, hi) in [
            ("x", x, -1.0, 1.0),
            ("y", y, -1.0, 1.0),
            ("z", z, -1.0, 1.0),
            ("scalar", p.scalar, 0.0, 1.0),
            ("hp", p.hp, 0.0, 1.0),
        ] {
            if !(v.is_finite() && v >= lo - slack && v <= hi + slack) {
                return Err(format!("point {i}: {name} = {v} is outside [{lo}, {hi}]"));
            }
        }
    }
    if let Some(count) = cloud.meta.point_count
        && count != cloud.points.len() as u64
    {
        return Err(format!(
            "point_count {count} accepted for {} points",
            cloud.points.len()
        ));
    }
    if !cloud.points.is_empty() {
        let (min, max) = (cloud.bounds.min, cloud.bounds.max);
        for p in &cloud.points {
            let v = glam::Vec3::from(p.position);
            if !(v.cmpge(min).all() && v.cmple(max).all()) {
                return Err(format!("bounds {min}..{max} miss a point at {v}"));
            }
        }
    }
    for (name, axis) in cloud.meta.axes.named() {
        if let Some(problem) = axis.problem() {
            return Err(format!("axis {name} accepted with a problem: {problem}"));
        }
        check_axis(name, axis)?;
    }
    // Hover read-outs of a few points and of the box corners: a number, the file's unit and a
    // note name, so short whatever the number.
    let longest_unit = cloud
        .meta
        .axes
        .named()
        .iter()
        .map(|(_, a)| a.unit.len())
        .max();
    for p in cloud.points.iter().take(8) {
        for reading in pick::point_readings(&cloud.meta.axes, p) {
            if reading.value.len() > 100 + longest_unit.unwrap_or(0) {
                return Err(format!(
                    "read-out of {} is {} bytes: {}",
                    reading.name,
                    reading.value.len(),
                    reading.value.chars().take(80).collect::<String>()
                ));
            }
        }
    }
    for corner in [cloud.bounds.min, cloud.bounds.max] {
        let _ = pick::position_readings(&cloud.meta.axes, corner);
    }
    for x in [-1.0, 0.0, 0.5, 1.0] {
        let _ = pick::song_at(&cloud.meta.songs, x);
    }
    Ok(())
}

fn check_axis(name: &str, axis: &Axis) -> Result<(), String> {
    for n in [1, 2, 5, 8, 12] {
        let ticks = axis.ticks(n);
        if axis.ticks.is_none() && ticks.len() > n {
            return Err(format!(
                "axis {name}: {} ticks for at most {n}",
                ticks.len()
            ));
        }
        if let Some(t) = ticks
            .iter()
            .find(|t| axis.ticks.is_none() && !(-1.0..=1.0).contains(&t.at))
        {
            return Err(format!("axis {name}: tick at {}", t.at));
        }
    }
    for t in [-1.0, -0.25, 0.0, 0.75, 1.0] {
        let value = axis.value_at(t);
        if !value.is_finite() && axis.scale == loudscape::data::axes::AxisScale::Linear {
            return Err(format!("axis {name}: value at {t} is {value}"));
        }
        let _ = axis.format_value(value);
        let _ = axis.normalized_of(value);
        let _ = axis.value_at_unit((t + 1.0) * 0.5);
        let _ = loudscape::data::axes::note_name(value);
    }
    Ok(())
}

#[derive(Default)]
struct Tally {
    run: u64,
    accepted: u64,
    crashes: u64,
    /// Rejections whose message spans lines or runs past 300 characters (the CLI cuts them).
    long_messages: u64,
}

fn save_crash(dir: &Path, input: &[u8], why: &str, tally: &Tally) {
    let _ = std::fs::create_dir_all(dir);
    let path = dir.join(format!("crash-{:06}.ply", tally.crashes));
    let _ = std::fs::write(&path, input);
    let why: String = why.chars().take(300).collect();
    eprintln!("fuzz_ply: crash saved to {}: {why}", path.display());
}

fn main() {
    let options = fuzz_common::options("fuzz_ply", 0x5eed_1234_abcd_0001, &[]);
    let seeds = seeds();
    if seeds.is_empty() {
        eprintln!("fuzz_ply: no seeds found (run from the repository root)");
        std::process::exit(2);
    }
    // Panics are counted and saved, not printed one by one.
    let panic_message = std::sync::Arc::new(std::sync::Mutex::new(String::new()));
    let sink = panic_message.clone();
    let default_hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        if IN_LOAD.load(Ordering::Relaxed) {
            *sink.lock().unwrap_or_else(|e| e.into_inner()) = info.to_string();
        } else {
            default_hook(info);
        }
    }));
    let mut rng = Rng(options.seed);
    let limits = Limits::default_for_build();
    let mut tally = Tally::default();
    let start = Instant::now();
    let deadline = options.seconds.map(|s| start + Duration::from_secs_f64(s));
    let path = Path::new("fuzz.ply");
    loop {
        if options.inputs.is_some_and(|n| tally.run >= n) {
            break;
        }
        if tally.run % 256 == 0 && deadline.is_some_and(|d| Instant::now() >= d) {
            break;
        }
        let mut input = rng.pick(&seeds).clone();
        for _ in 0..=rng.below(4) {
            mutate(&mut rng, &mut input);
        }
        tally.run += 1;
        IN_LOAD.store(true, Ordering::Relaxed);
        let watch = limits.start();
        let outcome = catch_unwind(AssertUnwindSafe(|| {
            cloud::load_from_bytes(&input, path).map(|cloud| check_cloud(&cloud))
        }));
        IN_LOAD.store(false, Ordering::Relaxed);
        if let Err(why) = watch.check(&limits, input.len()) {
            save_crash(&options.crashes, &input, &why, &tally);
            tally.crashes += 1;
            continue;
        }
        match outcome {
            Ok(Ok(Ok(()))) => tally.accepted += 1,
            Ok(Err(rejected)) => {
                let message = rejected.to_string();
                if message.contains('\n') || message.chars().count() > 300 {
                    tally.long_messages += 1;
                }
            }
            Ok(Ok(Err(broken))) => {
                save_crash(&options.crashes, &input, &broken, &tally);
                tally.crashes += 1;
            }
            Err(_) => {
                let message = panic_message.lock().map(|m| m.clone()).unwrap_or_default();
                save_crash(
                    &options.crashes,
                    &input,
                    &format!("panic: {message}"),
                    &tally,
                );
                tally.crashes += 1;
            }
        }
    }
    let seconds = start.elapsed().as_secs_f64();
    let profile = if cfg!(debug_assertions) {
        "debug, overflow checks"
    } else {
        "release"
    };
    println!(
        "fuzz_ply ({profile}): {} inputs in {seconds:.1} s ({:.0} per second), {} accepted, {} \
         rejected ({} with a long or multi-line message), {} crashes, seed {}",
        tally.run,
        tally.run as f64 / seconds.max(1e-9),
        tally.accepted,
        tally.run - tally.accepted - tally.crashes,
        tally.long_messages,
        tally.crashes,
        options.seed
    );
    if tally.crashes > 0 {
        std::process::exit(1);
    }
}
