//! Fuzzing beyond the in-memory loader (examples/fuzz_ply.rs mutates bytes): inputs built from
//! the formats' structure, each with an oracle, a per-input memory and time limit
//! (examples/fuzz_common/mod.rs: an amplification is a finding like a crash).
//!
//! - `parts`: version-2 metadata (`comment loudscape-meta-v2 I/N CHUNK`) made from the seeds'
//!   JSON, split at random places (inside `\u0020` escapes and multi-byte escapes too) into 1 to
//!   300 parts; then left whole (it must load, with the same JSON) or changed in its structure:
//!   two parts swapped, one dropped or repeated, a wrong I or N, a leading zero, two spaces
//!   between words, a space, tab, control or non-ASCII byte in a chunk, an empty chunk, a part
//!   after `end_header`'s place, both layouts at once. A changed one must be refused.
//! - `stream`: a seed cut or with bytes flipped, read by `load_from_reader` with no length, in
//!   pieces of 1 to 4096 bytes, and by `load_from_bytes`: both accept (the same points and
//!   metadata) or both refuse. One in 64 also through `load` on a file.
//! - `npy`: arrays written by the writer with random dimensions, then their header changed
//!   (`descr`, `shape`, `fortran_order`, the version byte, the header length) or the data cut:
//!   `parse` must accept exactly the unchanged ones, with the same values.
//! - `sidecar`: `FIELD.npy.json` descriptions, right or with `dims`, `dtype`, `fields`,
//!   `box_min`/`box_max` changed (other sizes, types, NaN strings, deep nesting): a right one
//!   gives its box, a changed one is refused or (for a box still valid) gives that box.
//!
//! Run: `cargo run --release --example fuzz_formats -- [--inputs N | --seconds S] [--seed K]
//! [--only parts|stream|npy|sidecar]`; `make fuzz` runs it with fuzz_ply. Crashing inputs are
//! saved under `fuzz-crashes/`. Exit status 1 on any finding.

use std::io::Read;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::Path;
use std::time::{Duration, Instant};

use glam::UVec3;
use loudscape::data::cloud::{self, META_CHUNK_BYTES, PointCloud};
use loudscape::data::npy;
use serde_json::Value;

#[path = "fuzz_common/mod.rs"]
mod fuzz_common;
use fuzz_common::{Counting, Limits, Rng, header_end};

#[global_allocator]
static ALLOCATOR: Counting = Counting;

const TARGETS: [&str; 4] = ["parts", "stream", "npy", "sidecar"];

/// Inputs each target's code accepted (the rest it refused), for the summary.
static ACCEPTED: [std::sync::atomic::AtomicU64; 4] =
    [const { std::sync::atomic::AtomicU64::new(0) }; 4];

fn accepted(target: usize) {
    ACCEPTED[target].fetch_add(1, std::sync::atomic::Ordering::Relaxed);
}

/// The loudscape seeds: files and their metadata JSON (format fixtures and data/, cut to 64
/// points).
struct Seed {
    bytes: Vec<u8>,
    meta: Option<Value>,
    /// The header's lines before the metadata and after it (`end_header` included), and the
    /// body.
    before: Vec<String>,
    after: Vec<String>,
    body: Vec<u8>,
}

fn seeds() -> Vec<Seed> {
    let paths = fuzz_common::seed_files();
    let mut seeds = Vec::new();
    for path in paths {
        let Ok(bytes) = std::fs::read(&path) else {
            continue;
        };
        let Ok(cloud) = cloud::load_from_bytes(&bytes, &path) else {
            continue;
        };
        // Rewritten with 64 points at most, in version 2: the header is known exactly.
        let points = &cloud.points[..cloud.points.len().min(64)];
        let meta = (!cloud.meta.raw.is_null()).then(|| {
            let mut meta = cloud.meta.raw.clone();
            if meta.get("point_count").is_some() {
                meta["point_count"] = Value::from(points.len());
            }
            meta
        });
        let mut file = Vec::new();
        if cloud::write(&mut file, points, meta.as_ref()).is_err() {
            continue;
        }
        let Some(end) = header_end(&file) else {
            continue;
        };
        let header = String::from_utf8_lossy(&file[..end]).into_owned();
        let lines: Vec<&str> = header.lines().collect();
        let first_part = lines
            .iter()
            .position(|l| l.starts_with("comment loudscape-meta"));
        let last_part = lines
            .iter()
            .rposition(|l| l.starts_with("comment loudscape-meta"));
        let (before, after) = match (first_part, last_part) {
            (Some(a), Some(b)) => (lines[..a].to_vec(), lines[b + 1..].to_vec()),
            _ => (lines.clone(), Vec::new()),
        };
        seeds.push(Seed {
            body: file[end..].to_vec(),
            bytes: file,
            meta,
            before: before.iter().map(|s| s.to_string()).collect(),
            after: after.iter().map(|s| s.to_string()).collect(),
        });
    }
    seeds
}

/// The version-2 text of `meta` (as the writer makes it: spaces as `\u0020`, non-ASCII as
/// `\uXXXX`).
fn v2_text(meta: &Value) -> String {
    let mut file = Vec::new();
    cloud::write_header(&mut file, 0, Some(meta)).expect("write to memory");
    let header = String::from_utf8_lossy(&file).into_owned();
    header
        .lines()
        .filter_map(|l| l.strip_prefix("comment loudscape-meta-v2 "))
        .filter_map(|rest| rest.split_once(' ').map(|(_, chunk)| chunk.to_string()))
        .collect()
}

/// `text` cut into `n` chunks at random places (none empty).
fn split(rng: &mut Rng, text: &str, n: usize) -> Vec<String> {
    let n = n.clamp(1, text.len().max(1));
    let mut cuts: Vec<usize> = (0..n - 1).map(|_| 1 + rng.below(text.len() - 1)).collect();
    cuts.sort_unstable();
    cuts.dedup();
    let mut chunks = Vec::new();
    let mut start = 0;
    for cut in cuts.into_iter().chain(std::iter::once(text.len())) {
        if cut > start {
            chunks.push(text[start..cut].to_string());
            start = cut;
        }
    }
    chunks
}

/// A `parts` input: the file, and whether it must load (with `meta`).
fn parts_input(rng: &mut Rng, seed: &Seed) -> Option<(Vec<u8>, bool)> {
    let meta = seed.meta.as_ref()?;
    let text = v2_text(meta);
    let wanted = match rng.below(4) {
        0 => 1,
        1 => 1 + rng.below(8),
        2 => 1 + rng.below(300),
        _ => text.len().div_ceil(META_CHUNK_BYTES).max(1),
    };
    let chunks = split(rng, &text, wanted);
    let mut lines: Vec<String> = chunks
        .iter()
        .enumerate()
        .map(|(i, c)| format!("comment loudscape-meta-v2 {}/{} {c}", i + 1, chunks.len()))
        .collect();
    let n = lines.len();
    let intact = rng.chance(3);
    if !intact {
        let i = rng.below(n);
        match rng.below(12) {
            0 if n > 1 => {
                let j = (i + 1 + rng.below(n - 1)) % n;
                lines.swap(i, j);
            }
            1 if n > 1 => {
                lines.remove(i);
            }
            2 => {
                let line = lines[i].clone();
                lines.insert(i, line);
            }
            3 => {
                let wrong = *rng.pick(&[0, n + 1, n + 7, usize::MAX]);
                lines[i] = format!("comment loudscape-meta-v2 {}/{wrong} {}", i + 1, chunks[i]);
            }
            4 => {
                let wrong = *rng.pick(&[0, i + 2, n + 1]);
                lines[i] = format!("comment loudscape-meta-v2 {wrong}/{n} {}", chunks[i]);
            }
            5 => lines[i] = format!("comment loudscape-meta-v2 0{}/{n} {}", i + 1, chunks[i]),
            6 => lines[i] = lines[i].replacen("loudscape-meta-v2 ", "loudscape-meta-v2  ", 1),
            7 => {
                let odd = *rng.pick(&[" ", "\t", "\u{1}", "\u{7f}", "é", "\u{fffd}"]);
                let chunk = &chunks[i];
                let at = rng.below(chunk.len() + 1);
                let at = chunk.floor_char_boundary(at);
                lines[i] = format!(
                    "comment loudscape-meta-v2 {}/{n} {}{odd}{}",
                    i + 1,
                    &chunk[..at],
                    &chunk[at..]
                );
            }
            8 => lines[i] = format!("comment loudscape-meta-v2 {}/{n} ", i + 1),
            9 => lines.push(format!("comment loudscape-meta {}", meta)),
            10 => {
                // A part placed after the elements: still a header comment, still a part; but
                // then parts 1..n must still come in order, so make it out of order.
                if n > 1 {
                    let moved = lines.remove(0);
                    lines.push(moved);
                } else {
                    lines[0] = format!("comment loudscape-meta-v2 1/2 {}", chunks[0]);
                }
            }
            _ => {
                // Split a part in two where it stood, numbering unchanged: a part too many.
                let chunk = &chunks[i];
                if chunk.len() > 1 {
                    let at = 1 + rng.below(chunk.len() - 1);
                    lines[i] = format!("comment loudscape-meta-v2 {}/{n} {}", i + 1, &chunk[..at]);
                    lines.insert(
                        i + 1,
                        format!("comment loudscape-meta-v2 {}/{n} {}", i + 2, &chunk[at..]),
                    );
                } else {
                    lines.remove(i);
                    if lines.is_empty() {
                        lines.push("comment loudscape-meta-v2 1/1 {".to_string());
                    }
                }
            }
        }
    }
    let mut header: Vec<String> = seed.before.clone();
    header.extend(lines);
    header.extend(seed.after.iter().cloned());
    let mut file = header.join("\n").into_bytes();
    file.push(b'\n');
    file.extend_from_slice(&seed.body);
    Some((file, intact))
}

/// A reader that hands out its bytes in pieces of random length.
struct Pieces<'a> {
    bytes: &'a [u8],
    rng: Rng,
}

impl Read for Pieces<'_> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = (1 + self.rng.below(4096))
            .min(buf.len())
            .min(self.bytes.len());
        buf[..n].copy_from_slice(&self.bytes[..n]);
        self.bytes = &self.bytes[n..];
        Ok(n)
    }
}

fn same_cloud(a: &PointCloud, b: &PointCloud) -> bool {
    // Bitwise: NaN never loads, and -0.0 must stay -0.0.
    let bits = |c: &PointCloud| -> Vec<u32> {
        c.points
            .iter()
            .flat_map(|p| [p.position[0], p.position[1], p.position[2], p.scalar, p.hp])
            .map(f32::to_bits)
            .collect()
    };
    bits(a) == bits(b) && a.meta == b.meta
}

fn stream_input(rng: &mut Rng, seed: &Seed) -> Vec<u8> {
    let mut bytes = seed.bytes.clone();
    for _ in 0..=rng.below(3) {
        match rng.below(4) {
            0 => bytes.truncate(rng.below(bytes.len() + 1)),
            1 if !bytes.is_empty() => {
                let i = rng.below(bytes.len());
                bytes[i] ^= 1 << rng.below(8);
            }
            2 => {
                let i = rng.below(bytes.len() + 1);
                let run = rng.below(64) + 1;
                bytes.splice(i..i, std::iter::repeat_n(rng.next() as u8, run));
            }
            _ => {}
        }
    }
    bytes
}

/// The stream oracle: the same answer whatever the reader.
fn check_stream(rng: &mut Rng, input: &[u8], scratch: &Path, file: bool) -> Result<(), String> {
    let path = Path::new("fuzz.ply");
    let known = cloud::load_from_bytes(input, path);
    let streamed = cloud::load_from_reader(
        Pieces {
            bytes: input,
            rng: Rng(rng.next() | 1),
        },
        path,
        None,
    );
    compare("bytes", &known, "a stream of unknown length", &streamed)?;
    if known.is_ok() {
        accepted(1);
    }
    if file {
        let on_disk = scratch.join("fuzz.ply");
        std::fs::write(&on_disk, input).map_err(|e| format!("harness: {e}"))?;
        let loaded = cloud::load(&on_disk).map(|mut c| {
            c.path = path.to_owned();
            c
        });
        compare("bytes", &known, "a file", &loaded)?;
    }
    Ok(())
}

fn compare(
    a_name: &str,
    a: &Result<PointCloud, cloud::CloudError>,
    b_name: &str,
    b: &Result<PointCloud, cloud::CloudError>,
) -> Result<(), String> {
    match (a, b) {
        (Ok(a), Ok(b)) if same_cloud(a, b) => Ok(()),
        (Ok(_), Ok(_)) => Err(format!("{a_name} and {b_name} loaded different clouds")),
        (Err(_), Err(_)) => Ok(()),
        (Ok(_), Err(e)) => Err(format!("{a_name} loaded, {b_name} refused: {e}")),
        (Err(e), Ok(_)) => Err(format!("{a_name} refused ({e}), {b_name} loaded")),
    }
}

/// An `npy` input: the bytes and, when unchanged, the fields they hold.
/// An array's dimensions and fields.
type Fields = (UVec3, Vec<Vec<f32>>);

/// A check of one input, run under the limits.
type Check = Box<dyn FnOnce(&mut Rng) -> Result<(), String>>;

fn npy_input(rng: &mut Rng) -> (Vec<u8>, Option<Fields>) {
    let dims = UVec3::new(
        1 + rng.below(9) as u32,
        1 + rng.below(9) as u32,
        1 + rng.below(9) as u32,
    );
    let voxels = (dims.x * dims.y * dims.z) as usize;
    let fields: Vec<Vec<f32>> = (0..1 + rng.below(3))
        .map(|_| {
            (0..voxels)
                .map(|_| f32::from_bits(rng.next() as u32))
                .collect()
        })
        .collect();
    let refs: Vec<&[f32]> = fields.iter().map(Vec::as_slice).collect();
    let mut bytes = Vec::new();
    npy::write(&mut bytes, &refs, dims).expect("write to memory");
    if rng.chance(3) {
        return (bytes, Some((dims, fields)));
    }
    let header_len = u16::from_le_bytes([bytes[8], bytes[9]]) as usize;
    let header = String::from_utf8_lossy(&bytes[10..10 + header_len]).into_owned();
    let body = bytes[10 + header_len..].to_vec();
    let new_header = match rng.below(8) {
        0 => {
            let descrs = ["<i4", ">f4", "<f2", "|b1", "<f8", "'<f4"];
            let descr = descrs[rng.below(descrs.len())];
            header.replace("<f4", descr)
        }
        1 => {
            let orders = ["True", "0", "false", ""];
            let order = orders[rng.below(orders.len())];
            header.replace("False", order)
        }
        2 => {
            let shapes = [
                "()",
                "(0, 2, 2)",
                "(2,)",
                "(1, 1, 1, 1, 1)",
                "(99999999999, 99999999999, 99999999999)",
                "(-1, 2, 2)",
                "(2, 2, 2",
                "((2, 2), 2)",
                "(18446744073709551616, 1, 1)",
            ];
            let start = header.find("'shape': ").map_or(0, |i| i + 9);
            let end = header[start..]
                .find(')')
                .map_or(header.len(), |i| start + i + 1);
            format!(
                "{}{}{}",
                &header[..start],
                rng.pick(&shapes),
                &header[end..]
            )
        }
        3 => header.replace("'descr'", "'desc'"),
        4 => header[..rng.below(header.len() + 1)].to_string(),
        _ => header.clone(),
    };
    let mut out = b"\x93NUMPY".to_vec();
    out.push(*rng.pick(&[1u8, 1, 2, 3, 0, 9]));
    out.push(0);
    if out[6] == 1 {
        let len = if rng.chance(4) {
            rng.next() as u16
        } else {
            new_header.len() as u16
        };
        out.extend_from_slice(&len.to_le_bytes());
    } else {
        out.extend_from_slice(&(new_header.len() as u32).to_le_bytes());
    }
    out.extend_from_slice(new_header.as_bytes());
    let cut = if rng.chance(2) {
        rng.below(body.len() + 1)
    } else {
        body.len()
    };
    out.extend_from_slice(&body[..cut]);
    (out, None)
}

fn check_npy(input: &[u8], expected: Option<Fields>) -> Result<(), String> {
    let parsed = npy::parse(input);
    if parsed.is_ok() {
        accepted(2);
    }
    match (parsed, expected) {
        (Ok(got), Some((dims, fields))) => {
            let same = got.dims == dims
                && got.fields.len() == fields.len()
                && got.fields.iter().zip(&fields).all(|(a, b)| {
                    a.iter()
                        .map(|v| v.to_bits())
                        .eq(b.iter().map(|v| v.to_bits()))
                });
            if same {
                Ok(())
            } else {
                Err("the array read back differs from the one written".into())
            }
        }
        (Err(e), Some(_)) => Err(format!("a written array is refused: {e:#}")),
        (Ok(got), None) => {
            let voxels = got.dims.x as usize * got.dims.y as usize * got.dims.z as usize;
            if got.dims.min_element() == 0 || got.fields.iter().any(|f| f.len() != voxels) {
                Err(format!(
                    "accepted with dims {} and wrong field lengths",
                    got.dims
                ))
            } else {
                Ok(())
            }
        }
        (Err(e), None) => {
            let message = format!("{e:#}");
            if message.contains('\n') {
                Err(format!("a message on several lines: {message}"))
            } else {
                Ok(())
            }
        }
    }
}

/// A `sidecar` input: the description's text and the array it goes with; whether it must be
/// accepted as it is.
fn sidecar_input(rng: &mut Rng) -> (String, npy::NpyFields, bool) {
    let dims = UVec3::new(
        2 + rng.below(6) as u32,
        2 + rng.below(6) as u32,
        2 + rng.below(6) as u32,
    );
    let voxels = (dims.x * dims.y * dims.z) as usize;
    let fields = vec![vec![0.5f32; voxels]; 1 + rng.below(2)];
    let names = ["density", "hp_mean"];
    let mut meta = serde_json::json!({
        "dims": [dims.x, dims.y, dims.z],
        "dtype": "<f4",
        "box_min": [-1.0, -1.0, -1.0],
        "box_max": [1.0, 1.0, 1.0],
        "fields": names[..fields.len()],
    });
    let right = rng.chance(3);
    if !right {
        let key = *rng.pick(&["dims", "dtype", "fields", "box_min", "box_max", "other"]);
        let deep = (0..200).fold(Value::from(1), |v, _| Value::Array(vec![v]));
        let value = match rng.below(10) {
            0 => Value::Null,
            1 => serde_json::json!([dims.x + 1, dims.y, dims.z]),
            2 => serde_json::json!([1, 2]),
            3 => serde_json::json!("<f8"),
            4 => serde_json::json!(["NaN", 0, 0]),
            5 => serde_json::json!([1e39, 0, 0]),
            6 => serde_json::json!([-1.0, -1.0, -1.0]),
            7 => deep,
            8 => serde_json::json!([u64::MAX, 1, 1]),
            _ => serde_json::json!({"dims": 1}),
        };
        meta[key] = value;
    }
    let mut text = meta.to_string();
    if !right && rng.chance(5) {
        text.truncate(rng.below(text.len() + 1));
    }
    (
        text,
        npy::NpyFields {
            dims,
            fields,
            dtype: "<f4",
        },
        right,
    )
}

fn check_sidecar(text: &str, array: &npy::NpyFields, right: bool) -> Result<(), String> {
    let result = npy::field_box_of(text, Path::new("f.npy.json"), Path::new("f.npy"), array);
    match (result, right) {
        (Ok((min, max)), _) => {
            accepted(3);
            if min.is_finite() && max.is_finite() && min.cmplt(max).all() {
                Ok(())
            } else {
                Err(format!("an empty or infinite box accepted: {min} {max}"))
            }
        }
        (Err(e), true) => Err(format!("a right description refused: {e:#}")),
        (Err(e), false) => {
            let message = format!("{e:#}");
            if message.contains('\n') {
                Err(format!("a message on several lines: {message}"))
            } else {
                Ok(())
            }
        }
    }
}

#[derive(Default)]
struct Tally {
    run: [u64; 4],
    findings: u64,
}

fn save(dir: &Path, target: &str, input: &[u8], why: &str, findings: u64) {
    let _ = std::fs::create_dir_all(dir);
    let path = dir.join(format!("{target}-{findings:06}.bin"));
    let _ = std::fs::write(&path, input);
    let why: String = why.chars().take(300).collect();
    eprintln!("fuzz_formats: finding saved to {}: {why}", path.display());
}

fn main() {
    let options = fuzz_common::options("fuzz_formats", 0x5eed_f0a7_0000_0001, &TARGETS);
    let seeds = seeds();
    let with_meta: Vec<&Seed> = seeds.iter().filter(|s| s.meta.is_some()).collect();
    if with_meta.is_empty() {
        eprintln!("fuzz_formats: no seeds found (run from the repository root)");
        std::process::exit(2);
    }
    let scratch = std::env::temp_dir().join(format!("loudscape-fuzz-{}", std::process::id()));
    let _ = std::fs::create_dir_all(&scratch);
    std::panic::set_hook(Box::new(|_| {}));
    let limits = Limits::default_for_build();
    let mut rng = Rng(options.seed);
    let mut tally = Tally::default();
    let start = Instant::now();
    let deadline = options.seconds.map(|s| start + Duration::from_secs_f64(s));
    let mut n = 0u64;
    loop {
        if options.inputs.is_some_and(|limit| n >= limit) {
            break;
        }
        if n.is_multiple_of(64) && deadline.is_some_and(|d| Instant::now() >= d) {
            break;
        }
        n += 1;
        let which = match &options.only {
            Some(only) => TARGETS.iter().position(|t| t == only).unwrap_or(0),
            None => rng.below(TARGETS.len()),
        };
        tally.run[which] += 1;
        // Each input is built before the watch starts: only the code under test is measured.
        let (input, check): (Vec<u8>, Check) = match which {
            0 => {
                let seed = rng_pick(&mut rng, &with_meta);
                let Some((file, intact)) = parts_input(&mut rng, seed) else {
                    continue;
                };
                let copy = file.clone();
                (
                    file,
                    Box::new(move |_| {
                        match (cloud::load_from_bytes(&copy, Path::new("p.ply")), intact) {
                            (Ok(_), true) => {
                                accepted(0);
                                Ok(())
                            }
                            (Err(_), false) => Ok(()),
                            (Err(e), true) => Err(format!("whole parts refused: {e}")),
                            (Ok(_), false) => Err("changed parts accepted".into()),
                        }
                    }),
                )
            }
            1 => {
                let seed = rng_pick(&mut rng, &with_meta);
                let bytes = stream_input(&mut rng, seed);
                let copy = bytes.clone();
                let file = rng.chance(64);
                let scratch = scratch.clone();
                (
                    bytes,
                    Box::new(move |rng| check_stream(rng, &copy, &scratch, file)),
                )
            }
            2 => {
                let (bytes, expected) = npy_input(&mut rng);
                let copy = bytes.clone();
                (bytes, Box::new(move |_| check_npy(&copy, expected)))
            }
            _ => {
                let (text, array, right) = sidecar_input(&mut rng);
                let bytes = text.clone().into_bytes();
                (
                    bytes,
                    Box::new(move |_| check_sidecar(&text, &array, right)),
                )
            }
        };
        let watch = limits.start();
        let outcome = catch_unwind(AssertUnwindSafe(|| check(&mut rng)));
        let verdict = match outcome {
            Ok(Ok(())) => watch.check(&limits, input.len()),
            Ok(Err(why)) => Err(why),
            Err(_) => Err("panic".into()),
        };
        if let Err(why) = verdict {
            save(
                &options.crashes,
                TARGETS[which],
                &input,
                &why,
                tally.findings,
            );
            tally.findings += 1;
        }
    }
    let _ = std::fs::remove_dir_all(&scratch);
    let seconds = start.elapsed().as_secs_f64();
    let profile = if cfg!(debug_assertions) {
        "debug, overflow checks"
    } else {
        "release"
    };
    let per_target: Vec<String> = TARGETS
        .iter()
        .zip(tally.run)
        .enumerate()
        .map(|(i, (t, r))| {
            let ok = ACCEPTED[i].load(std::sync::atomic::Ordering::Relaxed);
            format!("{t} {r} ({ok} accepted)")
        })
        .collect();
    println!(
        "fuzz_formats ({profile}): {n} inputs in {seconds:.1} s ({:.0} per second; {}), {} \
         findings, seed {}",
        n as f64 / seconds.max(1e-9),
        per_target.join(", "),
        tally.findings,
        options.seed
    );
    if tally.findings > 0 {
        std::process::exit(1);
    }
}

fn rng_pick<'a>(rng: &mut Rng, seeds: &[&'a Seed]) -> &'a Seed {
    seeds[rng.below(seeds.len())]
}
