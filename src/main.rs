//! Command-line entry point: parses arguments and calls the library.
use std::path::PathBuf;

use clap::{Parser, Subcommand};

#[derive(Parser)]
#[command(
    name = "pedsynth",
    version,
    about = "Synthetic pedestrian-crossing datasets"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Road networks: built-in towns and OpenDRIVE maps.
    Town {
        #[command(subcommand)]
        command: TownCommand,
    },
}

#[derive(Subcommand)]
enum TownCommand {
    /// List the built-in towns.
    List,
    /// Summarise a town and optionally draw it.
    Show {
        /// A built-in town name or a path to an .xodr file.
        name_or_xodr: String,
        /// Write a top-down PNG map here.
        #[arg(long)]
        png: Option<PathBuf>,
        /// Print the summary as JSON.
        #[arg(long)]
        json: bool,
    },
}

fn main() -> miette::Result<()> {
    let cli = Cli::parse();
    match cli.command {
        Command::Town {
            command: TownCommand::List,
        } => print!("{}", pedsynth::world::town_list_text()),
        Command::Town {
            command:
                TownCommand::Show {
                    name_or_xodr,
                    png,
                    json,
                },
        } => {
            print!(
                "{}",
                pedsynth::world::town_show(&name_or_xodr, png.as_deref(), json)?
            )
        }
    }
    Ok(())
}
