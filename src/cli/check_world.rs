//! `glowbrick check-world`: validate a world file or scene recipe and print its summary.

use crate::world::source::load_path;
use clap::Args;
use std::path::PathBuf;

#[derive(Args)]
pub struct CheckWorldArgs {
    path: PathBuf,
}

impl CheckWorldArgs {
    pub fn run(self) -> Result<(), String> {
        let world = load_path(&self.path).map_err(|e| e.to_string())?;
        println!("{}", world.summary());
        Ok(())
    }
}
