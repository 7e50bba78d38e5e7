//! `loudscape voxelize`: not yet built.

use std::path::PathBuf;

#[derive(clap::Args, Debug)]
pub struct VoxelizeArgs {
    /// The point cloud (.ply).
    pub input: PathBuf,
}

pub fn run(args: VoxelizeArgs) -> anyhow::Result<()> {
    anyhow::bail!(
        "{}: 'voxelize' is not available in this build yet",
        args.input.display()
    )
}
