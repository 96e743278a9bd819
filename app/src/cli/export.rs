//! `lodestone export`: the engine bundle, so another engine can run the filtering without Lodestone.

use crate::cli::Context;
use crate::preset_io;
use anyhow::Result;
use std::path::PathBuf;

/// The arguments of `lodestone export`.
#[derive(Debug, Clone, clap::Args)]
pub struct ExportArgs {
    /// Output directory (created if needed).
    #[arg(long)]
    pub out: PathBuf,
}

/// Write the bundle and say where.
pub fn run(args: ExportArgs, ctx: &Context) -> Result<()> {
    let written = preset_io::export_bundle(&ctx.preset, ctx.path.as_deref(), &args.out)?;
    outln!(
        "wrote {} files to {} (see manifest.json)",
        written.len(),
        args.out.display()
    );
    Ok(())
}
