//! The `littoral` command line. Thin: parsing, progress bars and exit codes;
//! the library does the work.

use clap::{Args, Parser, Subcommand};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use littoral::job::{EmitJob, MemoryBudget, RenderJob};
use littoral::progress::Progress;
use littoral::scene::{BoundaryMode, Overrides, Scene, SpectralMode};
use littoral::store::{build_map, MapFile, PhotonMap, PhotonQuery, Search};
use littoral::synth::{Distribution, SynthSource};
use std::io::Write;
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::Mutex;
use std::time::Instant;

#[derive(Parser)]
#[command(
    name = "littoral",
    version,
    about = "Spectral photon mapping for coastal waters"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
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
}

#[derive(Args)]
struct RenderArgs {
    /// Scene file (TOML); the built-in coastal scene when absent.
    scene: Option<PathBuf>,
    /// Output directory.
    #[arg(long, default_value = "out")]
    out: PathBuf,
    /// Keep the photon map here, and reuse it when its recorded provenance
    /// matches the scene's emission inputs.
    #[arg(long)]
    map: Option<PathBuf>,
    /// Photons to trace (overrides the scene).
    #[arg(long)]
    photons: Option<u64>,
    /// Bands evenly spaced over 400-700 nm (overrides the scene's grid).
    #[arg(long)]
    bands: Option<usize>,
    /// Worker threads (0 = one per core); outputs are identical for any number.
    #[arg(long, default_value_t = 0)]
    threads: usize,
    /// Random seed (overrides the scene).
    #[arg(long)]
    seed: Option<u64>,
    /// Memory budget, e.g. 64MiB, 2GiB, 500MB or plain bytes.
    #[arg(long, default_value = "512MiB")]
    mem_budget: String,
    /// Boundary-bias compensation (overrides the scene).
    #[arg(long, value_enum)]
    boundary: Option<BoundaryMode>,
    /// Spectral-bias compensation (overrides the scene).
    #[arg(long, value_enum)]
    spectral: Option<SpectralMode>,
    /// No progress on stderr.
    #[arg(long)]
    quiet: bool,
}

#[derive(Subcommand)]
enum SceneCommand {
    /// Print the built-in coastal scene (TOML).
    Default,
    /// Validate a scene file; prints a summary on success.
    Check { file: PathBuf },
}

#[derive(Args)]
struct EmitArgs {
    /// Scene file (TOML).
    scene: PathBuf,
    /// Photon map to write.
    #[arg(long)]
    map: PathBuf,
    /// Write the emission report (JSON) here.
    #[arg(long)]
    report: Option<PathBuf>,
    /// Photons to trace (overrides the scene).
    #[arg(long)]
    photons: Option<u64>,
    /// Worker threads (default: all cores); the map is identical for any number.
    #[arg(long, default_value_t = 0)]
    threads: usize,
    /// Random seed (overrides the scene).
    #[arg(long)]
    seed: Option<u64>,
    /// Memory budget, e.g. 64MiB, 2GiB, 500MB or plain bytes.
    #[arg(long, default_value = "256MiB")]
    mem_budget: String,
    /// No progress on stderr.
    #[arg(long)]
    quiet: bool,
}

#[derive(Subcommand)]
enum MapCommand {
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
struct SynthArgs {
    /// Number of photons.
    #[arg(long)]
    photons: u64,
    /// Number of spectral bands (evenly spaced over 400-700 nm).
    #[arg(long, default_value_t = 16)]
    bands: usize,
    #[arg(long, default_value_t = 1)]
    seed: u64,
    #[arg(long, value_enum, default_value_t = Distribution::Water)]
    distribution: Distribution,
    /// Memory budget, e.g. 64MiB, 2GiB, 500MB or plain bytes.
    #[arg(long, default_value = "256MiB")]
    mem_budget: String,
    /// Producer threads (default: all cores).
    #[arg(long, default_value_t = 0)]
    threads: usize,
    #[arg(long)]
    out: PathBuf,
    /// No progress on stderr.
    #[arg(long)]
    quiet: bool,
}

#[derive(Args)]
#[command(group(clap::ArgGroup::new("search").required(true).args(["k", "radius"])))]
struct QueryArgs {
    file: PathBuf,
    /// Query point X,Y,Z in metres.
    #[arg(long, allow_hyphen_values = true)]
    at: String,
    /// Number of nearest photons.
    #[arg(long)]
    k: Option<usize>,
    /// With --k: ignore photons farther than this (m).
    #[arg(long, requires = "k", allow_hyphen_values = true)]
    max_radius: Option<f32>,
    /// All photons within this radius (m).
    #[arg(long, allow_hyphen_values = true)]
    radius: Option<f32>,
    /// Only photons of this layer (default: both).
    #[arg(long, value_enum)]
    layer: Option<Layer>,
    /// Tile cache budget.
    #[arg(long, default_value = "256MiB")]
    mem_budget: String,
}

/// Photon map layers.
#[derive(Clone, Copy, clap::ValueEnum)]
enum Layer {
    /// Photons stored at scattering events in the water.
    Volume,
    /// Photons stored on the floor and targets.
    Surface,
}

/// Progress bars on stderr, one per stage.
struct Bars {
    quiet: bool,
    bar: Mutex<Option<ProgressBar>>,
}

impl Bars {
    fn new(quiet: bool) -> Self {
        Bars {
            quiet,
            bar: Mutex::new(None),
        }
    }
    fn current(&self) -> Option<ProgressBar> {
        self.bar.lock().unwrap_or_else(|e| e.into_inner()).clone()
    }
}

impl Progress for Bars {
    fn stage(&self, name: &str, total: u64) {
        if self.quiet {
            return;
        }
        let bar = ProgressBar::with_draw_target(Some(total), ProgressDrawTarget::stderr());
        bar.set_style(
            ProgressStyle::with_template(
                "{msg:>14} [{bar:32}] {human_pos}/{human_len} {per_sec} eta {eta}",
            )
            .expect("valid template")
            .progress_chars("=> "),
        );
        bar.set_message(name.to_string());
        *self.bar.lock().unwrap_or_else(|e| e.into_inner()) = Some(bar);
    }
    fn advance(&self, n: u64) {
        if let Some(b) = self.current() {
            b.inc(n);
        }
    }
    fn finish(&self) {
        if let Some(b) = self.bar.lock().unwrap_or_else(|e| e.into_inner()).take() {
            b.finish_and_clear();
        }
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("littoral: error: {e}");
            ExitCode::FAILURE
        }
    }
}

type AnyResult<T> = Result<T, Box<dyn std::error::Error>>;

fn run(cli: Cli) -> AnyResult<()> {
    match cli.command {
        Command::Map(cmd) => run_map(cmd),
        Command::Scene(SceneCommand::Default) => {
            print!("{}", littoral::scene::COASTAL_TOML);
            Ok(())
        }
        Command::Scene(SceneCommand::Check { file }) => {
            let scene = Scene::load(&file, &Overrides::default())?;
            println!(
                "{}: scene '{}' is valid: {} bands {:.1}-{:.1} nm, {} photons, {} triangles, {} tally depths",
                file.display(),
                scene.name,
                scene.bands.len(),
                scene.bands.centers_nm()[0],
                scene.bands.centers_nm()[scene.bands.len() - 1],
                scene.photons,
                scene.geometry.triangle_count(),
                scene.tally_depths.len()
            );
            Ok(())
        }
        Command::Emit(a) => run_emit(a),
        Command::Render(a) => run_render(a),
    }
}

fn run_render(a: RenderArgs) -> AnyResult<()> {
    let start = Instant::now();
    let budget = run_budget(&a.mem_budget, a.photons)?;
    let overrides = Overrides {
        photons: a.photons,
        bands: a.bands,
        seed: a.seed,
        boundary: a.boundary,
        spectral: a.spectral,
    };
    let scene = match &a.scene {
        Some(path) => Scene::load(path, &overrides)?,
        None => Scene::coastal(&overrides)?,
    };
    let job = RenderJob {
        scene: &scene,
        out_dir: a.out.clone(),
        map: a.map.clone(),
        threads: a.threads,
        budget,
        scene_seconds: start.elapsed().as_secs_f64(),
    };
    let r = job.run(&Bars::new(a.quiet))?;
    if !a.quiet {
        eprintln!(
            "rendered {} ({}x{} px, {} bands) into {} in {:.1} s ({} {:.1} s, render {:.1} s); peak memory {:.1} MiB",
            scene.name,
            r.sensor.pixels[0],
            r.sensor.pixels[1],
            scene.bands.len(),
            a.out.display(),
            r.timings_s.total,
            if r.reused_map { "reused map" } else { "emit" },
            r.timings_s.emit,
            r.timings_s.render,
            mib(r.peak_rss_bytes)
        );
    }
    Ok(())
}

/// The memory budget of a run, after checking a `--photons` override.
fn run_budget(mem_budget: &str, photons: Option<u64>) -> AnyResult<MemoryBudget> {
    if photons == Some(0) {
        return Err(littoral::Error::invalid("--photons", "must be at least 1").into());
    }
    Ok(MemoryBudget::parse("--mem-budget", mem_budget)?)
}

fn mib(bytes: u64) -> f64 {
    bytes as f64 / (1u64 << 20) as f64
}

fn run_emit(a: EmitArgs) -> AnyResult<()> {
    let start = Instant::now();
    let budget = run_budget(&a.mem_budget, a.photons)?;
    let overrides = Overrides {
        photons: a.photons,
        seed: a.seed,
        ..Overrides::default()
    };
    let scene = Scene::load(&a.scene, &overrides)?;
    let job = EmitJob {
        scene: &scene,
        map: a.map.clone(),
        threads: a.threads,
        budget,
        scene_seconds: start.elapsed().as_secs_f64(),
    };
    let r = job.run(&Bars::new(a.quiet))?;
    let text = serde_json::to_string_pretty(&r)? + "\n";
    match &a.report {
        Some(path) => littoral::output::write_atomic(path, text.as_bytes())?,
        None => print!("{text}"),
    }
    if !a.quiet {
        eprintln!(
            "emitted {} photons: {} volume + {} surface photons stored in {} ({} tiles, {:.2} bytes/photon); energy closure {:.2} sigma; {:.1} s, peak memory {:.1} MiB",
            r.emission.photons.traced,
            r.emission.photons.stored_volume,
            r.emission.photons.stored_surface,
            a.map.display(),
            r.map.tiles,
            r.map.bytes_per_photon,
            r.emission.energy.closure_sigma,
            r.timings_s.total,
            mib(r.peak_rss_bytes)
        );
    }
    Ok(())
}

fn run_map(cmd: MapCommand) -> AnyResult<()> {
    match cmd {
        MapCommand::Synth(a) => {
            let budget = run_budget(&a.mem_budget, Some(a.photons))?;
            let source = SynthSource::new(a.photons, a.bands, a.seed, a.distribution)?;
            let bars = Bars::new(a.quiet);
            let summary = build_map(&a.out, &source, &budget.emission(a.threads), &bars)?;
            if !a.quiet {
                let peak = littoral::mem::peak_rss_bytes().unwrap_or(0);
                eprintln!(
                    "wrote {}: {} photons in {} tiles, {} bytes ({:.2} bytes/photon); peak memory {:.1} MiB ({peak} bytes)",
                    a.out.display(),
                    summary.photons,
                    summary.tiles,
                    summary.file_bytes,
                    summary.file_bytes as f64 / summary.photons.max(1) as f64,
                    peak as f64 / (1 << 20) as f64,
                );
            }
            Ok(())
        }
        MapCommand::Info { file } => {
            let map = MapFile::open(&file)?;
            print_json(&map.info())
        }
        MapCommand::Verify { file, quiet } => {
            let map = MapFile::open(&file)?;
            let report = map.verify(&Bars::new(quiet))?;
            print_json(&report)
        }
        MapCommand::Query(a) => {
            let at = parse_point(&a.at)?;
            let budget = littoral::size::parse_size("--mem-budget", &a.mem_budget)?;
            let search = match (a.k, a.radius) {
                (Some(k), None) => Search::Nearest {
                    k,
                    max_radius: a.max_radius,
                },
                (None, Some(radius)) => Search::Radius { radius },
                _ => unreachable!("clap enforces exactly one of --k and --radius"),
            };
            for (name, v) in [("--radius", a.radius), ("--max-radius", a.max_radius)] {
                if v.is_some_and(|r| !(r.is_finite() && r >= 0.0)) {
                    return Err(
                        littoral::Error::invalid(name, "must be a finite radius >= 0").into(),
                    );
                }
            }
            let map = PhotonMap::new(MapFile::open(&a.file)?, budget)?;
            let found = match a.layer {
                None => map.query(at, search)?,
                Some(Layer::Volume) => {
                    map.query_layer(at, littoral::photon::LAYER_VOLUME, search)?
                }
                Some(Layer::Surface) => {
                    map.query_layer(at, littoral::photon::LAYER_SURFACE, search)?
                }
            };
            let json: Vec<serde_json::Value> = found
                .iter()
                .map(|n| {
                    let p = &n.photon;
                    serde_json::json!({
                        "x": p.position.x, "y": p.position.y, "z": p.position.z,
                        "dx": p.direction.x, "dy": p.direction.y, "dz": p.direction.z,
                        "band": p.band, "power": p.power,
                        "distance": n.distance_sq.sqrt(),
                    })
                })
                .collect();
            print_json(&json)
        }
        MapCommand::Dump { file } => {
            let map = MapFile::open(&file)?;
            let stdout = std::io::stdout();
            let mut out = std::io::BufWriter::with_capacity(1 << 16, stdout.lock());
            match map.dump_csv(&mut out).and_then(|_| out.flush()) {
                Ok(()) => Ok(()),
                Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => Ok(()),
                Err(e) => match e.into_inner() {
                    Some(inner) => Err(inner),
                    None => Err("stdout: write failed".into()),
                },
            }
        }
    }
}

fn parse_point(text: &str) -> AnyResult<glam::Vec3> {
    let v: Vec<f32> = text
        .split(',')
        .map(|s| s.trim().parse::<f32>())
        .collect::<Result<_, _>>()
        .map_err(|_| littoral::Error::invalid("--at", format!("'{text}' is not X,Y,Z")))?;
    match v[..] {
        [x, y, z] if v.iter().all(|c| c.is_finite()) => Ok(glam::Vec3::new(x, y, z)),
        _ => Err(littoral::Error::invalid("--at", format!("'{text}' is not X,Y,Z")).into()),
    }
}

fn print_json<T: serde::Serialize>(value: &T) -> AnyResult<()> {
    let stdout = std::io::stdout();
    let mut out = stdout.lock();
    serde_json::to_writer_pretty(&mut out, value)?;
    writeln!(out)?;
    Ok(())
}
