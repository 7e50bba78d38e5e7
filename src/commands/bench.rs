//! `loudscape bench`: timings of every pass on this machine's GPU (being built).

use std::path::PathBuf;

#[derive(clap::Args, Debug)]
pub struct BenchArgs {
    /// Timed runs per measurement (the median is reported).
    #[arg(long, default_value_t = 10)]
    pub runs: usize,
    /// Isovalue of the isosurface benchmarks.
    #[arg(long, default_value_t = 0.3)]
    pub iso: f32,
    /// Write the benchmark fields here as .npy files (for bench/bench_surface.py).
    #[arg(long)]
    pub fields_dir: Option<PathBuf>,
}

pub fn run(args: BenchArgs) -> anyhow::Result<()> {
    if let Some(dir) = &args.fields_dir {
        if !dir.is_dir() {
            anyhow::bail!("{}: the folder does not exist", dir.display());
        }
    }
    let surfaces = super::bench_surface::run(args.runs, args.iso, args.fields_dir.as_deref())?;
    super::bench_surface::print_paper_comparison(&surfaces);
    Ok(())
}
