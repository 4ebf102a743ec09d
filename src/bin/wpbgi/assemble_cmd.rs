//! `wpbgi assemble`: the tiles of one frame (`render --tile` or `--crop`) stitched into the
//! frame, byte for byte what one process would have rendered (see [`wpbgi::assemble`]).

use anyhow::Result;
use clap::Args;
use std::path::PathBuf;

#[derive(Args)]
pub struct AssembleArgs {
    /// The tiles of one frame: EXRs from `render --tile` or `--crop` of the same render. Their
    /// data windows say where each goes; they must cover the frame exactly once (a missing or
    /// an overlapping tile is refused, and nothing is written).
    #[arg(required = true)]
    pub tiles: Vec<PathBuf>,
    /// The frame to write (OpenEXR, atomically).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Write one JSON document to standard output: the frame's file, size, tile count and
    /// channels; a failure as {"error": ...}.
    #[arg(long)]
    pub json: bool,
}

pub fn assemble_command(a: AssembleArgs) -> Result<()> {
    crate::interrupt::guard_outputs(std::iter::once(a.output.clone()));
    let done = wpbgi::assemble::assemble(&a.tiles, &a.output)?;
    say!(
        "wrote {} ({}x{} from {} tiles)",
        a.output.display(),
        done.width,
        done.height,
        done.tiles
    );
    if a.json {
        println!(
            "{}",
            serde_json::json!({
                "command": "assemble",
                "output": a.output.display().to_string(),
                "size": [done.width, done.height],
                "tiles": done.tiles,
                "channels": done.channels,
            })
        );
    }
    Ok(())
}
