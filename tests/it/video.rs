//! `loudscape video`: the file is what players and upload sites take (ffprobe: one H.264 yuv420p
//! video stream and one AAC stream, the size, rate and length asked for); frame k is what
//! `render --playhead` draws for start + k/fps; the sound track is the source passage to the
//! sample; a 1-second golden video of the demo; bad requests fail cleanly; SIGTERM and SIGINT leave no
//! file and no encoder behind. Needs ffmpeg and ffprobe (scripts/setup-system.sh installs them).

use crate::common::{
    self, assert_success, decode_audio, decode_frames, ffprobe, half, loudscape, repo,
};

#[cfg(unix)]
use std::io::{BufRead, BufReader};
use std::path::PathBuf;
use std::process::Command;
#[cfg(unix)]
use std::process::Stdio;
use std::sync::OnceLock;
#[cfg(unix)]
use std::time::{Duration, Instant};

fn demo() -> String {
    repo().join("data/demo_song.ply").display().to_string()
}

fn out(name: &str) -> PathBuf {
    let dir = common::output_dir().join("video");
    std::fs::create_dir_all(&dir).expect("mkdir");
    let path = dir.join(name);
    let _ = std::fs::remove_file(&path);
    path
}

/// The passage of the shared test video.
const START: f64 = 2.0;
const END: f64 = 3.5;
const FPS: u32 = 10;
const SIZE: (u32, u32) = (640, 360);

/// One video shared by the tests that read it: 1.5 s of the demo at 640x360, 10 fps, every
/// point (`--detail full`, as `render` draws), no strip (so a frame is `render`'s picture).
fn shared_video() -> &'static (PathBuf, Vec<String>) {
    static VIDEO: OnceLock<(PathBuf, Vec<String>)> = OnceLock::new();
    VIDEO.get_or_init(|| {
        let path = out("passage.mp4");
        let output = loudscape(&[
            "video",
            &demo(),
            "--size",
            "640x360",
            "--fps",
            "10",
            "--start",
            "2",
            "--end",
            "3.5",
            "--detail",
            "full",
            "--no-strip",
            "--progress",
            "json",
            "-o",
            path.to_str().unwrap(),
        ]);
        assert_success(&output);
        let lines = String::from_utf8_lossy(&output.stdout)
            .lines()
            .map(str::to_string)
            .collect();
        (path, lines)
    })
}

#[test]
fn the_file_is_h264_and_aac_of_the_asked_size_rate_and_length() {
    let (path, progress) = shared_video();
    let probe = ffprobe(path);
    let streams = probe["streams"].as_array().expect("streams");
    assert_eq!(streams.len(), 2, "{probe}");
    let video: Vec<_> = streams
        .iter()
        .filter(|s| s["codec_type"] == "video")
        .collect();
    let audio: Vec<_> = streams
        .iter()
        .filter(|s| s["codec_type"] == "audio")
        .collect();
    assert_eq!((video.len(), audio.len()), (1, 1), "{probe}");
    let (v, a) = (video[0], audio[0]);
    assert_eq!(v["codec_name"], "h264");
    assert_eq!(v["pix_fmt"], "yuv420p");
    assert_eq!(v["color_space"], "bt709", "the colour matrix is tagged");
    assert_eq!(v["width"], SIZE.0);
    assert_eq!(v["height"], SIZE.1);
    assert_eq!(v["r_frame_rate"], format!("{FPS}/1"));
    assert_eq!(a["codec_name"], "aac");
    let seconds = |x: &serde_json::Value| -> f64 { x.as_str().unwrap().parse().unwrap() };
    let frame = 1.0 / f64::from(FPS);
    let passage = END - START;
    for (what, d) in [
        ("video", seconds(&v["duration"])),
        ("audio", seconds(&a["duration"])),
        ("file", seconds(&probe["format"]["duration"])),
    ] {
        assert!(
            (d - passage).abs() <= frame + 1e-6,
            "{what} lasts {d} s, the passage {passage} s"
        );
    }
    assert_eq!(v["nb_frames"], "15");
    // faststart: the index (moov) comes before the media data (mdat).
    let bytes = std::fs::read(path).unwrap();
    let find = |tag: &[u8]| bytes.windows(4).position(|w| w == tag).unwrap();
    assert!(
        find(b"moov") < find(b"mdat"),
        "moov after mdat: no faststart"
    );
    // --progress json: one object a line, ending at the last frame.
    let last: serde_json::Value =
        serde_json::from_str(progress.last().expect("progress lines")).expect("json");
    assert_eq!(last["frame"], 15);
    assert_eq!(last["frames"], 15);
    assert!(last["fps"].as_f64().unwrap() > 0.0);
    assert_eq!(last["eta_s"].as_f64(), Some(0.0));
}

#[test]
fn frame_k_is_render_with_the_playhead_at_start_plus_k_over_fps() {
    let (path, _) = shared_video();
    let frames = decode_frames(path, SIZE);
    assert_eq!(frames.len(), 15);
    let render = |t: f64| {
        let png = out(&format!("render_{t:.2}.png"));
        let output = loudscape(&[
            "render",
            &demo(),
            "--size",
            "640x360",
            "--playhead",
            &t.to_string(),
            "-o",
            png.to_str().unwrap(),
        ]);
        assert_success(&output);
        image::open(&png).expect("png").to_rgba8()
    };
    let frame_s = 1.0 / f64::from(FPS);
    for k in [0usize, 7, 14] {
        let t = START + k as f64 * frame_s;
        let frame = &frames[k];
        frame
            .save(out(&format!("frame_{k}.png")))
            .expect("save frame");
        let (share, mean) = common::difference(&half(frame), &half(&render(t)), 32);
        assert!(
            share < 0.001,
            "frame {k}: {share} of pixels differ from render --playhead {t} (mean {mean})"
        );
        // Sync to the frame: the playhead one frame earlier or later is plainly another picture.
        for other in [t - frame_s, t + frame_s] {
            let (off, _) = common::difference(&half(frame), &half(&render(other)), 32);
            assert!(
                off > 10.0 * share && off > 0.001,
                "frame {k}: render at {other:.2} s differs by {off}, at {t:.2} s by {share}"
            );
        }
    }
}

#[test]
fn the_sound_is_the_source_passage_to_the_sample() {
    let (path, _) = shared_video();
    let rate = 22_050; // the demo's own rate
    let sound = decode_audio(path, rate);
    let source = decode_audio(&repo().join("data/demo_song.flac"), rate);
    let first = (START * f64::from(rate)).round() as usize;
    let len = ((END - START) * f64::from(rate)) as usize;
    assert!(
        sound.len().abs_diff(len) <= (rate / FPS) as usize,
        "{} samples, the passage has {len}",
        sound.len()
    );
    // Normalized cross-correlation over +-50 ms, away from the edges.
    let margin = 2_000usize;
    let window = &sound[margin..len - margin];
    let energy = |s: &[f32]| s.iter().map(|v| f64::from(*v).powi(2)).sum::<f64>().sqrt();
    let (mut best_lag, mut best) = (i64::MIN, f64::MIN);
    for lag in -1102i64..=1102 {
        let at = (first + margin) as i64 + lag;
        let other = &source[at as usize..at as usize + window.len()];
        let dot: f64 = window
            .iter()
            .zip(other)
            .map(|(a, b)| f64::from(*a) * f64::from(*b))
            .sum();
        let c = dot / (energy(window) * energy(other)).max(1e-12);
        if c > best {
            (best_lag, best) = (lag, c);
        }
    }
    assert_eq!(
        best_lag, 0,
        "the sound is {best_lag} samples off (correlation {best})"
    );
    assert!(best > 0.95, "correlation {best}");
}

#[test]
fn golden_one_second_video_of_the_demo() {
    let path = out("golden_demo.mp4");
    let output = loudscape(&[
        "video",
        &demo(),
        "--size",
        "640x360",
        "--fps",
        "10",
        "--start",
        "10",
        "--end",
        "11",
        "--detail",
        "full",
        "--camera",
        "orbit",
        "--progress",
        "none",
        "-o",
        path.to_str().unwrap(),
    ]);
    assert_success(&output);
    let golden = repo().join("tests/golden/video_demo.mp4");
    let actual = decode_frames(&path, SIZE);
    if std::env::var_os("UPDATE_GOLDEN").is_some() {
        // Written only when a frame no longer matches within the tolerance below, and then the
        // test fails naming it: one run never re-blesses the golden silently
        // (tests/it/common/golden.rs).
        let changed = !golden.exists() || {
            let expected = decode_frames(&golden, SIZE);
            expected.len() != actual.len()
                || actual
                    .iter()
                    .zip(&expected)
                    .any(|(a, e)| common::difference(&half(a), &half(e), 32).0 >= 0.01)
        };
        if changed {
            std::fs::copy(&path, &golden).expect("write golden");
            panic!(
                "golden {} rewritten: look at it, then run again without UPDATE_GOLDEN",
                golden.display()
            );
        }
        return;
    }
    let expected = decode_frames(&golden, SIZE);
    assert_eq!(actual.len(), 10);
    assert_eq!(expected.len(), actual.len());
    // Tolerance: under 1% of the half-size pixels past 32. The frames went through H.264
    // (lossy: its blocks move with the encoder's version), compared at half size so block
    // edges average out, and were rendered on lavapipe (common::RASTER_EDGES: edges flip on
    // other rasterizers); a wrong frame (camera, playhead, strip) changes far more.
    for (k, (a, e)) in actual.iter().zip(&expected).enumerate() {
        let (share, mean) = common::difference(&half(a), &half(e), 32);
        if share >= 0.01 {
            a.save(out(&format!("golden_{k}.actual.png"))).unwrap();
            e.save(out(&format!("golden_{k}.expected.png"))).unwrap();
        }
        assert!(
            share < 0.01,
            "frame {k}: {share} of pixels differ (mean {mean})"
        );
    }
    // The strip is under the view (a 360-pixel frame has room), and its playhead moves.
    let strip_row = SIZE.1 - 60;
    let white = |img: &image::RgbaImage| -> Vec<u32> {
        (0..SIZE.0)
            .filter(|&x| img.get_pixel(x, strip_row).0[..3].iter().all(|&c| c > 200))
            .collect()
    };
    let (a, b) = (white(&actual[0]), white(&actual[9]));
    assert!(!a.is_empty() && !b.is_empty(), "no strip playhead");
    assert!(
        b[0] > a[0],
        "the strip's playhead does not move: {a:?} -> {b:?}"
    );
}

#[test]
fn bad_requests_fail_cleanly() {
    let video = out("bad.mp4");
    let v = video.to_str().unwrap();
    let d = demo();
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (vec!["--size", "641x360"], "even"),
        (vec!["--size", "4096x2304"], "3840x2160"),
        (vec!["--fps", "0"], "fps"),
        (vec!["--start", "5", "--end", "4"], "after --start"),
        (vec!["--end", "99"], "past the end"),
        (vec!["--camera", "spin"], "fixed, orbit, follow"),
        (vec!["--view", "compare"], "--compare"),
        (vec!["--progress", "loud"], "auto, json, none"),
    ];
    for (extra, needle) in cases {
        let mut args = vec!["video", d.as_str()];
        args.extend(extra.iter());
        args.extend(["-o", v]);
        let output = loudscape(&args);
        let err = String::from_utf8_lossy(&output.stderr);
        assert!(!output.status.success(), "{extra:?} succeeded");
        assert!(err.contains(needle), "{extra:?}: {err}");
        assert_eq!(err.lines().count(), 1, "{extra:?}: {err}");
        assert!(!video.exists());
    }
    // The output is never the input.
    let output = loudscape(&["video", d.as_str(), "-o", d.as_str()]);
    assert!(!output.status.success());
    assert!(String::from_utf8_lossy(&output.stderr).contains("the output is the input"));
    let flac = repo().join("data/demo_song.flac");
    let copy = out("song.mp4");
    std::fs::copy(&flac, &copy).unwrap();
    let output = loudscape(&[
        "video",
        copy.to_str().unwrap(),
        "-o",
        copy.to_str().unwrap(),
    ]);
    assert!(String::from_utf8_lossy(&output.stderr).contains("the output is the input"));
    // render --playhead is for a song's time axis.
    let png = out("timeline_playhead.png");
    let timeline = repo().join("data/demo_timeline.ply");
    let output = loudscape(&[
        "render",
        timeline.to_str().unwrap(),
        "--playhead",
        "3",
        "-o",
        png.to_str().unwrap(),
    ]);
    assert!(!output.status.success());
    assert!(String::from_utf8_lossy(&output.stderr).contains("--playhead needs a song cloud"));
    // Without ffmpeg: one line naming the package to install.
    let output = Command::new(env!("CARGO_BIN_EXE_loudscape"))
        .args(["video", d.as_str(), "-o", v])
        .env("PATH", "")
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&output.stderr);
    assert!(!output.status.success());
    assert!(
        err.contains("ffmpeg is not installed") && err.contains("'ffmpeg'"),
        "{err}"
    );
}

#[cfg(unix)]
#[test]
fn sigterm_and_ctrl_c_stop_at_once_and_leave_no_file_and_no_encoder() {
    for (signal, code) in [("TERM", 143), ("INT", 130)] {
        stops_on(signal, code);
    }
}

#[cfg(unix)]
fn stops_on(signal: &str, code: i32) {
    let video = out(&format!("killed_{signal}.mp4"));
    let mut child = Command::new(env!("CARGO_BIN_EXE_loudscape"))
        .args([
            "video",
            &demo(),
            "--size",
            "320x180",
            // A camera that moves draws every frame (a still one draws the view once), so
            // the whole song's video is still encoding when the signal comes.
            "--camera",
            "orbit",
            "--detail",
            "full",
            "--progress",
            "json",
            "-o",
            video.to_str().unwrap(),
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    // The temporary beside the output carries the writer's PID.
    let partial = out(&format!(
        "killed_{signal}.mp4.loudscape-{}.partial.mp4",
        child.id()
    ));
    // Frames are flowing to ffmpeg once the first progress line comes.
    let mut lines = BufReader::new(child.stdout.take().unwrap()).lines();
    let first = lines.next().expect("a progress line").unwrap();
    assert!(first.contains("\"frame\""), "{first}");
    assert!(partial.exists(), "no temporary file while encoding");
    let encoders = || common::processes_naming(&partial);
    assert_eq!(encoders(), 1, "ffmpeg is not running");
    let sent = Instant::now();
    Command::new("kill")
        .args([format!("-{signal}"), child.id().to_string()])
        .status()
        .unwrap();
    let status = child.wait().unwrap();
    assert!(sent.elapsed() < Duration::from_secs(5), "slow to stop");
    assert_eq!(status.code(), Some(code), "SIG{signal}");
    assert!(!video.exists(), "a video was written after SIG{signal}");
    assert!(!partial.exists(), "the temporary file is left");
    assert_eq!(encoders(), 0, "ffmpeg is still running");
}

#[test]
fn a_timeline_sweeps_across_its_years_over_a_silent_track() {
    let path = out("timeline.mp4");
    let output = loudscape(&[
        "video",
        repo().join("data/demo_timeline.ply").to_str().unwrap(),
        "--view",
        "timeline",
        "--size",
        "640x360",
        "--fps",
        "5",
        "--sweep",
        "2",
        "--progress",
        "none",
        "-o",
        path.to_str().unwrap(),
    ]);
    assert_success(&output);
    let probe = ffprobe(&path);
    let streams = probe["streams"].as_array().expect("streams");
    assert_eq!(streams.len(), 2, "{probe}");
    assert!(streams.iter().any(|s| s["codec_name"] == "aac"));
    let frames = decode_frames(&path, SIZE);
    assert_eq!(frames.len(), 10);
    // The sweep moves: the first and the last frame differ, and each names a song at the
    // bottom (the title's plate is there, over the background).
    let (moved, _) = common::difference(&half(&frames[0]), &half(&frames[9]), 32);
    assert!(moved > 0.01, "the sweep does not move ({moved})");
    let bottom = |img: &image::RgbaImage| {
        image::imageops::crop_imm(img, SIZE.0 / 4, SIZE.1 - 40, SIZE.0 / 2, 30).to_image()
    };
    for k in [0, 9] {
        assert!(
            common::coverage(&bottom(&frames[k])) > 0.05,
            "frame {k}: no song title"
        );
    }
}

/// A real player shows it: mpv plays the golden video under Xvfb (software output), paused half
/// way, and the screen holds that frame.
#[test]
fn mpv_plays_the_video_under_xvfb() {
    let golden = repo().join("tests/golden/video_demo.mp4");
    let shot = out("mpv_screen.png");
    let script = format!(
        "mpv --no-config --vo=x11 --ao=null --pause --start=0.5 --geometry=640x360+0+0 \
         --no-border --no-osc --osd-level=0 '{}' >/dev/null 2>&1 & p=$!; sleep 4; \
         import -window root '{}'; kill $p",
        golden.display(),
        shot.display()
    );
    let status = Command::new("xvfb-run")
        .args([
            "-a",
            "-s",
            "-screen 0 800x500x24 -noreset",
            "bash",
            "-c",
            &script,
        ])
        .status()
        .expect("xvfb-run (install xvfb, mpv, imagemagick)");
    assert!(status.success());
    let screen = image::open(&shot).expect("screenshot").to_rgba8();
    let shown = image::imageops::crop_imm(&screen, 0, 0, SIZE.0, SIZE.1).to_image();
    let frame = &decode_frames(&golden, SIZE)[5];
    let (share, mean) = common::difference(&half(&shown), &half(frame), 32);
    assert!(
        share < 0.05,
        "mpv shows something else: {share} of pixels differ (mean {mean}); see {}",
        shot.display()
    );
}

/// A compare video's frame is `render --compare --playhead` at its time too.
#[test]
fn a_compare_frame_is_render_compare_with_the_playhead() {
    let (a, b) = (PathBuf::from(demo()), repo().join("data/fixture_song.ply"));
    let (frames, _) = common::compare_video(&a, &b, &[], &out("compare.mp4"));
    assert_eq!(frames.len(), 2);
    let render = common::compare_render(&a, &b, &[], &out("compare_render.png"));
    let (share, mean) = common::difference(&half(&frames[1]), &half(&render), 32);
    assert!(share < 0.001, "{share} of pixels differ (mean {mean})");
}

/// The video keeps two frames in flight: frame k's read-back is submitted, frame k+1 drawn into
/// the other target, and only then is frame k read. Each reader must give back its own
/// target's picture as it was when its copy was submitted, whatever was drawn after it.
#[test]
fn frames_in_flight_are_read_back_each_from_its_own_target() {
    use loudscape::render::gpu::target::{RenderTarget, TargetReader};
    let gpu = common::gpu();
    let (w, h) = (70, 24);
    let picture = |seed: u8| -> Vec<u8> {
        (0..w * h)
            .flat_map(|i| [seed, (i % 251) as u8, seed.wrapping_mul(i as u8), 255])
            .collect()
    };
    let targets = [0, 1].map(|_| RenderTarget::new(&gpu.device, w, h));
    let readers = targets
        .each_ref()
        .map(|target| TargetReader::new(&gpu.device, target));
    let draw = |target: &RenderTarget, rgba: &[u8]| {
        gpu.queue.write_texture(
            target.color.as_image_copy(),
            rgba,
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(4 * w),
                rows_per_image: Some(h),
            },
            wgpu::Extent3d {
                width: w,
                height: h,
                depth_or_array_layers: 1,
            },
        );
    };
    let mut pending = None;
    for k in 0..5u8 {
        let slot = usize::from(k % 2);
        draw(&targets[slot], &picture(k));
        let index = readers[slot]
            .submit_copy(&gpu.device, &gpu.queue, &targets[slot])
            .expect("submit the copy");
        // Frame k drawn and its copy submitted; only now is frame k-1 read.
        if let Some((previous, slot, index)) = pending.replace((k, slot, index)) {
            let mut out = vec![0; (w * h * 4) as usize];
            readers[slot]
                .finish_into(&gpu.device, index, &mut out)
                .expect("read back");
            assert!(out == picture(previous), "frame {previous} read back wrong");
        }
    }
    let (last, slot, index) = pending.expect("a last frame");
    let mut out = vec![0; (w * h * 4) as usize];
    readers[slot]
        .finish_into(&gpu.device, index, &mut out)
        .expect("read back");
    assert!(out == picture(last), "frame {last} read back wrong");
    // A buffer of the wrong size is refused, not written past.
    let index = readers[0]
        .submit_copy(&gpu.device, &gpu.queue, &targets[0])
        .expect("submit the copy");
    assert!(
        readers[0]
            .finish_into(&gpu.device, index, &mut [0; 16])
            .is_err()
    );
}

/// A compare video with a still camera draws each half once (`render/still.rs`): its pictures
/// equal the compare picture drawn whole, byte for byte, side by side (points and surface) and
/// the difference, at two playheads, and each layer is drawn once.
#[test]
fn a_still_compare_picture_is_the_compare_drawn_whole_byte_for_byte() {
    use loudscape::picture::compare::{CompareView, render_compare_image};
    use loudscape::render::compare::CompareScene;
    use loudscape::render::grid::difference::DifferenceMeasure;
    use loudscape::render::markers::MarkerBox;
    use loudscape::render::scene::{RenderSettings, Renderer, ViewKind};
    use loudscape::render::still::StillLayer;
    let gpu = common::gpu();
    let renderer = Renderer::new(&gpu.device);
    let a = common::demo_song();
    let b = loudscape::extract::open_for_command(&repo().join("data/fixture_song.ply"))
        .expect("the fixture song");
    let mut scene = CompareScene::new(&gpu.device, &renderer, &a, &b).expect("the compare");
    let size = (480, 200);
    for what in [
        CompareView::SideBySide(ViewKind::Points),
        CompareView::SideBySide(ViewKind::Surface),
        CompareView::Difference(DifferenceMeasure::Density),
    ] {
        let mut stills: [StillLayer; 2] = Default::default();
        for x in [-0.3f32, 0.4] {
            let settings = RenderSettings {
                markers: vec![MarkerBox::playhead(x)],
                ..Default::default()
            };
            let picture = |stills: Option<&mut [StillLayer; 2]>, scene: &mut CompareScene| {
                render_compare_image(
                    &gpu, &renderer, scene, what, None, size, &settings, true, None, stills,
                )
                .expect("the compare picture")
            };
            let whole = picture(None, &mut scene);
            let still = picture(Some(&mut stills), &mut scene);
            let differ = whole
                .pixels()
                .zip(still.pixels())
                .filter(|(p, q)| p != q)
                .count();
            assert_eq!(differ, 0, "{what:?}, playhead {x}: pixels differ");
        }
        let draws = stills.each_ref().map(StillLayer::draws);
        let expected = match what {
            CompareView::SideBySide(_) => [1, 1],
            CompareView::Difference(_) => [1, 0],
        };
        assert_eq!(draws, expected, "{what:?}: each half drawn once");
    }
}
