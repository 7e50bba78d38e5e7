//! `loudscape bench`: timings of every pass on this machine's GPU (being built).
#[derive(clap::Args, Debug)]
pub struct BenchArgs {}
pub fn run(_args: BenchArgs) -> anyhow::Result<()> {
    anyhow::bail!("bench is not built yet")
}
