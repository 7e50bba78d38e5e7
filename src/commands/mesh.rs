//! `loudscape mesh`: not yet built.

use std::path::PathBuf;

#[derive(clap::Args, Debug)]
pub struct MeshArgs {
    /// The point cloud (.ply).
    pub input: PathBuf,
}

pub fn run(args: MeshArgs) -> anyhow::Result<()> {
    anyhow::bail!(
        "{}: 'mesh' is not available in this build yet",
        args.input.display()
    )
}
