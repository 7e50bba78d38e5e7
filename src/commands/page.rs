//! `loudscape page SONG -o song.html`: one web page that shows the song in 3D in a browser, the
//! app's own viewer built for the web (src/web/, `make web`).
//!
//! The page is one self-contained file: the viewer's wasm and its script glue, and the cloud
//! thinned and quantized (`data::page_cloud`), both base64 in the page, so it opens from the file
//! system as from any static host. The cloud is thinned so the page stays under
//! [`PAGE_BUDGET_BYTES`]; the page says what was thinned. The wasm is found in the folder `make
//! web` writes (see [`viewer_dirs`]). With `--audio` the song's sound rides along ([`audio`]).

mod audio;
mod compare;

use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::bail;
use clap::Args;

use crate::commands::args::{check_output, load_cloud};
use crate::commands::compare_align::AlignAsk;
use loudscape::data::cloud::DataMode;
use loudscape::data::page_cloud;

/// What a page may weigh without its sound, everything included: a 3-minute song's page
/// without audio stays under 12 MB, with audio under 20 MB ([`audio::AUDIO_BUDGET_BYTES`]
/// more; issue 38).
pub const PAGE_BUDGET_BYTES: usize = 12_000_000;
/// The viewer's wasm and glue as `wasm-bindgen` names them.
const WASM_FILE: &str = "loudscape_bg.wasm";
const GLUE_FILE: &str = "loudscape.js";
/// The page around the viewer.
const TEMPLATE: &str = include_str!("page.html");
/// Room left in the budget for the template, the metadata header and the names.
const TEMPLATE_ROOM: usize = 256 * 1024;

#[derive(Args, Debug)]
pub struct PageArgs {
    /// The song: a point cloud (.ply) or an audio file (extracted and cached, as `render` does).
    pub input: PathBuf,

    /// The page to write (.html); written whole or not at all.
    #[arg(short, long)]
    pub output: PathBuf,

    /// Carry at most this many points (default: as many as the page's 12 MB allow).
    #[arg(long)]
    pub max_points: Option<usize>,

    /// Put the song's sound in the page (Opus, by ffmpeg), with play, a playhead and
    /// click-to-seek: off by default, as publishing the page publishes the music. The sound is
    /// the input when it is audio, else the cloud's source audio, checked against the cloud.
    #[arg(long)]
    pub audio: bool,

    /// A second song (B) shown beside the first (A), as the window's Compare view: both on one
    /// set of axes, one camera. Not with a timeline, nor with --audio.
    #[arg(long)]
    pub compare: Option<PathBuf>,

    /// With --compare: B moved onto A's time by the offset found in their audio (as `render
    /// --compare --align`).
    #[arg(long)]
    pub align: bool,

    /// With --compare: B's offset against A in seconds (positive: B's music comes later),
    /// added to the one --align finds.
    #[arg(long, allow_hyphen_values = true)]
    pub offset: Option<f64>,

    /// With --compare and --align: B's levels moved by the gain that matches its loudness to A's.
    #[arg(long)]
    pub match_loudness: bool,
}

/// The folders searched for the viewer: `$LOUDSCAPE_WEB_DIR` alone when it is set, else `web/`
/// beside the binary, then `target/web` of the source tree this binary was built from (where
/// `make web` writes).
pub fn viewer_dirs() -> Vec<PathBuf> {
    if let Some(dir) = std::env::var_os("LOUDSCAPE_WEB_DIR") {
        return vec![PathBuf::from(dir)];
    }
    let mut dirs = Vec::new();
    if let Some(exe_dir) = std::env::current_exe()
        .ok()
        .and_then(|exe| exe.parent().map(Path::to_path_buf))
    {
        dirs.push(exe_dir.join("web"));
    }
    dirs.push(Path::new(env!("CARGO_MANIFEST_DIR")).join("target/web"));
    dirs
}

/// The viewer's wasm and glue, from the first folder of [`viewer_dirs`] that holds both.
fn read_viewer() -> anyhow::Result<(Vec<u8>, String)> {
    let dirs = viewer_dirs();
    for dir in &dirs {
        let (wasm, glue) = (dir.join(WASM_FILE), dir.join(GLUE_FILE));
        if wasm.is_file() && glue.is_file() {
            let read = |path: &Path| {
                std::fs::read(path)
                    .map_err(|e| anyhow::anyhow!("{}: cannot read: {e}", path.display()))
            };
            let glue_text = String::from_utf8(read(&glue)?)
                .map_err(|_| anyhow::anyhow!("{}: not UTF-8 text", glue.display()))?;
            return Ok((read(&wasm)?, glue_text));
        }
    }
    let searched: Vec<String> = dirs.iter().map(|d| d.display().to_string()).collect();
    bail!(
        "the web viewer is not built (no {WASM_FILE} in {}): run `make web` in the source tree",
        searched.join(", ")
    );
}

/// A JSON string literal safe inside a `<script>` element.
fn script_string(text: &str) -> String {
    serde_json::Value::from(text)
        .to_string()
        .replace('<', "\\u003c")
}

/// Base64 (standard alphabet, padded).
fn base64(bytes: &[u8]) -> String {
    const ALPHABET: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for chunk in bytes.chunks(3) {
        let b = [
            chunk[0],
            *chunk.get(1).unwrap_or(&0),
            *chunk.get(2).unwrap_or(&0),
        ];
        let n = (u32::from(b[0]) << 16) | (u32::from(b[1]) << 8) | u32::from(b[2]);
        for i in 0..4 {
            if i <= chunk.len() {
                out.push(ALPHABET[(n >> (18 - 6 * i) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

/// `bytes` gzipped (the page's script unpacks them with the browser's DecompressionStream).
fn gzip(bytes: &[u8]) -> Vec<u8> {
    let mut encoder = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::best());
    encoder.write_all(bytes).expect("writing to memory");
    encoder.finish().expect("writing to memory")
}

/// The most points a page can carry with `viewer_bytes` of packed viewer (wasm and glue),
/// reckoned at 10 bytes a point before gzip (which takes off about a third) and 4/3 for base64.
fn points_in_budget(viewer_bytes: usize) -> usize {
    let left = PAGE_BUDGET_BYTES.saturating_sub(viewer_bytes * 4 / 3 + TEMPLATE_ROOM);
    left * 3 / 4 / 10
}

pub fn run(args: PageArgs) -> anyhow::Result<()> {
    let mut inputs = vec![args.input.as_path()];
    inputs.extend(args.compare.as_deref());
    check_output(&args.output, &["html", "htm"], &inputs)?;
    if args.max_points == Some(0) {
        bail!("--max-points must be at least 1");
    }
    let ask = AlignAsk {
        align: args.align,
        offset: args.offset,
        match_loudness: args.match_loudness,
    };
    ask.check(args.compare.is_some())?;
    if args.compare.is_some() && args.audio {
        bail!(
            "--audio is for one song's page: a compare's page carries no sound (make A's page \
             without --compare to share its sound)"
        );
    }
    let (wasm, glue) = read_viewer()?;
    let cloud = load_cloud(&args.input)?;
    if let Some(b) = &args.compare {
        return run_compare(&args, b, ask, cloud, wasm, glue);
    }
    let sound = if args.audio {
        if cloud.meta.mode == DataMode::Timeline {
            bail!(
                "{}: --audio is for a song; a timeline has no one sound",
                args.input.display()
            );
        }
        let source = audio::song_sound(&args.input, &cloud)?;
        check_output(&args.output, &["html", "htm"], &[source.as_path()])?;
        let duration = loudscape::playback::song_duration_s(&cloud);
        Some((audio::encode(&source, duration)?, duration))
    } else {
        None
    };
    let wasm = gzip(&wasm);
    let budget = points_in_budget(wasm.len() + glue.len());
    let max_points = args.max_points.unwrap_or(budget).min(budget).max(1);
    let (data, thinning) = page_cloud::encode(&cloud, max_points);
    let data = gzip(&data);
    let name = file_name(&cloud);
    let note = thinning_note(&thinning, cloud.meta.mode);
    let title = html_text(&loudscape::annotate::legend::picture_name(&cloud));
    let page = TEMPLATE
        .replace("__TITLE__", &title)
        .replace("__NAME__", &script_string(&name))
        .replace("__NOTE__", &script_string(&note))
        .replace("__COMPARE__", "")
        .replace("__COMPARE_NAME__", "\"\"")
        .replace("__LABELS__", "[]")
        .replace("__GLUE__", &glue)
        .replace(
            "__DURATION__",
            &format!("{}", sound.as_ref().map_or(0.0, |s| s.1)),
        )
        .replace("__WASM__", &base64(&wasm))
        .replace("__CLOUD__", &base64(&data))
        .replace(
            "__AUDIO__",
            &sound.as_ref().map_or(String::new(), |s| base64(&s.0.webm)),
        );
    // The cloud's warnings were said when it was loaded (`load_cloud`), once.
    crate::commands::write_atomically(&args.output, |out| Ok(out.write_all(page.as_bytes())?))?;
    crate::commands::wrote(
        &args.output,
        &format!(
            "{:.1} MB, {} of {} points{}",
            page.len() as f64 / 1e6,
            thinning.kept,
            thinning.total,
            sound.as_ref().map_or(String::new(), |(sound, _)| format!(
                ", sound {:.1} MB at {} kbit/s",
                sound.webm.len() as f64 / 1e6,
                sound.kbps
            ))
        ),
    );
    Ok(())
}

/// The page of `A --compare B` (checked by [`run`]; `cloud_a` loaded): B loaded, moved onto A
/// as `ask` says, both on their union axes, thinned into the budget together.
fn run_compare(
    args: &PageArgs,
    b_path: &Path,
    ask: AlignAsk,
    cloud_a: loudscape::data::cloud::PointCloud,
    wasm: Vec<u8>,
    glue: String,
) -> anyhow::Result<()> {
    let cloud_b = load_cloud(b_path)?;
    compare::check_songs(&cloud_a, &cloud_b)?;
    let aligned = crate::commands::compare_align::align_b_as(&cloud_a, cloud_b, ask)?;
    let wasm = gzip(&wasm);
    let budget = points_in_budget(wasm.len() + glue.len());
    let max_points = args.max_points.unwrap_or(budget).min(budget).max(2);
    let names = version_names(&args.input, b_path);
    let page = compare::compare_page(
        &cloud_a,
        &aligned.cloud,
        [&names[0], &names[1]],
        aligned.offset_s,
        aligned.gain_db,
        max_points,
    )?;
    let title = html_text(&format!("Compare {} with {}", names[0], names[1]));
    let labels = serde_json::Value::from(page.labels.to_vec())
        .to_string()
        .replace('<', "\\u003c");
    let html = TEMPLATE
        .replace("__TITLE__", &title)
        .replace("__NAME__", &script_string(&names[0]))
        .replace("__NOTE__", &script_string(&page.note))
        .replace("__COMPARE_NAME__", &script_string(&names[1]))
        .replace("__LABELS__", &labels)
        .replace("__GLUE__", &glue)
        .replace("__DURATION__", "0")
        .replace("__WASM__", &base64(&wasm))
        .replace("__CLOUD__", &base64(&gzip(&page.data[0])))
        .replace("__COMPARE__", &base64(&gzip(&page.data[1])))
        .replace("__AUDIO__", "");
    crate::commands::write_atomically(&args.output, |out| Ok(out.write_all(html.as_bytes())?))?;
    let [a, b] = &page.thinning;
    crate::commands::wrote(
        &args.output,
        &format!(
            "{:.1} MB, compare: A {} of {} points, B {} of {} points{}",
            html.len() as f64 / 1e6,
            a.kept,
            a.total,
            b.kept,
            b.total,
            aligned.note.map(|n| format!(", {n}")).unwrap_or_default()
        ),
    );
    Ok(())
}

/// A and B named as the user gave them: an audio file's cloud comes from the cache under a
/// hashed name, which says nothing on the page. Two versions of one file name in different
/// folders are told apart by their folders ("master/song.flac", "remaster/song.flac").
fn version_names(a: &Path, b: &Path) -> [String; 2] {
    let name = |path: &Path, parts: usize| {
        let names: Vec<String> = path
            .components()
            .rev()
            .take(parts)
            .map(|c| c.as_os_str().to_string_lossy().into_owned())
            .collect();
        names.into_iter().rev().collect::<Vec<_>>().join("/")
    };
    let (short_a, short_b) = (name(a, 1), name(b, 1));
    if short_a == short_b {
        [name(a, 2), name(b, 2)]
    } else {
        [short_a, short_b]
    }
}

/// The cloud's file name, as the page names it.
fn file_name(cloud: &loudscape::data::cloud::PointCloud) -> String {
    cloud
        .path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "song".into())
}

/// `text` safe as HTML text.
fn html_text(text: &str) -> String {
    text.replace('&', "&amp;").replace('<', "&lt;")
}

/// What the page says it carries: every point, or which of them, of the song or the timeline.
fn thinning_note(thinning: &page_cloud::Thinning, mode: DataMode) -> String {
    let whole = match mode {
        DataMode::Timeline => "timeline",
        _ => "song",
    };
    if thinning.stride > 1 {
        format!(
            "This page carries {} of the {whole}'s {} points (every {}), positions to 1/65535 \
             of the box.",
            thinning.kept,
            thinning.total,
            ordinal(thinning.stride)
        )
    } else {
        format!("Every point of the {whole}, positions to 1/65535 of the box.")
    }
}

/// "2nd", "3rd", "11th", "21st": the k of "every k-th point".
fn ordinal(n: usize) -> String {
    let suffix = match (n % 10, n % 100) {
        (_, 11..=13) => "th",
        (1, _) => "st",
        (2, _) => "nd",
        (3, _) => "rd",
        _ => "th",
    };
    format!("{n}{suffix}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn compare_versions_are_named_as_given_and_told_apart_by_folder() {
        let names = version_names(Path::new("in/master.flac"), Path::new("vinyl.wav"));
        assert_eq!(names, ["master.flac".to_string(), "vinyl.wav".to_string()]);
        let names = version_names(
            Path::new("music/master/song.flac"),
            Path::new("music/remaster/song.flac"),
        );
        assert_eq!(
            names,
            [
                "master/song.flac".to_string(),
                "remaster/song.flac".to_string()
            ]
        );
    }

    #[test]
    fn base64_matches_the_standard_alphabet_and_padding() {
        assert_eq!(base64(b""), "");
        assert_eq!(base64(b"f"), "Zg==");
        assert_eq!(base64(b"fo"), "Zm8=");
        assert_eq!(base64(b"foo"), "Zm9v");
        assert_eq!(base64(b"foobar\xff"), "Zm9vYmFy/w==");
    }

    #[test]
    fn the_note_names_what_was_thinned_in_english() {
        let thinned = page_cloud::Thinning {
            total: 10,
            kept: 5,
            stride: 2,
        };
        assert_eq!(
            thinning_note(&thinned, DataMode::Timeline),
            "This page carries 5 of the timeline's 10 points (every 2nd), positions to \
             1/65535 of the box."
        );
        let whole = page_cloud::Thinning {
            total: 10,
            kept: 10,
            stride: 1,
        };
        assert!(thinning_note(&whole, DataMode::Song).starts_with("Every point of the song,"));
        let ordinals: Vec<String> = [1, 2, 3, 4, 11, 12, 13, 21, 22, 23, 101, 111]
            .into_iter()
            .map(ordinal)
            .collect();
        assert_eq!(
            ordinals,
            [
                "1st", "2nd", "3rd", "4th", "11th", "12th", "13th", "21st", "22nd", "23rd",
                "101st", "111th"
            ]
        );
    }

    #[test]
    fn strings_cannot_close_the_script_they_sit_in() {
        assert_eq!(script_string("a</script>\"b"), "\"a\\u003c/script>\\\"b\"");
    }
}
