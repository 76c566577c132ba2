//! Command-line entry point: parses arguments (clap) and calls the library's commands.

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};
use pedsynth::commands;
use pedsynth::dsl::LoadOptions;

/// Synthetic pedestrian-crossing datasets for autonomous-driving research.
#[derive(Parser)]
#[command(name = "pedsynth", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

/// Options shared by the commands that load a spec.
#[derive(clap::Args)]
struct SpecArgs {
    /// Override a spec value, e.g. `--set crossing.target_ratio=0.5` (YAML value; repeatable).
    #[arg(long = "set", value_name = "KEY.PATH=VALUE")]
    overrides: Vec<String>,
    /// Accept a spec beyond the sanity limits (clip count, image size, estimated dataset size).
    #[arg(long)]
    allow_large: bool,
}

#[derive(Subcommand)]
enum Command {
    /// Validate specs; print a summary line per valid spec and every problem of the invalid ones.
    Validate {
        /// Spec files.
        #[arg(required = true)]
        specs: Vec<PathBuf>,
        /// Print the fully defaulted spec instead of the summary.
        #[arg(long)]
        resolved: bool,
        #[command(flatten)]
        spec_args: SpecArgs,
    },
    /// Compile a spec into a plan and print dry-run statistics (nothing is simulated).
    Plan {
        /// Spec file.
        spec: PathBuf,
        /// Print stable JSON instead of tables.
        #[arg(long)]
        json: bool,
        /// Write the plan (clip scripts) to this JSON file.
        #[arg(long, value_name = "PLAN.json")]
        emit: Option<PathBuf>,
        /// Plan only this clip (e.g. `town01_like-clear_noon-0001`).
        #[arg(long, value_name = "CLIP_ID")]
        only: Option<String>,
        #[command(flatten)]
        spec_args: SpecArgs,
    },
    /// Generate a dataset: plan, simulate, annotate and write Parquet tables (resumable).
    Generate {
        /// Spec file (.yaml) or plan file (.json from `pedsynth plan --emit`).
        input: PathBuf,
        /// Output directory (new, empty, or a partly generated dataset of the same spec to resume).
        #[arg(long, value_name = "DIR")]
        out: PathBuf,
        /// Worker threads (default: one per core).
        #[arg(long, value_name = "N")]
        jobs: Option<usize>,
        /// Generate only this clip.
        #[arg(long, value_name = "CLIP_ID")]
        only: Option<String>,
        /// No progress output.
        #[arg(long)]
        quiet: bool,
        #[command(flatten)]
        spec_args: SpecArgs,
    },
    /// Dataset statistics computed from the written tables.
    Stats {
        /// Dataset directory.
        dir: PathBuf,
        /// Print JSON instead of tables.
        #[arg(long)]
        json: bool,
    },
    /// Print the spec language's JSON Schema (draft-07).
    Schema,
    /// Inspect towns.
    Town {
        #[command(subcommand)]
        command: TownCommand,
    },
}

#[derive(Subcommand)]
enum TownCommand {
    /// List the built-in towns.
    List,
    /// Summarise a town (built-in name or .xodr path); draw it with --png.
    Show {
        /// Built-in town name or path to an OpenDRIVE file.
        town: String,
        /// Write a top-down map to this PNG file.
        #[arg(long, value_name = "OUT.png")]
        png: Option<PathBuf>,
        /// Print summary figures as JSON.
        #[arg(long)]
        json: bool,
    },
}

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(err) => {
            // clap prints usage errors to stderr and --help/--version to stdout; if that fails, the exit code
            // still tells.
            err.print().ok();
            let code = if err.use_stderr() {
                commands::exit::INVALID
            } else {
                commands::exit::OK
            };
            return ExitCode::from(code as u8);
        }
    };
    // Unlocked handles: worker threads print progress to stderr while a command runs.
    let mut out = std::io::stdout();
    let mut err = std::io::stderr();
    let load_options = |spec_args: SpecArgs| LoadOptions {
        overrides: spec_args.overrides,
        allow_large: spec_args.allow_large,
    };
    let result = match cli.command {
        Command::Validate {
            specs,
            resolved,
            spec_args,
        } => commands::validate(&specs, &load_options(spec_args), resolved, &mut out),
        Command::Plan {
            spec,
            json,
            emit,
            only,
            spec_args,
        } => commands::plan(
            &spec,
            &load_options(spec_args),
            &commands::PlanArgs { json, emit, only },
            &mut out,
        ),
        Command::Generate {
            input,
            out: dir,
            jobs,
            only,
            quiet,
            spec_args,
        } => {
            let args = commands::GenerateArgs {
                out: dir,
                jobs,
                only,
                quiet,
            };
            commands::generate(&input, &load_options(spec_args), &args, &mut out)
        }
        Command::Stats { dir, json } => commands::stats(&dir, json, &mut out),
        Command::Schema => commands::schema(&mut out),
        Command::Town {
            command: TownCommand::List,
        } => commands::town_list(&mut out),
        Command::Town {
            command: TownCommand::Show { town, png, json },
        } => commands::town_show(&town, png.as_deref(), json, &mut out),
    };
    let code = commands::finish(result, &mut err);
    ExitCode::from(code as u8)
}
