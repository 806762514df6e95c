//! The command line of `littoral`: subcommands and flags, with their help.

use clap::{Args, Parser, Subcommand};
use littoral::scene::{BoundaryMode, IntegratorMode, SpectralMode};
use littoral::synth::Distribution;
use std::path::PathBuf;

#[derive(Parser)]
#[command(
    name = "littoral",
    version,
    about = "Spectral photon mapping for coastal waters"
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Subcommand)]
pub enum Command {
    /// Render a scene (default: the built-in coastal scene) into a radiance
    /// cube, a quicklook and a report.
    Render(RenderArgs),
    /// Trace a scene's photons into a photon map, with irradiance tallies.
    Emit(EmitArgs),
    /// Scene files: print the built-in scene, validate a file.
    #[command(subcommand)]
    Scene(SceneCommand),
    /// Photon map files: build synthetic maps, inspect, verify, query, dump.
    #[command(subcommand)]
    Map(MapCommand),
    /// Write Slurm batch scripts for a sharded run: an emit job array, the
    /// merge, a render job array and the assembly, chained by submit.sh.
    Plan(PlanArgs),
    /// Assemble the part directories of a render split with `littoral
    /// render --tiles I/N` into the files a whole render writes (cubes
    /// byte-identical to it); the scene is built again from what the parts
    /// recorded, so its files must be where they were. (`littoral-cube
    /// assemble` does the same.)
    Assemble(AssembleArgs),
}

#[derive(Args)]
pub struct AssembleArgs {
    /// Every part directory of the render, any order.
    #[arg(required = true)]
    pub parts: Vec<PathBuf>,
    /// Output directory.
    #[arg(long)]
    pub out: PathBuf,
    /// Worker threads (0 = one per core).
    #[arg(long, default_value_t = 0, value_parser = littoral::cli::threads_arg)]
    pub threads: usize,
}

impl RenderArgs {
    /// The scene overrides the flags give.
    pub fn overrides(&self) -> littoral::scene::Overrides {
        littoral::scene::Overrides {
            photons: self.photons,
            bands: self.bands.map(usize::from),
            seed: self.seed,
            boundary: self.boundary,
            spectral: self.spectral,
            integrator: self.integrator,
            samples_per_pixel: self.spp,
            inelastic: self.inelastic.map(OnOff::on),
            no_atmosphere: self.no_atmosphere,
        }
    }
}

/// A switch given on the command line.
#[derive(Clone, Copy, clap::ValueEnum)]
pub enum OnOff {
    On,
    Off,
}

impl OnOff {
    pub fn on(self) -> bool {
        matches!(self, OnOff::On)
    }
}

impl EmitArgs {
    /// The scene overrides the flags give.
    pub fn overrides(&self) -> littoral::scene::Overrides {
        littoral::scene::Overrides {
            photons: self.photons,
            seed: self.seed,
            inelastic: self.inelastic.map(OnOff::on),
            ..Default::default()
        }
    }
}

#[derive(Args)]
pub struct RenderArgs {
    /// Scene file (TOML); the built-in coastal scene when absent.
    pub scene: Option<PathBuf>,
    /// Output directory.
    #[arg(long, default_value = "out")]
    pub out: PathBuf,
    /// Keep the photon map here, and reuse it when its recorded provenance
    /// matches the scene's emission inputs.
    #[arg(long)]
    pub map: Option<PathBuf>,
    /// Photons to trace (overrides the scene).
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..), allow_hyphen_values = true)]
    pub photons: Option<u64>,
    /// Bands evenly spaced over the scene's own range (its start_nm-end_nm, or the
    /// span of its explicit centres), replacing its grid.
    #[arg(long, value_parser = clap::value_parser!(u16).range(1..), allow_hyphen_values = true)]
    pub bands: Option<u16>,
    /// Worker threads (0 = one per core); outputs are identical for any number.
    #[arg(long, default_value_t = 0, value_parser = littoral::cli::threads_arg)]
    pub threads: usize,
    /// Random seed (overrides the scene).
    #[arg(long)]
    pub seed: Option<u64>,
    /// Memory budget, e.g. 64MiB, 2GiB, 500MB or plain bytes.
    #[arg(long, default_value = "512MiB")]
    pub mem_budget: String,
    /// Boundary-bias compensation (overrides the scene).
    #[arg(long, value_enum)]
    pub boundary: Option<BoundaryMode>,
    /// Spectral-bias compensation (overrides the scene).
    #[arg(long, value_enum)]
    pub spectral: Option<SpectralMode>,
    /// Integrator (overrides the scene's `[render] integrator`): the photon
    /// map, or the unbiased path tracer that needs no map.
    #[arg(long, value_enum)]
    pub integrator: Option<IntegratorMode>,
    /// Samples (paths, for the path integrator) per pixel (overrides the
    /// scene's `[sensor] samples_per_pixel`).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=65536), allow_hyphen_values = true)]
    pub spp: Option<u32>,
    /// Inelastic light on or off, overriding the scene: on turns on water
    /// Raman scattering (`[water] raman`) and, in water given by its
    /// constituents, chlorophyll and CDOM fluorescence
    /// (`[water.fluorescence]`); `off` is the elastic-only ablation.
    #[arg(long, value_enum)]
    pub inelastic: Option<OnOff>,
    /// See the sea from just above the surface, without the air between:
    /// the scene's `[sensor] altitude_m` is dropped, while its
    /// `[atmosphere]` still gives the sun and the sky at the surface (the
    /// same photon map serves both views).
    #[arg(long)]
    pub no_atmosphere: bool,
    /// Render only part I of N of the image tiles into --out (a part
    /// directory), from the photon map at --map; `littoral assemble`
    /// joins the parts. Started again, a part keeps its finished tiles.
    #[arg(long, value_name = "I/N", value_parser = parse_shard, conflicts_with = "resume")]
    pub tiles: Option<(u64, u64)>,
    /// Keep finished tiles in OUT/.NAME.parts so that a killed render,
    /// started again with --resume, renders only the rest.
    #[arg(long)]
    pub resume: bool,
    /// No progress on stderr.
    #[arg(long)]
    pub quiet: bool,
}

#[derive(Subcommand)]
pub enum SceneCommand {
    /// Print the built-in coastal scene (TOML).
    Default,
    /// Validate a scene file; prints a summary on success.
    Check { file: PathBuf },
    /// Print a scene file with keys changed, e.g. `littoral scene set
    /// base.toml sensor.pixels=[48,48] 'water.phase={kind="petzold"}'`.
    Set(SetArgs),
    /// Print a scene's atmosphere as JSON: per band its layers' optical
    /// depths, the sun's beam and the sky at the surface (irradiances and
    /// the sky's radiance per cell), and what leaves the top.
    Atmosphere {
        file: PathBuf,
        /// Also the radiance leaving the top of the atmosphere per cell
        /// (over a black surface).
        #[arg(long)]
        toa: bool,
    },
}

#[derive(Args)]
pub struct SetArgs {
    /// Scene file to start from (`default`: the built-in scene).
    pub base: PathBuf,
    /// KEY=VALUE, the key dotted and the value in TOML; set in order.
    pub changes: Vec<String>,
    /// TOML fragment files merged in (table by table) before the changes.
    #[arg(long)]
    pub merge: Vec<PathBuf>,
}

impl SetArgs {
    /// The scene text these arguments make.
    pub fn scene(&self) -> littoral::Result<littoral::scene::text::SceneText> {
        littoral::scene::text::from_command_line(&self.base, &self.changes, &self.merge)
    }
}

#[derive(Args)]
pub struct EmitArgs {
    /// Scene file (TOML).
    pub scene: PathBuf,
    /// Photon map to write.
    #[arg(long)]
    pub map: PathBuf,
    /// Write the emission report (JSON) here.
    #[arg(long)]
    pub report: Option<PathBuf>,
    /// Photons to trace (overrides the scene).
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..), allow_hyphen_values = true)]
    pub photons: Option<u64>,
    /// Worker threads (0 = one per core); the map is identical for any number.
    #[arg(long, default_value_t = 0, value_parser = littoral::cli::threads_arg)]
    pub threads: usize,
    /// Random seed (overrides the scene).
    #[arg(long)]
    pub seed: Option<u64>,
    /// Inelastic light on or off, overriding the scene (as `render
    /// --inelastic`).
    #[arg(long, value_enum)]
    pub inelastic: Option<OnOff>,
    /// Memory budget, e.g. 64MiB, 2GiB, 500MB or plain bytes.
    #[arg(long, default_value = "256MiB")]
    pub mem_budget: String,
    /// Trace only shard I of N (I from 0) of the photons into a shard file
    /// at --map, to be merged by `littoral map merge`; give every shard and
    /// the merge the same --mem-budget.
    #[arg(long, value_name = "I/N", value_parser = parse_shard)]
    pub shard: Option<(u64, u64)>,
    /// No progress on stderr.
    #[arg(long)]
    pub quiet: bool,
}

/// `I/N` with 0 <= I < N.
pub fn parse_shard(s: &str) -> Result<(u64, u64), String> {
    let (i, n) = s
        .split_once('/')
        .ok_or_else(|| format!("'{s}' is not I/N (e.g. 0/4)"))?;
    let i: u64 = i
        .trim()
        .parse()
        .map_err(|_| format!("'{i}' is not a number"))?;
    let n: u64 = n
        .trim()
        .parse()
        .map_err(|_| format!("'{n}' is not a number"))?;
    if n == 0 || i >= n {
        return Err(format!("{i}/{n}: need 0 <= I < N"));
    }
    Ok((i, n))
}

#[derive(Args)]
pub struct MergeArgs {
    /// The shard files of one sharded emission (`emit --shard I/N`), all of them, any order.
    #[arg(required = true)]
    pub parts: Vec<PathBuf>,
    /// The photon map to write.
    #[arg(long)]
    pub out: PathBuf,
    /// Write the emission report (JSON) here.
    #[arg(long)]
    pub report: Option<PathBuf>,
    /// Memory budget [default: the shards' --mem-budget, which gives the
    /// single run's map to the byte; 256MiB for shards that did not record it].
    #[arg(long)]
    pub mem_budget: Option<String>,
    /// No progress on stderr.
    #[arg(long)]
    pub quiet: bool,
}

#[derive(Subcommand)]
pub enum MapCommand {
    /// Merge the shard files of a sharded emission into one photon map,
    /// byte-identical to a single `emit` with the same --mem-budget.
    Merge(MergeArgs),
    /// Write a synthetic photon map (for tests, benchmarks and low-memory runs).
    Synth(SynthArgs),
    /// Print a JSON summary of a map.
    Info { file: PathBuf },
    /// Decode every tile and check every checksum.
    Verify {
        file: PathBuf,
        #[arg(long)]
        quiet: bool,
    },
    /// Print the photons near a point as JSON, nearest first.
    Query(QueryArgs),
    /// Print every photon as CSV: x,y,z,dx,dy,dz,band,power.
    Dump { file: PathBuf },
}

#[derive(Args)]
pub struct SynthArgs {
    /// Number of photons.
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..), allow_hyphen_values = true)]
    pub photons: u64,
    /// Number of spectral bands (evenly spaced over 400-700 nm).
    #[arg(long, default_value_t = 16, value_parser = clap::value_parser!(u16).range(1..), allow_hyphen_values = true)]
    pub bands: u16,
    /// Random seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Where the photons lie: evenly in a 100 x 100 x 10 m box, or crowded
    /// toward the surface with a quarter on a flat floor at 10 m.
    #[arg(long, value_enum, default_value_t = Distribution::Water)]
    pub distribution: Distribution,
    /// Memory budget, e.g. 64MiB, 2GiB, 500MB or plain bytes.
    #[arg(long, default_value = "256MiB")]
    pub mem_budget: String,
    /// Producer threads (0 = one per core); the map is identical for any number.
    #[arg(long, default_value_t = 0, value_parser = littoral::cli::threads_arg)]
    pub threads: usize,
    /// The map file to write.
    #[arg(long)]
    pub out: PathBuf,
    /// No progress on stderr.
    #[arg(long)]
    pub quiet: bool,
}

#[derive(Args)]
#[command(group(clap::ArgGroup::new("search").required(true).args(["k", "radius"])))]
pub struct QueryArgs {
    pub file: PathBuf,
    /// Query point X,Y,Z in metres.
    #[arg(long, allow_hyphen_values = true)]
    pub at: String,
    /// Number of nearest photons.
    #[arg(long)]
    pub k: Option<usize>,
    /// With --k: ignore photons farther than this (m).
    #[arg(long, requires = "k", allow_hyphen_values = true)]
    pub max_radius: Option<f32>,
    /// All photons within this radius (m).
    #[arg(long, allow_hyphen_values = true)]
    pub radius: Option<f32>,
    /// Only photons of this layer (default: both).
    #[arg(long, value_enum)]
    pub layer: Option<Layer>,
    /// Tile cache budget.
    #[arg(long, default_value = "256MiB")]
    pub mem_budget: String,
}

impl QueryArgs {
    /// The search the flags ask for (radii finite and >= 0).
    pub fn search(&self) -> Result<littoral::store::Search, littoral::Error> {
        for (name, v) in [("--radius", self.radius), ("--max-radius", self.max_radius)] {
            if v.is_some_and(|r| !(r.is_finite() && r >= 0.0)) {
                return Err(littoral::Error::invalid(
                    name,
                    "must be a finite radius >= 0",
                ));
            }
        }
        Ok(match (self.k, self.radius) {
            (Some(k), None) => littoral::store::Search::Nearest {
                k,
                max_radius: self.max_radius,
            },
            (None, Some(radius)) => littoral::store::Search::Radius { radius },
            _ => unreachable!("clap enforces exactly one of --k and --radius"),
        })
    }
}

/// Photon map layers.
#[derive(Clone, Copy, clap::ValueEnum)]
pub enum Layer {
    /// Photons stored at scattering events in the water, travelling down.
    Volume,
    /// Photons stored at scattering events in the water, travelling up.
    VolumeUp,
    /// Photons stored on the floor and targets.
    Surface,
}

impl Layer {
    /// The map's index of the layer.
    pub fn index(self) -> u16 {
        match self {
            Layer::Volume => littoral::photon::LAYER_VOLUME,
            Layer::VolumeUp => littoral::photon::LAYER_VOLUME_UP,
            Layer::Surface => littoral::photon::LAYER_SURFACE,
        }
    }
}

#[derive(Args)]
pub struct PlanArgs {
    /// Scene file (TOML); the built-in coastal scene when absent (written
    /// into the plan directory).
    pub scene: Option<PathBuf>,
    /// Shards of the emission and parts of the render (array tasks).
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..=10000))]
    pub shards: u64,
    /// The plan directory: scripts, shards, parts, logs, the map. On a
    /// cluster it must be on a filesystem every node sees.
    #[arg(long)]
    pub out: PathBuf,
    /// Where the assembled outputs go (default: OUT/results).
    #[arg(long)]
    pub results: Option<PathBuf>,
    /// Memory budget of every task; each asks Slurm for it plus a quarter
    /// plus 256 MiB.
    #[arg(long, default_value = "512MiB")]
    pub mem_budget: String,
    /// CPUs per task (each task runs that many threads).
    #[arg(long, default_value_t = 2, value_parser = clap::value_parser!(u32).range(1..=1024))]
    pub cpus_per_task: u32,
    /// Slurm partition.
    #[arg(long)]
    pub partition: Option<String>,
    /// Time limit per task (Slurm's format, e.g. 2:00:00).
    #[arg(long)]
    pub time: Option<String>,
    /// Photons to trace (overrides the scene).
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..), allow_hyphen_values = true)]
    pub photons: Option<u64>,
    /// Random seed (overrides the scene).
    #[arg(long)]
    pub seed: Option<u64>,
    /// Integrator (overrides the scene).
    #[arg(long, value_enum)]
    pub integrator: Option<IntegratorMode>,
    /// Samples per pixel (overrides the scene).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=65536), allow_hyphen_values = true)]
    pub spp: Option<u32>,
    /// Directory of the littoral and littoral-cube binaries the jobs run
    /// (default: this binary's).
    #[arg(long)]
    pub bin_dir: Option<PathBuf>,
}
