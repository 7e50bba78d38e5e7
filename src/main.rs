//! The `loudscape` command: opens the window, or renders, voxelizes, meshes and benchmarks
//! from the command line with the same GPU passes.

mod commands;

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{CommandFactory, Parser, Subcommand};

#[derive(Parser, Debug)]
#[command(
    name = "loudscape",
    version,
    about = "See how music is loud: audio point clouds in 3D"
)]
struct Cli {
    /// Song and/or timeline point clouds (.ply), or audio files (extracted by loudscape-extract
    /// and cached; several audio files or a folder become a timeline), to open in the window.
    files: Vec<PathBuf>,

    /// Open the window in this view.
    #[arg(long, value_enum, ignore_case = true)]
    view: Option<loudscape::render::scene::ViewKind>,

    /// Compare the song with these versions (B, C...; up to 7): side by side, their
    /// difference, playback switching between them at the same moment of the music.
    #[arg(long, num_args = 1..=7)]
    compare: Vec<PathBuf>,

    /// Start playback at this position, in seconds.
    #[arg(long)]
    seek: Option<f64>,

    /// Show the timeline as heard after this playback normalization (the side panel's
    /// "level as heard"; docs/DYNAMICS.md).
    #[arg(long, value_enum, ignore_case = true, default_value_t)]
    normalize: loudscape::data::normalize::Normalization,

    /// Save a screenshot of the window to this PNG once the data is shown, then close.
    #[arg(long, hide = true)]
    screenshot: Option<PathBuf>,

    /// Press these keys once the data is shown (`?`, `F`, `Ctrl+S`; for tests).
    #[arg(long, hide = true)]
    press: Vec<String>,

    /// Print the full error chain and backtraces.
    #[arg(long, global = true)]
    debug: bool,

    /// Quiet: no "wrote ..." summaries (errors are still reported).
    #[arg(short, long, global = true)]
    quiet: bool,

    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Render a view of a cloud to a PNG file, without a window.
    Render(Box<commands::render::RenderArgs>),
    /// Render every view of the given clouds to PNG files in a folder.
    RenderDemo(commands::render::RenderDemoArgs),
    /// Voxelize a cloud and write its density and mean-hp grids (.npy or .nrrd).
    Voxelize(commands::voxelize::VoxelizeArgs),
    /// Extract an isosurface and write it as a mesh (.ply or .obj).
    Mesh(commands::mesh::MeshArgs),
    /// Measure frame and pass timings on this machine's GPU.
    Bench(commands::bench::BenchArgs),
    /// Make an MP4 video of a view with the playhead moving through the song, and its sound.
    Video(Box<commands::video::VideoArgs>),
    /// Compare 2 to 8 releases of a song, aligned in time and matched in loudness: a sheet,
    /// a CSV table or JSON (docs/COMPARE.md).
    Compare(commands::compare::CompareArgs),
    /// Write one web page that shows a song in 3D in the browser (orbit, pan, zoom), the app's
    /// own viewer built for the web; opens from the file system (`make web` builds the viewer).
    Page(commands::page::PageArgs),
}

/// Longest error line printed (characters); longer ones are cut, with an ellipsis.
const MAX_MESSAGE_CHARS: usize = 300;

/// `text` as one line of at most `max` characters: line breaks and other control characters
/// become spaces, runs of spaces one, and the tail is cut with an ellipsis.
fn one_line(text: &str, max: usize) -> String {
    let mut out = String::with_capacity(text.len().min(max + 4));
    let mut chars = 0;
    let mut last_space = false;
    for c in text.trim().chars() {
        let c = if c.is_control() { ' ' } else { c };
        if c == ' ' && last_space {
            continue;
        }
        last_space = c == ' ';
        if chars == max {
            out.truncate(out.trim_end().len());
            out.push('…');
            return out;
        }
        out.push(c);
        chars += 1;
    }
    out
}

/// Vulkan's window-system probing prints "error: XDG_RUNTIME_DIR is invalid or not set in the
/// environment." when the variable names no folder. Commands without a window point it at a
/// private folder (`loudscape-runtime-UID` in the temporary folder, mode 0700) in that case;
/// the window leaves the environment alone. Called first thing, before any thread starts.
#[cfg(target_os = "linux")]
fn headless_runtime_dir() {
    use std::os::unix::fs::{DirBuilderExt, MetadataExt, PermissionsExt};
    let valid = std::env::var_os("XDG_RUNTIME_DIR")
        .map(PathBuf::from)
        .is_some_and(|dir| dir.is_absolute() && dir.is_dir());
    if valid {
        return;
    }
    let Ok(uid) = std::fs::metadata("/proc/self").map(|m| m.uid()) else {
        return;
    };
    let dir = std::env::temp_dir().join(format!("loudscape-runtime-{uid}"));
    let _ = std::fs::DirBuilder::new().mode(0o700).create(&dir);
    // Only a folder that is ours and private (not one planted by someone else).
    let private = std::fs::symlink_metadata(&dir)
        .is_ok_and(|m| m.is_dir() && m.uid() == uid && m.permissions().mode() & 0o077 == 0);
    if private {
        // SAFETY: called at the start of main, before any other thread exists.
        unsafe { std::env::set_var("XDG_RUNTIME_DIR", &dir) };
    }
}

#[cfg(not(target_os = "linux"))]
fn headless_runtime_dir() {}

/// A first FILES argument that is no file and looks like a word (no extension, no folder) was
/// meant as a subcommand: answer as clap does for an unknown one, instead of opening a window.
fn reject_unknown_subcommand(files: &[PathBuf]) {
    let Some(first) = files.first() else {
        return;
    };
    let word = first.to_str().is_some_and(|s| {
        !s.is_empty()
            && s.chars()
                .all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_')
    });
    if word && !first.exists() {
        Cli::command()
            .error(
                clap::error::ErrorKind::InvalidSubcommand,
                format!("unrecognized subcommand '{}'", first.display()),
            )
            .exit();
    }
}

/// The outputs of the window's `--screenshot`: a .png that is none of the files opened.
fn check_screenshot(cli: &Cli) -> anyhow::Result<()> {
    if let Some(shot) = &cli.screenshot {
        let mut inputs: Vec<&std::path::Path> = cli.files.iter().map(PathBuf::as_path).collect();
        inputs.extend(cli.compare.iter().map(PathBuf::as_path));
        commands::args::check_output(shot, &["png"], &inputs)?;
    }
    Ok(())
}

/// Parses the command line. A bad value or a missing argument is reported as every other
/// error is, on one line (clap's message with its list of possible values, without the hint
/// to try --help), with clap's exit status 2; help and version print as clap prints them.
fn parse_command_line() -> Result<Cli, ExitCode> {
    let error = match Cli::try_parse() {
        Ok(cli) => return Ok(cli),
        Err(error) => error,
    };
    use clap::error::ErrorKind;
    if matches!(
        error.kind(),
        ErrorKind::DisplayHelp
            | ErrorKind::DisplayVersion
            | ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand
    ) {
        error.exit();
    }
    let rendered = error.render().to_string();
    let said: Vec<&str> = rendered
        .lines()
        .map(str::trim)
        .filter(|line| !line.is_empty() && !line.starts_with("For more information"))
        .collect();
    let text = said.join(" ");
    let text = text.strip_prefix("error: ").unwrap_or(&text);
    eprintln!("loudscape: error: {}", one_line(text, MAX_MESSAGE_CHARS));
    Err(ExitCode::from(2))
}

fn main() -> ExitCode {
    let cli = match parse_command_line() {
        Ok(cli) => cli,
        Err(status) => return status,
    };
    if cli.command.is_some() {
        headless_runtime_dir();
    } else {
        reject_unknown_subcommand(&cli.files);
    }
    commands::set_quiet(cli.quiet);
    if !cli.debug {
        // No backtrace dumps for users; errors are reported as one line below.
        std::panic::set_hook(Box::new(|info| {
            let text = one_line(&info.to_string(), MAX_MESSAGE_CHARS);
            eprintln!("loudscape: internal error: {text} (run with --debug for details)");
        }));
    }
    // Temporary files go with the process on SIGTERM and SIGINT, as they do on errors.
    if let Err(e) = loudscape::files::remove_temporaries_on_signal() {
        log::warn!("cannot watch for signals: {e}");
    }
    let result = match cli.command {
        None => check_screenshot(&cli).and_then(|()| {
            loudscape::ui::run(loudscape::ui::WindowOptions {
                normalize: cli.normalize,
                files: cli.files,
                screenshot: cli.screenshot,
                view: cli.view,
                compare: cli.compare,
                seek: cli.seek,
                press: cli.press,
            })
        }),
        Some(Command::Render(args)) => match args.draw.compare.clone() {
            Some(compare) => commands::render_compare::run_args(*args, &compare),
            None => commands::render::run(*args),
        },
        Some(Command::RenderDemo(args)) => commands::render::run_demo(args),
        Some(Command::Voxelize(args)) => commands::voxelize::run(args),
        Some(Command::Mesh(args)) => commands::mesh::run(args),
        Some(Command::Bench(args)) => commands::bench::run(args),
        Some(Command::Video(args)) => commands::video::run(*args),
        Some(Command::Compare(args)) => commands::compare::run(args),
        Some(Command::Page(args)) => commands::page::run(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(error) => {
            if cli.debug {
                eprintln!("loudscape: error: {error:?}");
            } else {
                let text = one_line(&format!("{error:#}"), MAX_MESSAGE_CHARS);
                eprintln!("loudscape: error: {text}");
            }
            ExitCode::FAILURE
        }
    }
}

#[cfg(test)]
mod tests {
    use super::one_line;

    #[test]
    fn messages_become_one_short_line() {
        assert_eq!(one_line("a\n  b\tc\r\n", 300), "a b c");
        let long = "x".repeat(1000);
        let cut = one_line(&long, 300);
        assert_eq!(cut.chars().count(), 301);
        assert!(cut.ends_with('…'));
        assert_eq!(one_line("é".repeat(5).as_str(), 3), "ééé…");
        assert_eq!(one_line("short", 300), "short");
    }
}
