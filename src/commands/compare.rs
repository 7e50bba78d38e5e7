//! `loudscape compare A B [C ...]`: 2 to 8 releases of a song aligned in time and matched in
//! loudness (docs/COMPARE.md, "Releases"). The analysis is the extractor's
//! (`loudscape-extract compare`, the one implementation of alignment and loudness); this command
//! takes what the app takes (audio files, or song clouds whose recorded source it finds as
//! playback does, checked against the cloud: `playback::checked_source`), checks the outputs
//! before any work, and hands the extractor absolute paths. A PNG sheet then gains a row of
//! small multiples drawn by the app's own renderer (`compare_multiples.rs`).

use std::path::{Path, PathBuf};
use std::process::Command;

use anyhow::{Context, bail};
use clap::Args;

use loudscape::extract::align::Comparison;
use loudscape::extract::locate;
use loudscape::playback::SourceError;

/// The most versions one comparison takes.
pub const MAX_VERSIONS: usize = 8;

#[derive(Args, Debug)]
pub struct CompareArgs {
    /// The versions, the reference (A) first: audio files or song clouds (.ply, whose source
    /// audio is used).
    #[arg(required = true, num_args = 2..=MAX_VERSIONS)]
    pub versions: Vec<PathBuf>,

    /// Write the sheet: aligned loudness curves, tonal balance at matched loudness, the table
    /// (.png or .pdf); a PNG sheet also shows every version in the 3D view of --sheet-view.
    #[arg(short, long)]
    pub output: Option<PathBuf>,

    /// The view of the sheet's small multiples: every version on shared axes, from one camera.
    #[arg(long, value_enum, ignore_case = true, default_value = "points")]
    pub sheet_view: loudscape::render::scene::ViewKind,

    /// Write the table as CSV, one row a version (.csv).
    #[arg(long)]
    pub csv: Option<PathBuf>,

    /// Print each version's path, offset against A, matching gain, alignment confidence and
    /// metrics as JSON.
    #[arg(long)]
    pub json: bool,

    /// Match loudness to the quietest version (default) or to a service's level
    /// (spotify, youtube, ebu_r128, ...; docs/DYNAMICS.md).
    #[arg(long = "match", default_value = "quietest")]
    pub matched_to: String,
}

/// The audio of one version: the file itself, or a song cloud's recorded source.
fn audio_of(path: &Path) -> anyhow::Result<PathBuf> {
    let is_cloud = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("ply"));
    if !is_cloud {
        if !path.is_file() {
            bail!("{}: no such file", path.display());
        }
        return Ok(path.to_path_buf());
    }
    let cloud = loudscape::data::cloud::load(path)
        .with_context(|| format!("{}: cannot read the cloud", path.display()))?;
    loudscape::playback::checked_source(&cloud).map_err(|e| match e {
        SourceError::NotFound(e) => anyhow::anyhow!(
            "{}: the comparison needs the song's audio, and its source is not found ({e})",
            path.display()
        ),
        e => anyhow::anyhow!(
            "{}: the comparison needs the song's audio: {e}",
            path.display()
        ),
    })
}

pub fn run(args: CompareArgs) -> anyhow::Result<()> {
    if args.output.is_none() && args.csv.is_none() && !args.json {
        bail!("say what to write: -o SHEET.png, --csv TABLE.csv or --json");
    }
    let inputs: Vec<&Path> = args.versions.iter().map(PathBuf::as_path).collect();
    if let Some(sheet) = &args.output {
        super::args::check_output(sheet, &["png", "pdf"], &inputs)?;
    }
    if let Some(csv) = &args.csv {
        super::args::check_output(csv, &["csv"], &inputs)?;
    }
    let audio = args
        .versions
        .iter()
        .map(|p| audio_of(p))
        .collect::<anyhow::Result<Vec<_>>>()?;
    let extractor =
        locate::extractor().map_err(|looked| anyhow::anyhow!(locate::not_found(&looked)))?;
    let mut command = Command::new(&extractor);
    command.arg("compare").arg("--match").arg(&args.matched_to);
    if let Some(sheet) = &args.output {
        command.arg("-o").arg(std::path::absolute(sheet)?);
    }
    if let Some(csv) = &args.csv {
        command.arg("--csv").arg(std::path::absolute(csv)?);
    }
    // A PNG sheet's small multiples need the offsets: the JSON is read here too.
    let multiples = args.output.as_ref().filter(|sheet| {
        sheet
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("png"))
    });
    if args.json || multiples.is_some() {
        command.arg("--json");
    }
    if super::quiet() {
        command.arg("-q");
    }
    command.arg("--");
    for version in &audio {
        command.arg(std::path::absolute(version)?);
    }
    let output = command
        .stderr(std::process::Stdio::inherit())
        .output()
        .with_context(|| format!("cannot run {}", extractor.display()))?;
    if !output.status.success() {
        // The extractor said why, on stderr, in one line.
        bail!("the comparison failed ({})", output.status);
    }
    let json = String::from_utf8_lossy(&output.stdout);
    if args.json {
        print!("{json}");
    }
    if let Some(sheet) = multiples {
        let comparison = Comparison::parse(&json).map_err(anyhow::Error::msg)?;
        let width = image::image_dimensions(sheet)
            .with_context(|| format!("{}: cannot read the sheet back", sheet.display()))?
            .0;
        let row = super::compare_multiples::render_row(
            &args.versions,
            &comparison,
            args.sheet_view,
            width,
        )?;
        super::compare_multiples::append_row(sheet, &row)?;
    }
    Ok(())
}
