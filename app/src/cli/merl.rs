//! `lodestone merl`: a MERL-format table of an analytic plastic, for a preset that names a
//! measured BRDF without the MERL database at hand.

use crate::UsageError;
use crate::cli::args;
use crate::preset_io;
use anyhow::Result;
use lodestone_core::material::merl::{MerlBrdf, ggx_reference};
use std::path::PathBuf;

/// The arguments of `lodestone merl`.
#[derive(Debug, Clone, clap::Args)]
pub struct MerlArgs {
    /// The file to write (atomically).
    #[arg(long)]
    pub out: PathBuf,
    /// Diffuse albedo per channel (linear RGB), 0 to 1 each, comma-separated.
    #[arg(long, default_value = "0.5,0.06,0.05", value_delimiter = ',', value_parser = args::unit_fraction)]
    pub diffuse: Vec<f64>,
    /// Fresnel reflectance at normal incidence (Schlick's F0), 0 to 1.
    #[arg(long, default_value_t = 0.04, value_parser = args::unit_fraction)]
    pub f0: f64,
    /// GGX roughness α, 0.01 to 1.
    #[arg(long, default_value_t = 0.15, value_parser = args::ggx_alpha)]
    pub alpha: f64,
}

/// Tabulate the plastic and write it atomically, after checking where it goes.
pub fn run(args: MerlArgs) -> Result<()> {
    let MerlArgs {
        out,
        diffuse,
        f0,
        alpha,
    } = args;
    let [r, g, b] = diffuse[..] else {
        return Err(UsageError(format!(
            "--diffuse takes three values (red, green, blue), got {}",
            diffuse.len()
        ))
        .into());
    };
    if out.is_dir() {
        return Err(UsageError(format!("--out {}: is a folder", out.display())).into());
    }
    if let Some(dir) = out
        .parent()
        .filter(|d| !d.as_os_str().is_empty() && !d.is_dir())
    {
        return Err(UsageError(format!(
            "--out {}: the folder {} does not exist",
            out.display(),
            dir.display()
        ))
        .into());
    }
    let table = MerlBrdf::tabulate(ggx_reference([r, g, b], [f0; 3], alpha));
    preset_io::write_atomic_bytes(&out, &table.to_bytes())?;
    outln!(
        "wrote {} (MERL BRDF: diffuse {r}, {g}, {b}; F0 {f0}; GGX α {alpha})",
        out.display()
    );
    Ok(())
}
