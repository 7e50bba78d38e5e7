//! The side panel's "Loudness report" button: the one-page report of the song shown
//! (`loudscape-extract report SONG -o PDF`, docs/DYNAMICS.md), made in the background.
//!
//! The report goes beside the song's audio as `NAME.loudness-report.pdf`; a file of that name
//! that this button did not just write is never replaced: the next free `NAME.loudness-report-2.pdf`
//! is taken instead. The job's state lives in egui's memory under one id, so the panel needs no
//! field of the app: the button shows "making the report…" while the extractor runs, then the
//! file written with the warnings the extractor printed about the song that the cloud's own
//! (listed under it) do not already say (the audio truncated since the cloud was made: the
//! report's readings are of what decoded), or the extractor's one-line reason.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::{Arc, Mutex};

use eframe::egui;

use crate::data::cloud::{DataMode, PointCloud};

/// Where the report of `song` goes: beside it, under a name no file has yet.
pub fn report_path(song: &Path) -> PathBuf {
    let folder = song.parent().unwrap_or(Path::new(""));
    let stem = song
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "song".into());
    (1..)
        .map(|n| {
            let suffix = if n == 1 {
                String::new()
            } else {
                format!("-{n}")
            };
            folder.join(format!("{stem}.loudness-report{suffix}.pdf"))
        })
        .find(|candidate| std::fs::symlink_metadata(candidate).is_err())
        .expect("a free name")
}

/// What the report is made from: the song's audio when it is found and is the audio the cloud
/// was made from (the whole curves), else the cloud itself (its stored metrics and curves).
pub fn report_input(cloud: &PointCloud) -> PathBuf {
    crate::playback::checked_source(cloud).unwrap_or_else(|_| cloud.path.clone())
}

/// A report written, and what the extractor warned about on the way.
#[derive(Debug, PartialEq)]
struct Written {
    path: PathBuf,
    /// Each `warning:` line's text, the input's path before it shortened to its file name.
    warnings: Vec<String>,
}

#[derive(Default)]
struct Job {
    /// The song the job is for (a new song shows the button again).
    song: PathBuf,
    running: bool,
    result: Option<Result<Written, String>>,
}

type Shared = Arc<Mutex<Job>>;

fn run(extractor: &Path, input: &Path, output: &Path) -> Result<Written, String> {
    let absolute = |p: &Path| std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf());
    let input = absolute(input);
    let out = Command::new(extractor)
        .arg("report")
        .arg("-q")
        .arg("-o")
        .arg(absolute(output))
        .arg("--")
        .arg(&input)
        .output()
        .map_err(|e| format!("cannot run {}: {e}", extractor.display()))?;
    if out.status.success() && output.is_file() {
        let prefix = format!("{}: ", input.display());
        let name = input
            .file_name()
            .map_or_else(String::new, |n| format!("{}: ", n.to_string_lossy()));
        let warnings = crate::extract::lines::Stderr::read_from(&out.stderr[..])
            .warnings
            .into_iter()
            .map(|w| match w.strip_prefix(&prefix) {
                Some(rest) => format!("{name}{rest}"),
                None => w,
            })
            .collect();
        return Ok(Written {
            path: output.to_path_buf(),
            warnings,
        });
    }
    let stderr = String::from_utf8_lossy(&out.stderr);
    let reason = stderr
        .lines()
        .rev()
        .find(|l| !l.trim().is_empty())
        .unwrap_or("the extractor wrote no report")
        .trim()
        .to_string();
    Err(reason)
}

/// The button and its state, for a song cloud (nothing for a timeline).
pub fn report_button(ui: &mut egui::Ui, cloud: &PointCloud) {
    if cloud.meta.mode != DataMode::Song {
        return;
    }
    let id = egui::Id::unique("loudness-report-job");
    let shared: Shared = ui
        .ctx()
        .data_mut(|d| d.get_temp_mut_or_default::<Shared>(id).clone());
    let mut job = shared.lock().unwrap_or_else(|p| p.into_inner());
    if job.song != cloud.path {
        *job = Job {
            song: cloud.path.clone(),
            ..Job::default()
        };
    }
    if job.running {
        ui.horizontal(|ui| {
            ui.spinner();
            ui.label("making the loudness report…");
        });
        ui.ctx()
            .request_repaint_after(std::time::Duration::from_millis(200));
        return;
    }
    let clicked = ui
        .button("Loudness report (PDF)")
        .on_hover_text(
            "One page for a client: EBU Mode readings, PLR, PSR, DR, the curves, each \
             service's gain; written beside the song",
        )
        .clicked();
    match &job.result {
        Some(Ok(written)) => {
            ui.label(egui::RichText::new(format!("wrote {}", written.path.display())).small());
            // Those the cloud's own warnings (listed under the button) do not already say.
            let news = written.warnings.iter().filter(|w| {
                !cloud
                    .warnings()
                    .iter()
                    .any(|own| w.ends_with(own.message.as_str()))
            });
            for warning in news {
                ui.label(
                    egui::RichText::new(format!("warning: {warning}"))
                        .small()
                        .color(ui.visuals().warn_fg_color),
                );
            }
        }
        Some(Err(reason)) => {
            ui.label(
                egui::RichText::new(format!("no report: {reason}"))
                    .small()
                    .color(ui.visuals().warn_fg_color),
            );
        }
        None => {}
    }
    if !clicked {
        return;
    }
    let extractor = match crate::extract::locate::extractor() {
        Ok(path) => path,
        Err(tried) => {
            job.result = Some(Err(crate::extract::locate::not_found(&tried)));
            return;
        }
    };
    let input = report_input(cloud);
    let output = report_path(&input);
    job.running = true;
    job.result = None;
    drop(job);
    let ctx = ui.ctx().clone();
    let shared = shared.clone();
    std::thread::spawn(move || {
        let result = run(&extractor, &input, &output);
        match &result {
            Ok(written) => {
                for warning in &written.warnings {
                    eprintln!("loudscape: warning: loudness report: {warning}");
                }
                eprintln!("wrote {}", written.path.display());
            }
            Err(reason) => eprintln!("loudscape: no loudness report: {reason}"),
        }
        let mut job = shared.lock().unwrap_or_else(|p| p.into_inner());
        job.running = false;
        job.result = Some(result);
        ctx.request_repaint();
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_report_never_takes_the_name_of_a_file_that_is_there() {
        let dir =
            std::env::temp_dir().join(format!("loudscape-report-link-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let song = dir.join("song.flac");
        assert_eq!(report_path(&song), dir.join("song.loudness-report.pdf"));
        std::fs::write(dir.join("song.loudness-report.pdf"), b"the client's copy").unwrap();
        assert_eq!(report_path(&song), dir.join("song.loudness-report-2.pdf"));
        assert_eq!(
            std::fs::read(dir.join("song.loudness-report.pdf")).unwrap(),
            b"the client's copy"
        );
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// A report made of a truncated song: the extractor's warning comes back with the file
    /// written (the panel shows both), not "wrote …" alone.
    #[cfg(unix)]
    #[test]
    fn the_extractors_warnings_come_back_with_the_report() {
        use std::os::unix::fs::PermissionsExt;
        let dir =
            std::env::temp_dir().join(format!("loudscape-report-warn-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let song = dir.join("song.ogg");
        std::fs::write(&song, b"audio").unwrap();
        // `report -q -o OUT -- INPUT`, as the extractor prints a truncated decode.
        let extractor = dir.join("fake-extract");
        std::fs::write(
            &extractor,
            "#!/bin/sh\nprintf 'x' > \"$4\"\n\
             echo \"warning: $6: decoded 1.49 s of 4.00 s (the file ends early)\" >&2\n",
        )
        .unwrap();
        std::fs::set_permissions(&extractor, std::fs::Permissions::from_mode(0o755)).unwrap();
        let output = report_path(&song);
        let written = run(&extractor, &song, &output).expect("a report");
        assert_eq!(written.path, output);
        assert_eq!(
            written.warnings,
            ["song.ogg: decoded 1.49 s of 4.00 s (the file ends early)"]
        );
        let _ = std::fs::remove_dir_all(&dir);
    }
}
