//! Never a silent wrong result, the cache side: the extractor's warnings reach the user on every
//! use of a song's cloud (fresh or cached, written in the metadata or only printed), a damaged
//! cache entry is found by its checksum and extracted again, and a cache folder that cannot be
//! written does not stop `render`. A fake extractor (a shell script that copies a prepared cloud
//! and prints what the real one prints) keeps these fast and independent of Python.

use crate::common::{self, fresh_dir, names_in, runs};

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const TRUNCATED: &str = "decoded 1.49 s of the 4.00 s the file promises";
const CANCEL: &str = "the channels cancel in the mono mix";

/// A song cloud whose metadata carries one warning (the contract's `warnings`).
fn cloud_with_warning(path: &Path) {
    let warnings = [serde_json::json!({"kind": "truncated", "message": TRUNCATED})];
    common::write_song_cloud(
        path,
        2000,
        37.0,
        serde_json::json!({ "warnings": warnings }),
    );
}

/// A fake `loudscape-extract` in `dir`: `--version` answers, `song AUDIO -o OUT` copies
/// `cloud` to OUT, printing the truncation warning (also in the cloud's metadata) and one the
/// metadata does not hold, as an extractor that only prints would.
fn fake_extractor(dir: &Path, cloud: &Path) -> PathBuf {
    let script = dir.join("loudscape-extract");
    let text = format!(
        "#!/bin/sh\n\
         if [ \"$1\" = --version ]; then echo 'loudscape-extract 0.0.1-fake'; exit 0; fi\n\
         echo \"$2\" >> '{runs}'\n\
         echo '{{\"stage\": \"decode\", \"fraction\": 0.5}}'\n\
         echo \"loudscape-extract: warning: $2: {TRUNCATED}\" >&2\n\
         echo \"loudscape-extract: warning: $2: {CANCEL}\" >&2\n\
         cp '{cloud}' \"$4\" || exit 1\n\
         echo \"{{\\\"done\\\": \\\"$4\\\"}}\"\n",
        runs = dir.join("runs.txt").display(),
        cloud = cloud.display(),
    );
    std::fs::write(&script, text).unwrap();
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(&script, std::fs::Permissions::from_mode(0o755)).unwrap();
    }
    script
}

fn render(song: &Path, png: &Path, cache: &Path, extractor: &Path) -> (Output, String) {
    let output = common::loudscape_extracting(
        &[
            "render".as_ref(),
            song.as_os_str(),
            "--size".as_ref(),
            "160x120".as_ref(),
            "-o".as_ref(),
            png.as_os_str(),
        ],
        cache,
        extractor,
    );
    let err = String::from_utf8_lossy(&output.stderr).into_owned();
    assert!(output.status.success(), "render failed: {err}");
    (output, err)
}

/// Each warning once, as `warning: SONG: MESSAGE`.
fn assert_warned(err: &str, song: &Path) {
    for message in [TRUNCATED, CANCEL] {
        let line = format!("warning: {}: {message}", song.display());
        assert_eq!(
            err.lines().filter(|l| *l == line).count(),
            1,
            "expected `{line}` once in:\n{err}"
        );
    }
}

#[test]
fn warnings_travel_with_the_cloud_and_a_damaged_entry_is_extracted_again() {
    let dir = fresh_dir("reliability_warnings_cache");
    let cloud = dir.join("prepared.ply");
    cloud_with_warning(&cloud);
    let extractor = fake_extractor(&dir, &cloud);
    let (song, cache, png) = (dir.join("cut.flac"), dir.join("cache"), dir.join("x.png"));
    std::fs::write(
        &song,
        b"fLaC not really, the fake extractor does not read it",
    )
    .unwrap();

    // Fresh: both warnings, each once (the metadata's and the printed one, not repeated).
    let (_, err) = render(&song, &png, &cache, &extractor);
    assert_warned(&err, &song);
    assert_eq!(runs(&dir), 1);
    let files = names_in(&cache);
    assert_eq!(files.len(), 2, "the cloud and its checksum file: {files:?}");
    let ply = cache.join(files.iter().find(|f| f.ends_with(".ply")).unwrap());
    assert!(
        cache
            .join(format!(
                "{}.sum",
                ply.file_name().unwrap().to_string_lossy()
            ))
            .is_file()
    );

    // Cached: the same warnings, the printed one too (kept in the checksum file).
    let (_, err) = render(&song, &png, &cache, &extractor);
    assert_warned(&err, &song);
    assert_eq!(runs(&dir), 1, "the cache answered");

    // voxelize says them as well.
    let npy = dir.join("grid.npy");
    let output = common::loudscape_extracting(
        &[
            "voxelize".as_ref(),
            song.as_os_str(),
            "--res".as_ref(),
            "64".as_ref(),
            "-o".as_ref(),
            npy.as_os_str(),
        ],
        &cache,
        &extractor,
    );
    let err = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{err}");
    assert_warned(&err, &song);

    // Damage: cut the cached cloud, then flip bytes at the same length. Each time one line says
    // so, the song is extracted again, and the entry is whole after.
    let whole = std::fs::read(&ply).unwrap();
    let cut = &whole[..whole.len() / 2];
    let mut flipped = whole.clone();
    let at = flipped.len() - 100;
    flipped[at] ^= 0x55;
    for (i, damaged) in [cut.to_vec(), flipped].into_iter().enumerate() {
        std::fs::write(&ply, &damaged).unwrap();
        let (_, err) = render(&song, &png, &cache, &extractor);
        let said: Vec<&str> = err.lines().filter(|l| l.contains("is damaged")).collect();
        assert_eq!(said.len(), 1, "{err}");
        assert!(said[0].contains("cut.flac") && said[0].contains("extracting it again"));
        assert_warned(&err, &song);
        assert_eq!(runs(&dir), 2 + i);
        assert_eq!(std::fs::read(&ply).unwrap(), whole, "the entry is replaced");
    }
    // And now it is trusted again, without a word.
    let (_, err) = render(&song, &png, &cache, &extractor);
    assert!(!err.contains("damaged"), "{err}");
    assert_eq!(runs(&dir), 3);
}

#[test]
fn a_cache_that_cannot_be_written_does_not_stop_render() {
    let dir = fresh_dir("reliability_cache_readonly");
    let cloud = dir.join("prepared.ply");
    cloud_with_warning(&cloud);
    let extractor = fake_extractor(&dir, &cloud);
    let song = dir.join("song.wav");
    std::fs::write(&song, b"RIFF not really").unwrap();
    // A folder under a plain file can never be created, whoever runs the test (root included).
    let blocker = dir.join("not-a-folder");
    std::fs::write(&blocker, b"x").unwrap();
    let cache = blocker.join("cache");
    let png = dir.join("r.png");
    let tmp = dir.join("tmp");
    std::fs::create_dir_all(&tmp).unwrap();
    let output = Command::new(env!("CARGO_BIN_EXE_loudscape"))
        .args([
            "render".as_ref(),
            song.as_os_str(),
            "--size".as_ref(),
            "160x120".as_ref(),
        ])
        .args(["-o".as_ref(), png.as_os_str()])
        .env("LOUDSCAPE_CACHE_DIR", &cache)
        .env("LOUDSCAPE_EXTRACT", &extractor)
        .env("TMPDIR", &tmp)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{err}");
    assert!(png.is_file());
    let said: Vec<&str> = err
        .lines()
        .filter(|l| l.contains("cannot write the cloud cache"))
        .collect();
    assert_eq!(said.len(), 1, "one warning about the cache: {err}");
    assert_warned(&err, &song);
    // The temporary extraction is gone (the headless runtime folder may stay).
    let left: Vec<String> = names_in(&tmp)
        .into_iter()
        .filter(|name| !name.starts_with("loudscape-runtime"))
        .collect();
    assert!(left.is_empty(), "{left:?}");
}

/// Whether process `pid` is gone (or a zombie waiting for a reaper: it runs no more).
#[cfg(target_os = "linux")]
fn gone(pid: &str) -> bool {
    match std::fs::read_to_string(format!("/proc/{pid}/stat")) {
        Err(_) => true,
        Ok(stat) => stat
            .rsplit_once(')')
            .is_some_and(|(_, rest)| rest.trim_start().starts_with('Z')),
    }
}

/// SIGTERM or SIGINT to `render` while the extractor runs kills the extractor and what it
/// started (its process group), and leaves no temporary folder in the cache.
#[cfg(target_os = "linux")]
#[test]
fn stopping_render_kills_the_extractor_and_leaves_nothing() {
    for signal in ["TERM", "INT"] {
        let dir = fresh_dir(&format!("reliability_stop_{signal}"));
        let script = dir.join("loudscape-extract");
        let pids = dir.join("pids.txt");
        std::fs::write(
            &script,
            format!(
                "#!/bin/sh\n\
                 if [ \"$1\" = --version ]; then echo 'loudscape-extract 0.0.1-busy'; exit 0; fi\n\
                 sleep 600 &\n\
                 echo \"$$ $!\" > '{pids}.tmp'; mv '{pids}.tmp' '{pids}'\n\
                 echo partial > \"$4\"\n\
                 while :; do :; done\n",
                pids = pids.display()
            ),
        )
        .unwrap();
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(&script, std::fs::Permissions::from_mode(0o755)).unwrap();
        let song = dir.join("song.wav");
        std::fs::write(&song, b"RIFF").unwrap();
        let cache = dir.join("cache");
        let png = dir.join("x.png");
        let mut render = Command::new(env!("CARGO_BIN_EXE_loudscape"))
            .args([
                "render".as_ref(),
                song.as_os_str(),
                "-o".as_ref(),
                png.as_os_str(),
            ])
            .env("LOUDSCAPE_CACHE_DIR", &cache)
            .env("LOUDSCAPE_EXTRACT", &script)
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        let start = std::time::Instant::now();
        while !pids.exists() {
            assert!(
                start.elapsed().as_secs() < 60,
                "the extractor never started"
            );
            std::thread::sleep(std::time::Duration::from_millis(50));
        }
        let text = std::fs::read_to_string(&pids).unwrap();
        let (extractor, grandchild) = text.trim().split_once(' ').unwrap();
        let (extractor, grandchild) = (extractor.to_string(), grandchild.to_string());
        assert!(!gone(&extractor) && !gone(&grandchild));
        let status = Command::new("kill")
            .args([format!("-{signal}"), render.id().to_string()])
            .status()
            .unwrap();
        assert!(status.success());
        let code = render.wait().unwrap();
        assert!(!code.success(), "{code:?}");
        let start = std::time::Instant::now();
        while !(gone(&extractor) && gone(&grandchild)) {
            assert!(
                start.elapsed().as_secs() < 10,
                "SIG{signal}: the extractor ({extractor}) or its child ({grandchild}) still runs"
            );
            std::thread::sleep(std::time::Duration::from_millis(50));
        }
        let left: Vec<_> = std::fs::read_dir(&cache)
            .map(|d| d.flatten().map(|e| e.file_name()).collect())
            .unwrap_or_default();
        assert!(left.is_empty(), "SIG{signal}: left in the cache: {left:?}");
        assert!(!png.exists());
    }
}

/// FIFOs and devices are refused at once by every command, with one line naming them: before,
/// `render` hashed a FIFO for the cache key forever and `/dev/zero` without end.
#[cfg(unix)]
#[test]
fn fifos_and_devices_are_refused_by_every_command() {
    let dir = fresh_dir("reliability_fifo");
    let fifo = dir.join("song.wav");
    assert!(
        Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .unwrap()
            .success()
    );
    let fifo_npy = dir.join("grid.npy");
    assert!(
        Command::new("mkfifo")
            .arg(&fifo_npy)
            .status()
            .unwrap()
            .success()
    );
    let zero = Path::new("/dev/zero");
    let ok = dir.join("ok.ply");
    cloud_with_warning(&ok);
    let out = |name: &str| dir.join(name).into_os_string();
    let cases: Vec<(Vec<std::ffi::OsString>, &Path, &str)> = vec![
        (
            vec![
                "render".into(),
                fifo.clone().into(),
                "-o".into(),
                out("a.png"),
            ],
            &fifo,
            "FIFO",
        ),
        (
            vec!["render".into(), zero.into(), "-o".into(), out("b.png")],
            zero,
            "character device",
        ),
        (
            vec![
                "mesh".into(),
                fifo.clone().into(),
                "-o".into(),
                out("c.obj"),
            ],
            &fifo,
            "FIFO",
        ),
        (
            vec![
                "mesh".into(),
                fifo_npy.clone().into(),
                "-o".into(),
                out("d.obj"),
            ],
            &fifo_npy,
            "FIFO",
        ),
        (
            vec!["voxelize".into(), zero.into(), "-o".into(), out("e.npy")],
            zero,
            "character device",
        ),
        (
            vec![
                "render".into(),
                ok.clone().into(),
                "--compare".into(),
                fifo.clone().into(),
                "--view".into(),
                "compare".into(),
                "-o".into(),
                out("f.png"),
            ],
            &fifo,
            "FIFO",
        ),
    ];
    for (args, input, what) in cases {
        let mut child = Command::new(env!("CARGO_BIN_EXE_loudscape"))
            .args(&args)
            .env("LOUDSCAPE_CACHE_DIR", dir.join("cache"))
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        let start = std::time::Instant::now();
        let status = loop {
            if let Some(status) = child.try_wait().unwrap() {
                break status;
            }
            if start.elapsed().as_secs() > 30 {
                let _ = child.kill();
                panic!("{args:?} blocked on {}", input.display());
            }
            std::thread::sleep(std::time::Duration::from_millis(20));
        };
        let mut err = String::new();
        std::io::Read::read_to_string(&mut child.stderr.take().unwrap(), &mut err).unwrap();
        assert!(!status.success(), "{args:?}: {err}");
        let errors: Vec<&str> = err.lines().filter(|l| l.contains("error")).collect();
        assert_eq!(errors.len(), 1, "{args:?}: {err}");
        assert!(
            errors[0].contains(&input.display().to_string()) && errors[0].contains(what),
            "{args:?}: {err}"
        );
    }
}

/// A cloud with no points is refused with one line by the commands that draw or grid it (it
/// rendered an empty picture with exit 0).
#[test]
fn an_empty_cloud_is_refused_by_the_commands() {
    let dir = fresh_dir("reliability_empty");
    let empty = dir.join("empty.ply");
    let mut bytes = Vec::new();
    loudscape::data::cloud::write(&mut bytes, &[], None).unwrap();
    std::fs::write(&empty, bytes).unwrap();
    for (command, out) in [
        ("render", "e.png"),
        ("voxelize", "e.npy"),
        ("mesh", "e.obj"),
    ] {
        let out = dir.join(out);
        let output = Command::new(env!("CARGO_BIN_EXE_loudscape"))
            .args([
                command.as_ref(),
                empty.as_os_str(),
                "-o".as_ref(),
                out.as_os_str(),
            ])
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&output.stderr);
        assert!(!output.status.success(), "{command}: {err}");
        assert_eq!(err.trim().lines().count(), 1, "{command}: {err}");
        assert!(
            err.contains("empty.ply") && err.contains("no points"),
            "{command}: {err}"
        );
        assert!(!out.exists());
    }
}
