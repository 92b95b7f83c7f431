//! `imudrift diagnose` (being built).

#[derive(clap::Args)]
pub struct Args {}

pub fn run(_args: Args) -> anyhow::Result<()> {
    anyhow::bail!("`imudrift diagnose` is not built yet")
}
