//! Songs and videos for the command tests: the project's extractor, a song written as a WAV
//! from a formula, ffmpeg's decoding of a file's sound and a video's frames, and the compare
//! video and picture that the alignment and video tests hold side by side.

use std::ffi::{OsStr, OsString};
use std::path::{Path, PathBuf};
use std::process::Command;

use super::{assert_success, loudscape, repo};

/// The project's extractor (.venv, `make venv`), which the tests that extract songs run.
pub fn extractor() -> PathBuf {
    let program = repo().join(".venv/bin/loudscape-extract");
    assert!(
        program.is_file(),
        "these tests run the Python extractor: install it with `make venv` ({} is missing)",
        program.display()
    );
    program
}

/// Sample `i` (at 22,050 Hz) of a chord on A with a click every half second.
pub fn chord_with_clicks(i: usize) -> f32 {
    let rate = 22_050;
    let t = i as f32 / rate as f32;
    let chord: f32 = [220.0f32, 277.2, 329.6, 880.0]
        .iter()
        .map(|f| (std::f32::consts::TAU * f * t).sin())
        .sum();
    let click = if i % (rate / 2) < 40 { 0.6 } else { 0.0 };
    0.15 * chord + click
}

/// `seconds` of `song` (sample by sample) as a mono 16-bit WAV at `rate` Hz.
pub fn write_wav(path: &Path, seconds: f32, rate: u32, song: fn(usize) -> f32) {
    let n = (seconds * rate as f32) as usize;
    let data_len = (n * 2) as u32;
    let mut bytes = Vec::with_capacity(44 + n * 2);
    bytes.extend_from_slice(b"RIFF");
    bytes.extend_from_slice(&(36 + data_len).to_le_bytes());
    bytes.extend_from_slice(b"WAVEfmt ");
    bytes.extend_from_slice(&16u32.to_le_bytes());
    bytes.extend_from_slice(&1u16.to_le_bytes()); // PCM
    bytes.extend_from_slice(&1u16.to_le_bytes()); // mono
    bytes.extend_from_slice(&rate.to_le_bytes());
    bytes.extend_from_slice(&(rate * 2).to_le_bytes());
    bytes.extend_from_slice(&2u16.to_le_bytes());
    bytes.extend_from_slice(&16u16.to_le_bytes());
    bytes.extend_from_slice(b"data");
    bytes.extend_from_slice(&data_len.to_le_bytes());
    for i in 0..n {
        let s = (song(i).clamp(-1.0, 1.0) * 32_000.0) as i16;
        bytes.extend_from_slice(&s.to_le_bytes());
    }
    std::fs::write(path, bytes).unwrap();
}

/// The demo song 0.731 s later and 4 dB louder (as a remaster that starts later), as a float
/// WAV at `path`: the release the alignment tests find again.
pub fn delayed_louder_demo(path: &Path) {
    demo_through(path, "adelay=731:all=1,volume=4dB");
}

/// The demo song through ffmpeg's audio `filter` (another release of it: `adelay`, `atrim`,
/// `volume`), as a float WAV at `path`.
pub fn demo_through(path: &Path, filter: &str) {
    let made = Command::new("ffmpeg")
        .args(["-v", "error", "-y", "-i"])
        .arg(repo().join("data/demo_song.flac"))
        .args(["-af", filter, "-c:a", "pcm_f32le"])
        .arg(path)
        .output()
        .expect("this test needs ffmpeg");
    assert!(
        made.status.success(),
        "{}",
        String::from_utf8_lossy(&made.stderr)
    );
}

/// `path` for ffmpeg's command line: `file:` + the absolute path, whatever the name (a colon,
/// a leading dash, bytes that are not UTF-8).
fn ffmpeg_url(path: &Path) -> OsString {
    let mut url = OsString::from("file:");
    url.push(std::path::absolute(path).unwrap());
    url
}

/// Mono samples of `path`'s first audio stream at `rate` Hz (ffmpeg decodes; an MP4's AAC
/// priming is undone by its edit list).
pub fn decode_audio(path: &Path, rate: u32) -> Vec<f32> {
    let output = Command::new("ffmpeg")
        .args(["-v", "error", "-i"])
        .arg(ffmpeg_url(path))
        .args(["-map", "0:a:0", "-ac", "1", "-ar"])
        .arg(rate.to_string())
        .args(["-f", "f32le", "-"])
        .output()
        .expect("ffmpeg");
    assert_success(&output);
    output
        .stdout
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect()
}

/// Every frame of `path`'s video, decoded to RGBA.
pub fn decode_frames(path: &Path, (w, h): (u32, u32)) -> Vec<image::RgbaImage> {
    let output = Command::new("ffmpeg")
        .args(["-v", "error", "-i"])
        .arg(ffmpeg_url(path))
        .args(["-map", "0:v:0", "-f", "rawvideo", "-pix_fmt", "rgba", "-"])
        .output()
        .expect("ffmpeg");
    assert_success(&output);
    let frame = (w * h * 4) as usize;
    assert_eq!(output.stdout.len() % frame, 0, "not whole frames");
    output
        .stdout
        .chunks(frame)
        .map(|c| image::RgbaImage::from_raw(w, h, c.to_vec()).expect("frame"))
        .collect()
}

/// `image` at half the size, each pixel the mean of four: the resolution yuv420p keeps colour
/// at, so that what is compared is the picture, not the codec's loss on single points and glyphs.
pub fn half(image: &image::RgbaImage) -> image::RgbaImage {
    let (w, h) = (image.width() / 2, image.height() / 2);
    image::RgbaImage::from_fn(w, h, |x, y| {
        let mut sum = [0u32; 4];
        for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
            let p = image.get_pixel(2 * x + dx, 2 * y + dy);
            for c in 0..4 {
                sum[c] += u32::from(p[c]);
            }
        }
        image::Rgba(sum.map(|v| ((v + 2) / 4) as u8))
    })
}

/// The size of the compare videos and pictures.
const COMPARE_SIZE: (u32, u32) = (640, 360);

/// `video A --compare B --view compare` of 20 to 20.4 s at 5 fps (two frames, the last at
/// 20.2 s) into `video`, with `extra`; returns its frames and its stderr, asserting success.
pub fn compare_video(
    a: &Path,
    b: &Path,
    extra: &[&str],
    video: &Path,
) -> (Vec<image::RgbaImage>, String) {
    let mut args: Vec<&OsStr> = vec!["video".as_ref(), a.as_os_str()];
    args.extend(["--compare".as_ref(), b.as_os_str()]);
    args.extend(extra.iter().map(OsStr::new));
    args.extend(
        [
            "--view",
            "compare",
            "--size",
            "640x360",
            "--fps",
            "5",
            "--start",
            "20",
            "--end",
            "20.4",
            "--progress",
            "none",
            "-o",
        ]
        .map(OsStr::new),
    );
    args.push(video.as_os_str());
    let output = loudscape(&args);
    assert_success(&output);
    let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
    (decode_frames(video, COMPARE_SIZE), stderr)
}

/// `render A --compare B --view compare --playhead 20.2` into `png` with `extra`: what
/// [`compare_video`]'s last frame shows. Returns the picture, asserting success.
pub fn compare_render(a: &Path, b: &Path, extra: &[&str], png: &Path) -> image::RgbaImage {
    let mut args: Vec<&OsStr> = vec!["render".as_ref(), a.as_os_str()];
    args.extend(["--compare".as_ref(), b.as_os_str()]);
    args.extend(extra.iter().map(OsStr::new));
    args.extend(
        [
            "--view",
            "compare",
            "--size",
            "640x360",
            "--playhead",
            "20.2",
            "-o",
        ]
        .map(OsStr::new),
    );
    args.push(png.as_os_str());
    assert_success(&loudscape(&args));
    image::open(png).unwrap().to_rgba8()
}
