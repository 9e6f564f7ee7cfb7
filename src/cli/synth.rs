//! `hdi synth afm|ldv|profilometer`: the shipped synthetic sample data.

use anyhow::{bail, Context, Result};
use std::path::PathBuf;

pub(super) fn cmd_synth(
    what: &str,
    out_dir: Option<PathBuf>,
    format: &str,
    revolutions: Option<usize>,
    seed: Option<u64>,
    no_index: bool,
) -> Result<()> {
    match what {
        "ldv" => {
            let dir = out_dir.unwrap_or_else(|| PathBuf::from("raw/ldv"));
            let files = hdi::samples::write_ldv_sample(&dir, format, revolutions, seed, !no_index)?;
            for f in files {
                println!("{}", f.display());
            }
            Ok(())
        }
        "afm" => {
            let dir = out_dir.unwrap_or_else(|| PathBuf::from("raw/afm"));
            hdi::samples::write_afm_samples(&dir)
                .map(|_| ())
                .with_context(|| format!("writing samples to {}", dir.display()))
        }
        "profilometer" => {
            let dir = out_dir.unwrap_or_else(|| PathBuf::from("raw/bulge"));
            let files = hdi::samples::write_profilometer_samples(&dir)
                .with_context(|| format!("writing samples to {}", dir.display()))?;
            for f in files {
                println!("{}", f.display());
            }
            Ok(())
        }
        other => bail!("unknown synth target `{other}` (available: afm, ldv, profilometer)"),
    }
}
