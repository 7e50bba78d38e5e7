//! `loudscape bench`: timings of every pass on this machine's GPU.

use std::path::PathBuf;

#[derive(clap::Args, Debug)]
pub struct BenchArgs {
    /// Timed runs per stage (the median is reported).
    #[arg(long, default_value_t = 11)]
    pub runs: usize,
    /// Also write the benchmark's point clouds (raw float32, five per point) to this folder,
    /// for bench/bench_voxelize.py.
    #[arg(long)]
    pub export_points: Option<PathBuf>,
}

pub fn run(args: BenchArgs) -> anyhow::Result<()> {
    super::bench_volume::run(args.runs, args.export_points.as_ref())
}
