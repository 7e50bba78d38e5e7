//! The cloud cache shared and abused: a cloud without its checksum file is never trusted
//! (extracted again, no checksum written for bytes nobody vouched for), renders of one song at
//! once each write under names of their own and leave a valid pair, an extraction that cannot be
//! written in the cache folder (a full disk) still renders, and what a killed run left in the
//! cache is removed on the next run when its process is gone. A fake extractor (a shell script
//! copying a prepared cloud, as in `reliability_cache`) keeps these fast and free of Python.

use crate::common::{self, fresh_dir, names_in, runs};

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

use sha2::{Digest, Sha256};

/// A song cloud whose metadata holds an integrated loudness of `lufs` (written with two
/// decimals, so one digit can be changed in place) and whose points depend on `seed`.
fn cloud_with_metrics(path: &Path, lufs: f64, seed: f32) {
    let metrics = serde_json::json!({ "metrics": {"integrated_lufs": lufs} });
    common::write_song_cloud(path, 3000, 37.0 + seed, metrics);
}

/// A fake `loudscape-extract` in `dir`: `--version` answers; `song AUDIO -o OUT` appends AUDIO
/// to `runs.txt` and copies `dir/clouds/NAME.ply` (NAME: the audio's file name) to OUT. With
/// `together` runs, each waits until that many have started (so they finish together); an
/// output under `full` fails as the real extractor does on a full disk.
fn fake_extractor(dir: &Path, together: usize, full: Option<&Path>) -> PathBuf {
    let script = dir.join("loudscape-extract");
    let full_check = match full {
        Some(full) => format!(
            "case \"$4\" in '{full}'/*) \
             echo \"{{\\\"error\\\": \\\"$4: no space left on the device of '$(dirname \"$4\")', \
             0 bytes free; nothing was written\\\"}}\"; exit 1;; esac\n",
            full = full.display()
        ),
        None => String::new(),
    };
    let text = format!(
        "#!/bin/sh\n\
         if [ \"$1\" = --version ]; then echo 'loudscape-extract 0.0.1-fake'; exit 0; fi\n\
         echo \"$2\" >> '{dir}/runs.txt'\n\
         {full_check}\
         touch '{dir}/started-'$$\n\
         i=0\n\
         while [ $(ls '{dir}' | grep -c '^started-') -lt {together} ]; do\n\
           i=$((i + 1)); [ $i -gt 6000 ] && exit 3; sleep 0.01\n\
         done\n\
         cp \"{dir}/clouds/$(basename \"$2\").ply\" \"$4\" || exit 1\n\
         echo \"{{\\\"done\\\": \\\"$4\\\"}}\"\n",
        dir = dir.display(),
    );
    std::fs::write(&script, text).unwrap();
    use std::os::unix::fs::PermissionsExt;
    std::fs::set_permissions(&script, std::fs::Permissions::from_mode(0o755)).unwrap();
    std::fs::create_dir_all(dir.join("clouds")).unwrap();
    script
}

fn render_command(song: &Path, png: &Path, cache: &Path, extractor: &Path) -> Command {
    let mut command = Command::new(env!("CARGO_BIN_EXE_loudscape"));
    command
        .args(["render".as_ref(), song.as_os_str()])
        .args(["--size", "120x90", "-o"])
        .arg(png)
        .env("LOUDSCAPE_CACHE_DIR", cache)
        .env("LOUDSCAPE_EXTRACT", extractor);
    command
}

fn render(song: &Path, png: &Path, cache: &Path, extractor: &Path) -> (Output, String) {
    let output = render_command(song, png, cache, extractor)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&output.stderr).into_owned();
    assert!(output.status.success(), "render failed: {err}");
    (output, err)
}

/// The cache's one cloud file.
fn entry(cache: &Path) -> PathBuf {
    let clouds: Vec<PathBuf> = std::fs::read_dir(cache)
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|e| e == "ply"))
        .collect();
    assert_eq!(clouds.len(), 1, "{clouds:?}");
    clouds[0].clone()
}

fn sum_of(ply: &Path) -> PathBuf {
    let mut name = ply.file_name().unwrap().to_os_string();
    name.push(".sum");
    ply.with_file_name(name)
}

/// The checksum file of `ply` vouches for its bytes.
fn assert_valid_pair(ply: &Path) {
    let bytes = std::fs::read(ply).unwrap();
    let text = std::fs::read_to_string(sum_of(ply)).expect("the checksum file");
    let sum: serde_json::Value = serde_json::from_str(&text).unwrap();
    let sha: String = Sha256::digest(&bytes)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect();
    assert_eq!(sum["sha256"], sha.as_str(), "the pair does not match");
    assert_eq!(sum["bytes"], bytes.len() as u64);
}

/// A cloud whose checksum file is gone and one of whose metrics was changed (-9.77 LUFS made
/// -8.77) is not used: the song is extracted again, the entry is the fresh cloud with its own
/// checksum, and no checksum file is ever written for the changed bytes.
#[test]
fn a_cloud_without_its_checksum_is_extracted_again_not_trusted() {
    let dir = fresh_dir("reliability_cache_no_sum");
    let extractor = fake_extractor(&dir, 1, None);
    let song = dir.join("song.wav");
    std::fs::write(&song, b"RIFF not really").unwrap();
    let fresh = dir.join("clouds/song.wav.ply");
    cloud_with_metrics(&fresh, -9.77, 0.0);
    let (cache, png) = (dir.join("cache"), dir.join("x.png"));
    render(&song, &png, &cache, &extractor);
    assert_eq!(runs(&dir), 1);
    let ply = entry(&cache);
    let whole = std::fs::read(&ply).unwrap();
    assert_eq!(whole, std::fs::read(&fresh).unwrap());

    let at = whole
        .windows(5)
        .position(|w| w == b"-9.77")
        .expect("the metric in the header");
    let mut damaged = whole.clone();
    damaged[at + 1] = b'8';
    std::fs::write(&ply, &damaged).unwrap();
    std::fs::remove_file(sum_of(&ply)).unwrap();

    let (_, err) = render(&song, &png, &cache, &extractor);
    assert_eq!(runs(&dir), 2, "the unchecked cloud was used: {err}");
    let said: Vec<&str> = err
        .lines()
        .filter(|l| l.contains("no checksum file"))
        .collect();
    assert_eq!(said.len(), 1, "one line says why: {err}");
    assert!(said[0].contains("song.wav") && said[0].contains("extracting it again"));
    assert_eq!(std::fs::read(&ply).unwrap(), whole, "the fresh cloud");
    assert_valid_pair(&ply);

    // The same with no extractor to be found: the unchecked cloud does not open and gets no
    // checksum file.
    std::fs::write(&ply, &damaged).unwrap();
    std::fs::remove_file(sum_of(&ply)).unwrap();
    let output = render_command(&song, &png, &cache, &dir.join("no-such-extractor"))
        .output()
        .unwrap();
    assert!(!output.status.success());
    assert!(!sum_of(&ply).exists(), "a checksum for unchecked bytes");
}

/// Four renders of copies of one song into one cache at once, five times: all succeed without
/// a word about the cache, and the entry left is a cloud with its own checksum file (each copy
/// extracts to different bytes, as real clouds record their source's path, so a cloud paired
/// with another's checksum would show). Nothing else is left in the cache.
#[test]
fn renders_of_one_song_at_once_leave_a_valid_pair() {
    for trial in 0..5 {
        let dir = fresh_dir(&format!("reliability_cache_together_{trial}"));
        let extractor = fake_extractor(&dir, 4, None);
        let cache = dir.join("cache");
        let children: Vec<_> = (0..4)
            .map(|i| {
                let song = dir.join(format!("copy{i}.wav"));
                std::fs::write(&song, b"RIFF the same bytes in every copy").unwrap();
                cloud_with_metrics(
                    &dir.join(format!("clouds/copy{i}.wav.ply")),
                    -9.77,
                    i as f32,
                );
                render_command(&song, &dir.join(format!("{i}.png")), &cache, &extractor)
                    .stderr(Stdio::piped())
                    .spawn()
                    .unwrap()
            })
            .collect();
        for child in children {
            let output = child.wait_with_output().unwrap();
            let err = String::from_utf8_lossy(&output.stderr);
            assert!(output.status.success(), "trial {trial}: {err}");
            for word in ["cloud cache", "damaged", "trusted"] {
                assert!(!err.contains(word), "trial {trial}: {err}");
            }
        }
        assert_eq!(runs(&dir), 4, "trial {trial}: each render missed");
        let ply = entry(&cache);
        assert_valid_pair(&ply);
        assert_eq!(names_in(&cache).len(), 2, "{:?}", names_in(&cache));
        // And a fifth render trusts it.
        let (_, err) = render(
            &dir.join("copy0.wav"),
            &dir.join("5.png"),
            &cache,
            &extractor,
        );
        assert_eq!(runs(&dir), 4, "trial {trial}: {err}");
    }
}

/// An extraction that fails for want of room in the cache folder (the extractor says "no space
/// left" about its output there) is done again in the temporary folder: one warning, the
/// picture, exit 0, nothing kept or left.
#[test]
fn a_full_cache_disk_does_not_stop_render() {
    let dir = fresh_dir("reliability_cache_full");
    let cache = dir.join("cache");
    let extractor = fake_extractor(&dir, 1, Some(&cache));
    let song = dir.join("song.wav");
    std::fs::write(&song, b"RIFF not really").unwrap();
    cloud_with_metrics(&dir.join("clouds/song.wav.ply"), -9.77, 0.0);
    let tmp = dir.join("tmp");
    std::fs::create_dir_all(&tmp).unwrap();
    let png = dir.join("x.png");
    let output = render_command(&song, &png, &cache, &extractor)
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
    assert_eq!(said.len(), 1, "one warning: {err}");
    assert!(said[0].contains("no space left"), "{err}");
    assert_eq!(
        runs(&dir),
        2,
        "once in the cache, once in the temporary folder"
    );
    assert!(names_in(&cache).is_empty(), "{:?}", names_in(&cache));
    let left: Vec<String> = names_in(&tmp)
        .into_iter()
        .filter(|name| !name.starts_with("loudscape-runtime"))
        .collect();
    assert!(left.is_empty(), "{left:?}");
}

/// A killed render's private folder (`.extract-PID-N`) is removed on the next run when its
/// process is gone, minutes after, not a day after; one of a process that still runs is kept.
#[test]
fn leftovers_of_dead_processes_are_removed_on_the_next_run() {
    let dir = fresh_dir("reliability_cache_leftovers");
    let extractor = fake_extractor(&dir, 1, None);
    let song = dir.join("song.wav");
    std::fs::write(&song, b"RIFF not really").unwrap();
    cloud_with_metrics(&dir.join("clouds/song.wav.ply"), -9.77, 0.0);
    let cache = dir.join("cache");
    let mut dead = Command::new("true").spawn().unwrap();
    let dead_pid = dead.id();
    dead.wait().unwrap();
    let live = Running(
        Command::new("sleep")
            .arg("600")
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap(),
    );
    let plant = |pid: u32| {
        let folder = cache.join(format!(".extract-{pid}-0"));
        std::fs::create_dir_all(&folder).unwrap();
        std::fs::write(folder.join("cloud.ply"), vec![0u8; 4096]).unwrap();
        folder
    };
    let (dead_folder, live_folder) = (plant(dead_pid), plant(live.0.id()));
    // Once on a miss (the song is extracted), once on a hit.
    for pass in 0..2 {
        render(&song, &dir.join("x.png"), &cache, &extractor);
        assert!(
            !dead_folder.exists(),
            "pass {pass}: the dead process's folder stays"
        );
        assert!(
            live_folder.is_dir(),
            "pass {pass}: a running process's folder went"
        );
        if pass == 0 {
            plant(dead_pid);
        }
    }
    assert_eq!(runs(&dir), 1);
}

/// A child process killed and reaped when dropped (a failed assertion included).
struct Running(std::process::Child);

impl Drop for Running {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}
