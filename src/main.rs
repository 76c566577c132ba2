//! Command-line entry point: parses arguments (clap) and calls the library's commands.
#![forbid(unsafe_code)]

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};
use pedsynth::cli;
use pedsynth::spec::LoadOptions;

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
    /// Lay a profile over the spec before the overrides (a partial spec, e.g. written by `pedsynth calibrate`).
    #[arg(long, value_name = "PROFILE.yaml")]
    profile: Option<PathBuf>,
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
        /// Progress as one JSON object per finished clip on stderr (`json`, for cluster logs) instead of a bar
        /// on a terminal or plain lines otherwise (`auto`).
        #[arg(long, value_enum, default_value_t = ProgressFormat::Auto)]
        progress: ProgressFormat,
        /// Generate shard I of N (0-based) of the plan's clips, balanced by estimated cost; shards of one run
        /// may write into one --out at once. Without it, read from SLURM_ARRAY_TASK_ID / SLURM_ARRAY_TASK_COUNT
        /// (minus SLURM_ARRAY_TASK_MIN) or Kubernetes' JOB_COMPLETION_INDEX / PEDSYNTH_SHARD_COUNT when set.
        #[arg(long, value_name = "I/N", value_parser = parse_shard)]
        shard: Option<(usize, usize)>,
        #[command(flatten)]
        spec_args: SpecArgs,
    },
    /// Complete a dataset from shards generated into separate directories (or finish a shared --out): link or
    /// copy every clip --out lacks from a directory where it is finished, then write the manifest and card.
    Merge {
        /// Spec file (.yaml) or plan file (.json) the shards were generated from.
        input: PathBuf,
        /// The dataset to complete (created if missing).
        #[arg(long, value_name = "DIR")]
        out: PathBuf,
        /// Shard directories (`generate --shard I/N --out SHARD_DIR`); none: only finish --out.
        shards: Vec<PathBuf>,
        #[command(flatten)]
        spec_args: SpecArgs,
    },
    /// Write a SLURM submit script: a job array generating cost-balanced shards into one --out on shared
    /// storage, and a merge job after it.
    Slurm {
        /// Spec file (.yaml) or plan file (.json), as the jobs will name it.
        input: PathBuf,
        /// Dataset directory, as the jobs will name it (on storage every node sees).
        #[arg(long, value_name = "DIR")]
        out: PathBuf,
        /// Array tasks (shards).
        #[arg(long, value_name = "N")]
        array: usize,
        /// CPUs per task.
        #[arg(long, value_name = "N", default_value_t = 4)]
        cpus: u32,
        /// Wall-time limit per task (sbatch --time); default: three times the plan's estimate plus 10 minutes.
        #[arg(long, value_name = "TIME")]
        time: Option<String>,
        /// Memory per task (sbatch --mem, e.g. 8G).
        #[arg(long, value_name = "SIZE")]
        mem: Option<String>,
        /// Partition.
        #[arg(long)]
        partition: Option<String>,
        /// The pedsynth executable on the nodes.
        #[arg(long, value_name = "PATH", default_value = "pedsynth")]
        pedsynth: String,
        /// Write the script here (executable) instead of standard output.
        #[arg(long, value_name = "FILE")]
        script: Option<PathBuf>,
        #[command(flatten)]
        spec_args: SpecArgs,
    },
    /// Write a Kubernetes Indexed Job manifest (with the resolved spec in a ConfigMap) generating cost-balanced
    /// shards into one dataset directory on a ReadWriteMany volume.
    K8s {
        /// Spec file (.yaml).
        input: PathBuf,
        /// Dataset directory inside the volume (mounted at /data).
        #[arg(long, value_name = "DIR")]
        out: String,
        /// Completions (shards).
        #[arg(long, value_name = "N")]
        completions: usize,
        /// Pods at once (default: all).
        #[arg(long, value_name = "N")]
        parallelism: Option<usize>,
        /// Container image with `pedsynth` on its PATH.
        #[arg(long, default_value = "ghcr.io/pedsynth/pedsynth:latest")]
        image: String,
        /// CPUs per pod.
        #[arg(long, value_name = "N", default_value_t = 4)]
        cpus: u32,
        /// Memory per pod (Kubernetes quantity).
        #[arg(long, value_name = "QUANTITY", default_value = "4Gi")]
        memory: String,
        /// PersistentVolumeClaim (ReadWriteMany) holding the dataset.
        #[arg(long, value_name = "NAME")]
        pvc: String,
        /// Job name (default: from the dataset's name).
        #[arg(long)]
        name: Option<String>,
        /// Read the spec from this path inside the volume instead of a ConfigMap (needed for OpenDRIVE towns).
        #[arg(long, value_name = "PATH")]
        spec_on_volume: Option<String>,
        /// Write the manifest here instead of standard output.
        #[arg(long, value_name = "FILE")]
        manifest: Option<PathBuf>,
        #[command(flatten)]
        spec_args: SpecArgs,
    },
    /// Dataset statistics computed from the written tables (or a benchmark's sampling of them, --protocol).
    Stats {
        /// Dataset directory.
        dir: PathBuf,
        /// Print JSON instead of tables.
        #[arg(long)]
        json: bool,
        /// Report what a benchmark's sampling gets from the dataset: `pab` (PedestrianActionBenchmark:
        /// tracks up to the crossing point, observation windows before it), per class and split.
        #[arg(long, value_enum)]
        protocol: Option<Protocol>,
        /// Frames per observation window (PAB's obs_length).
        #[arg(long, value_name = "FRAMES", default_value_t = 16, requires = "protocol")]
        obs_length: usize,
        /// Frames from a window's end to the event, `MIN,MAX` (PAB's time_to_event).
        #[arg(long, value_name = "MIN,MAX", default_value = "30,60", value_parser = parse_pair, requires = "protocol")]
        tte: (usize, usize),
        /// Overlap of consecutive windows (0.6 PIE, 0.8 JAAD).
        #[arg(long, default_value_t = 0.6, requires = "protocol")]
        overlap: f64,
        /// Shortest eligible track, frames (default: obs length + largest TTE).
        #[arg(long, value_name = "FRAMES", requires = "protocol")]
        min_track: Option<usize>,
    },
    /// Fit a profile to real annotations (JAAD's or PIE's XML layout, or a Parquet/CSV table): the camera's
    /// horizon, height and image size, the frame rate and how long crossers are seen before crossing; prints what
    /// the real data shows (PedestrianActionBenchmark windows, cue table, ego actions). With --compare, the same
    /// measured on a generated dataset, side by side.
    Calibrate {
        /// The real annotations' root directory.
        real_dir: PathBuf,
        /// Their layout.
        #[arg(long, value_enum)]
        format: RealFormat,
        /// Splits to fit to, comma-separated (`all`: every video).
        #[arg(long, value_delimiter = ',', default_value = "train")]
        splits: Vec<String>,
        /// The profile to write (a partial spec for `--profile`).
        #[arg(long, value_name = "PROFILE.yaml")]
        out: PathBuf,
        /// Horizontal field of view assumed for the real camera, degrees (boxes do not fix it).
        #[arg(long, default_value_t = 90.0)]
        fov_deg: f64,
        /// Overlap of the benchmark's windows (0.8 JAAD, 0.6 PIE).
        #[arg(long, default_value_t = 0.8)]
        overlap: f64,
        /// A generated dataset to compare with the real annotations.
        #[arg(long, value_name = "DATASET")]
        compare: Option<PathBuf>,
        /// Write the comparison as Markdown here.
        #[arg(long, value_name = "REPORT.md", requires = "compare")]
        report: Option<PathBuf>,
        /// Print JSON instead of tables.
        #[arg(long)]
        json: bool,
    },
    /// Draw a clip's camera or LiDAR stream with its labels (boxes, ids, states, skeletons): a contact sheet of nine
    /// frames (--out FILE.png) or an animation (--out FILE.gif).
    Preview {
        /// Dataset directory.
        dir: PathBuf,
        /// Clip id (manifest.json lists them).
        #[arg(long, value_name = "CLIP_ID")]
        clip: String,
        /// Stream to show.
        #[arg(long, value_enum, default_value = "rgb")]
        stream: PreviewStream,
        /// Output file: .png (contact sheet) or .gif (animation); default `<clip>.<stream>.png`.
        #[arg(long, value_name = "FILE")]
        out: Option<PathBuf>,
    },
    /// One self-contained HTML page of a dataset's distributions (plots and labelled samples per weather, no
    /// script, nothing loaded from elsewhere), with a second dataset beside it (--compare).
    Report {
        /// Dataset directory.
        dir: PathBuf,
        /// A second generated dataset, or real annotations (JAAD's or PIE's XML, or the table layout `calibrate`
        /// reads), to show beside the first.
        #[arg(long, value_name = "DATASET|REAL")]
        compare: Option<PathBuf>,
        /// The layout of real annotations given to --compare (default: detected from the files).
        #[arg(long, value_enum, requires = "compare")]
        real_format: Option<RealFormat>,
        /// The splits of real annotations to show (default: all the annotations have).
        #[arg(long, value_delimiter = ',', requires = "compare")]
        real_splits: Vec<String>,
        /// Output HTML file.
        #[arg(long, value_name = "FILE.html")]
        out: PathBuf,
    },
    /// Check a dataset: manifest, completeness, every table's hash, metadata, schema, row counts and joins, and
    /// every sensor file's size and SHA-256; exit 0 when clean, 2 with the list of problems.
    Verify {
        /// Dataset directory.
        dir: PathBuf,
        /// Skip reading the sensor files (tables only: fast).
        #[arg(long)]
        tables_only: bool,
    },
    /// Export a finished dataset in a format the field's own tools read unmodified (PIE's `pie_data.py`,
    /// PedestrianActionBenchmark's pose files).
    Export {
        /// Format to write.
        #[arg(value_enum)]
        format: pedsynth::dataset::export::Format,
        /// Dataset directory (written by `pedsynth generate`, every clip done).
        dir: PathBuf,
        /// Output directory (re-running resumes: complete files are kept); for `rerun`, the `.rrd` file.
        #[arg(long, value_name = "DIR")]
        out: PathBuf,
        /// How images get there from the dataset's sensors/.
        #[arg(long, value_enum, default_value = "hard")]
        link: pedsynth::dataset::export::LinkMode,
        /// Copy images (same as `--link copy`).
        #[arg(long, conflicts_with = "link")]
        copy: bool,
        /// The 2D box to export: `tight` (the silhouette's) or `annotator` (as a person draws it); default: the
        /// dataset spec's `annotations.export_box`.
        #[arg(long = "box", value_enum)]
        export_box: Option<BoxArg>,
        /// nuScenes: keyframes (samples, with boxes) per second of a clip; a keyframe every round(fps / HZ)
        /// frames from frame 0.
        #[arg(long, value_name = "HZ", default_value_t = 2.0, value_parser = positive_hz)]
        keyframe_hz: f64,
        /// Rerun: the clip to record (`--out` is then the `.rrd` file).
        #[arg(long, value_name = "ID")]
        clip: Option<String>,
    },
    /// Print the spec language's JSON Schema (draft-07).
    Schema,
    /// Inspect towns.
    Town {
        #[command(subcommand)]
        command: TownCommand,
    },
}

/// A rate above 0 Hz.
fn positive_hz(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
        _ => Err(format!("`{s}` is not a rate above 0 Hz (nuScenes' own is 2)")),
    }
}

/// Streams `preview` can show.
#[derive(Clone, Copy, clap::ValueEnum)]
enum PreviewStream {
    Rgb,
    Semantic,
    Instance,
    Depth,
    Dvs,
    /// LiDAR points from above, coloured by tag, with the 3D boxes.
    Lidar,
}

/// Benchmark protocols of `stats --protocol`.
#[derive(Clone, Copy, clap::ValueEnum)]
enum BoxArg {
    /// The tight box of the projected body.
    Tight,
    /// The annotator box, as a person draws it.
    Annotator,
}

#[derive(Clone, Copy, clap::ValueEnum)]
enum RealFormat {
    /// JAAD's XML (annotations/, annotations_attributes/, annotations_vehicle/, split_ids/).
    Jaad,
    /// PIE's XML (annotations/<setNN>/, annotations_attributes/<setNN>/, annotations_vehicle/<setNN>/).
    Pie,
    /// Tables (videos, boxes, pedestrians, optional vehicle) as Parquet or CSV; DATASET.md documents them.
    Table,
}

#[derive(Clone, Copy, clap::ValueEnum)]
enum Protocol {
    /// PedestrianActionBenchmark (Kotseruba et al., WACV 2021).
    Pab,
}

/// Parses `A,B` into two counts.
fn parse_pair(text: &str) -> Result<(usize, usize), String> {
    let (a, b) = text
        .split_once(',')
        .ok_or_else(|| format!("expected MIN,MAX, found `{text}`"))?;
    let parse = |x: &str| x.trim().parse::<usize>().map_err(|e| format!("`{x}`: {e}"));
    Ok((parse(a)?, parse(b)?))
}

fn parse_shard(text: &str) -> Result<(usize, usize), String> {
    cli::parse_shard(text)
}

/// How `generate` reports progress.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
enum ProgressFormat {
    /// A bar on a terminal, a line every 5 % of the clips otherwise.
    Auto,
    /// One JSON object per finished clip.
    Json,
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
    /// Write a built-in town as OpenDRIVE 1.7 (roads, lanes, marks, junctions, crosswalks, buildings).
    Export {
        /// Built-in town name (see `pedsynth town list`).
        town: String,
        /// The OpenDRIVE file to write.
        #[arg(long, value_name = "OUT.xodr")]
        xodr: PathBuf,
    },
}

fn main() -> ExitCode {
    if let Some(message) = cli::unsupported_cpu() {
        eprint!("{message}");
        return ExitCode::from(pedsynth::error::exit::FAILURE as u8);
    }
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(err) => {
            // clap prints usage errors to stderr and --help/--version to stdout; if that fails, the exit code
            // still tells.
            err.print().ok();
            let code = if err.use_stderr() {
                pedsynth::error::exit::INVALID
            } else {
                pedsynth::error::exit::OK
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
        profile: spec_args.profile,
    };
    let result = match cli.command {
        Command::Validate {
            specs,
            resolved,
            spec_args,
        } => cli::validate(&specs, &load_options(spec_args), resolved, &mut out),
        Command::Plan {
            spec,
            json,
            emit,
            only,
            spec_args,
        } => cli::plan(
            &spec,
            &load_options(spec_args),
            &cli::PlanArgs { json, emit, only },
            &mut out,
        ),
        Command::Generate {
            input,
            out: dir,
            jobs,
            only,
            quiet,
            progress,
            shard,
            spec_args,
        } => {
            let args = cli::GenerateArgs {
                out: dir,
                jobs,
                only,
                quiet,
                progress_json: progress == ProgressFormat::Json,
                shard,
            };
            cli::generate(&input, &load_options(spec_args), &args, &mut out)
        }
        Command::Stats {
            dir,
            json,
            protocol,
            obs_length,
            tte,
            overlap,
            min_track,
        } => {
            let options = protocol.map(|Protocol::Pab| pedsynth::dataset::read::protocol::PabOptions {
                obs_length,
                tte_frames: tte,
                overlap,
                min_track: min_track.unwrap_or(obs_length + tte.1),
            });
            cli::stats(&dir, json, options.as_ref(), &mut out)
        }
        Command::Calibrate {
            real_dir,
            format,
            splits,
            out: profile,
            fov_deg,
            overlap,
            compare,
            report,
            json,
        } => {
            use pedsynth::dataset::calibrate::{CalibrateOptions, Format};
            let mut options = CalibrateOptions {
                format: match format {
                    RealFormat::Jaad => Format::Jaad,
                    RealFormat::Pie => Format::Pie,
                    RealFormat::Table => Format::Table,
                },
                splits: splits.into_iter().filter(|s| s != "all").collect(),
                fov_deg,
                ..CalibrateOptions::default()
            };
            options.pab.overlap = overlap;
            let paths = cli::CalibratePaths {
                real_dir: &real_dir,
                profile: &profile,
                compare: compare.as_deref(),
                report: report.as_deref(),
            };
            cli::calibrate(&paths, &options, json, &mut out)
        }
        Command::Preview {
            dir,
            clip,
            stream,
            out: file,
        } => {
            use pedsynth::dataset::read::preview::{PreviewOptions, Stream};
            let (stream, name) = match stream {
                PreviewStream::Rgb => (Stream::Rgb, "rgb"),
                PreviewStream::Semantic => (Stream::Semantic, "semantic"),
                PreviewStream::Instance => (Stream::Instance, "instance"),
                PreviewStream::Depth => (Stream::Depth, "depth"),
                PreviewStream::Dvs => (Stream::Dvs, "dvs"),
                PreviewStream::Lidar => (Stream::Lidar, "lidar"),
            };
            let file = file.unwrap_or_else(|| PathBuf::from(format!("{clip}.{name}.png")));
            cli::preview(
                &dir,
                &PreviewOptions {
                    clip,
                    stream,
                    out: file,
                },
                &mut out,
            )
        }
        Command::Report {
            dir,
            compare,
            real_format,
            real_splits,
            out: to,
        } => {
            use pedsynth::dataset::calibrate::Format;
            let real_format = real_format.map(|f| match f {
                RealFormat::Jaad => Format::Jaad,
                RealFormat::Pie => Format::Pie,
                RealFormat::Table => Format::Table,
            });
            cli::report(&dir, compare.as_deref(), (real_format, &real_splits), &to, &mut out)
        }
        Command::Export {
            format,
            dir,
            out: to,
            link,
            copy,
            export_box,
            keyframe_hz,
            clip,
        } => {
            let link = if copy {
                pedsynth::dataset::export::LinkMode::Copy
            } else {
                link
            };
            let export_box = export_box.map(|b| match b {
                BoxArg::Tight => pedsynth::spec::types::ExportBox::Tight,
                BoxArg::Annotator => pedsynth::spec::types::ExportBox::Annotator,
            });
            let options = pedsynth::dataset::export::Options {
                link,
                export_box,
                keyframe_hz,
                clip,
            };
            cli::export(&dir, format, &to, &options, &mut out, &mut err)
        }
        Command::Merge {
            input,
            out: dir,
            shards,
            spec_args,
        } => cli::merge(&input, &load_options(spec_args), &dir, &shards, &mut out),
        Command::Slurm {
            input,
            out: dir,
            array,
            cpus,
            time,
            mem,
            partition,
            pedsynth,
            script,
            spec_args,
        } => {
            let options = load_options(spec_args);
            let slurm = pedsynth::cli::cluster::SlurmOptions {
                input: input.display().to_string(),
                overrides: options.overrides.clone(),
                profile: options.profile.as_ref().map(|p| p.display().to_string()),
                out: dir.display().to_string(),
                array,
                cpus,
                time,
                mem,
                partition,
                pedsynth,
            };
            cli::slurm(&input, &options, &slurm, script.as_deref(), &mut out)
        }
        Command::K8s {
            input,
            out: dir,
            completions,
            parallelism,
            image,
            cpus,
            memory,
            pvc,
            name,
            spec_on_volume,
            manifest,
            spec_args,
        } => {
            let k8s = pedsynth::cli::cluster::K8sOptions {
                name,
                completions,
                parallelism,
                image,
                cpus,
                memory,
                pvc,
                out: dir,
                spec_on_volume,
            };
            cli::k8s(&input, &load_options(spec_args), &k8s, manifest.as_deref(), &mut out)
        }
        Command::Verify { dir, tables_only } => cli::verify(&dir, tables_only, &mut out),
        Command::Schema => cli::schema(&mut out),
        Command::Town {
            command: TownCommand::List,
        } => cli::town_list(&mut out),
        Command::Town {
            command: TownCommand::Show { town, png, json },
        } => cli::town_show(&town, png.as_deref(), json, &mut out),
        Command::Town {
            command: TownCommand::Export { town, xodr },
        } => cli::town_export(&town, &xodr, &mut out),
    };
    let code = cli::finish(result, &mut err);
    ExitCode::from(code as u8)
}
