//! The `loudscape` command: opens the window, or renders, voxelizes, meshes and benchmarks
//! from the command line with the same GPU passes.

mod commands;

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};

#[derive(Parser, Debug)]
#[command(
    name = "loudscape",
    version,
    about = "See how music is loud: audio point clouds in 3D"
)]
struct Cli {
    /// Song and/or timeline point clouds (.ply) to open in the window.
    files: Vec<PathBuf>,

    /// Open the window in this view: points, surface or volume.
    #[arg(long, value_parser = parse_view)]
    view: Option<loudscape::render::scene::ViewKind>,

    /// Save a screenshot of the window to this PNG once the data is shown, then close.
    #[arg(long, hide = true)]
    screenshot: Option<PathBuf>,

    /// Print the full error chain and backtraces.
    #[arg(long, global = true)]
    debug: bool,

    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Render a view of a cloud to a PNG file, without a window.
    Render(commands::render::RenderArgs),
    /// Render every view of the given clouds to PNG files in a folder.
    RenderDemo(commands::render::RenderDemoArgs),
    /// Voxelize a cloud and write its density and mean-hp grids (.npy or .nrrd).
    Voxelize(commands::voxelize::VoxelizeArgs),
    /// Extract an isosurface and write it as a mesh (.ply or .obj).
    Mesh(commands::mesh::MeshArgs),
    /// Measure frame and pass timings on this machine's GPU.
    Bench(commands::bench::BenchArgs),
}

fn parse_view(name: &str) -> Result<loudscape::render::scene::ViewKind, String> {
    loudscape::render::scene::ViewKind::parse(name)
        .ok_or_else(|| format!("'{name}' is not one of points, surface, volume"))
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    if !cli.debug {
        // No backtrace dumps for users; errors are reported as one line below.
        std::panic::set_hook(Box::new(|info| {
            eprintln!("loudscape: internal error: {info} (run with --debug for details)");
        }));
    }
    let result = match cli.command {
        None => loudscape::ui::run(loudscape::ui::WindowOptions {
            files: cli.files,
            screenshot: cli.screenshot,
            view: cli.view,
        }),
        Some(Command::Render(args)) => commands::render::run(args),
        Some(Command::RenderDemo(args)) => commands::render::run_demo(args),
        Some(Command::Voxelize(args)) => commands::voxelize::run(args),
        Some(Command::Mesh(args)) => commands::mesh::run(args),
        Some(Command::Bench(args)) => commands::bench::run(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(error) => {
            if cli.debug {
                eprintln!("loudscape: error: {error:?}");
            } else {
                eprintln!("loudscape: error: {error:#}");
            }
            ExitCode::FAILURE
        }
    }
}
