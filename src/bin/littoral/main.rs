//! The `littoral` command line. Thin: parsing, progress bars and exit codes;
//! the library does the work.

mod args;

use args::*;
use clap::Parser;
use littoral::cli::{self, print_json, AnyResult, Bars};
use littoral::job::{EmitJob, MemoryBudget, RenderJob};
use littoral::scene::{Overrides, Scene};
use littoral::store::{build_map, MapFile, PhotonMap, PhotonQuery};
use littoral::synth::SynthSource;
use std::process::ExitCode;
use std::time::Instant;

fn main() -> ExitCode {
    // Before any thread exists, so that every thread shares the one arena.
    littoral::mem::tune_allocator();
    cli::remove_temporaries_on_signals("littoral");
    cli::exit("littoral", run(Cli::parse()))
}

fn run(cli: Cli) -> AnyResult<()> {
    match cli.command {
        Command::Map(cmd) => run_map(cmd),
        Command::Scene(SceneCommand::Default) => cli::print(littoral::scene::COASTAL_TOML),
        Command::Scene(SceneCommand::Check { file }) => {
            let scene = Scene::load(&file, &Overrides::default())?;
            cli::print(&format!("{}: {}\n", file.display(), scene.summary()))
        }
        Command::Scene(SceneCommand::Set(a)) => cli::print(&a.scene()?.text()),
        Command::Scene(SceneCommand::Atmosphere { file, toa }) => {
            let scene = Scene::load(&file, &Overrides::default())?;
            let Some(json) = scene.atmosphere_json(toa) else {
                return Err(littoral::Error::invalid(
                    "atmosphere",
                    format!("{} has no [atmosphere]", file.display()),
                )
                .into());
            };
            cli::print(&format!("{}\n", serde_json::to_string_pretty(&json)?))
        }
        Command::Emit(a) => run_emit(a),
        Command::Plan(a) => run_plan(a),
        Command::Render(a) => run_render(a),
        Command::Assemble(a) => {
            let r = littoral::job::distributed::parts::assemble(&a.parts, &a.out, a.threads)?;
            eprintln!("assembled {} parts: {}", a.parts.len(), r.summary());
            warn(&r.warnings);
            Ok(())
        }
    }
}

fn run_render(a: RenderArgs) -> AnyResult<()> {
    let start = Instant::now();
    let budget = MemoryBudget::parse("--mem-budget", &a.mem_budget)?;
    let overrides = a.overrides();
    let scene = match &a.scene {
        Some(path) => Scene::load(path, &overrides)?,
        None => Scene::coastal(&overrides)?,
    };
    if let Some(tiles) = a.tiles {
        let job = littoral::job::distributed::parts::RenderPartJob {
            scene: &scene,
            part_dir: a.out.clone(),
            map: a.map.clone(),
            emit_map: tiles.1 == 1,
            tiles,
            threads: a.threads,
            budget,
        };
        let m = job.run(&Bars::new(a.quiet))?;
        if !a.quiet {
            eprintln!(
                "rendered part {}/{} ({} tiles) into {} in {:.1} s",
                m.part,
                m.parts,
                m.tiles.len(),
                a.out.display(),
                m.timings_s.total
            );
        }
        return Ok(());
    }
    let job = RenderJob {
        scene: &scene,
        out_dir: a.out.clone(),
        map: a.map.clone(),
        threads: a.threads,
        budget,
        scene_seconds: start.elapsed().as_secs_f64(),
    };
    let r = if a.resume {
        littoral::job::distributed::parts::render_resumable(&job, &Bars::new(a.quiet))?
    } else {
        job.run(&Bars::new(a.quiet))?
    };
    if !a.quiet {
        eprintln!("{}", r.summary());
    }
    warn(&r.warnings);
    Ok(())
}

fn run_emit(a: EmitArgs) -> AnyResult<()> {
    let start = Instant::now();
    let budget = MemoryBudget::parse("--mem-budget", &a.mem_budget)?;
    let scene = Scene::load(&a.scene, &a.overrides())?;
    if let Some(shard) = a.shard {
        let job = littoral::job::distributed::ShardJob {
            scene: &scene,
            path: a.map.clone(),
            shard,
            report: a.report.clone(),
            threads: a.threads,
            budget,
        };
        let r = job.run(&Bars::new(a.quiet))?;
        if !a.quiet {
            eprintln!("{}", r.summary());
        }
        return Ok(());
    }
    let job = EmitJob {
        scene: &scene,
        map: a.map.clone(),
        report: a.report.clone(),
        threads: a.threads,
        budget,
        scene_seconds: start.elapsed().as_secs_f64(),
    };
    let r = job.run(&Bars::new(a.quiet))?;
    if a.report.is_none() {
        cli::print(&r.json())?;
    }
    if !a.quiet {
        eprintln!("{}", r.summary());
    }
    warn(&r.warnings);
    Ok(())
}

/// Each warning as a line on stderr.
fn warn(warnings: &[String]) {
    for w in warnings {
        eprintln!("littoral: warning: {w}");
    }
}

fn run_map(cmd: MapCommand) -> AnyResult<()> {
    match cmd {
        MapCommand::Merge(a) => {
            let budget = match &a.mem_budget {
                Some(text) => Some(MemoryBudget::parse("--mem-budget", text)?),
                None => None,
            };
            let job = littoral::job::distributed::MergeJob {
                parts: &a.parts,
                map: a.out.clone(),
                report: a.report.clone(),
                budget,
            };
            let r = job.run(&Bars::new(a.quiet))?;
            if !a.quiet {
                eprintln!("merged {} shards: {}", a.parts.len(), r.summary());
            }
            Ok(())
        }
        MapCommand::Synth(a) => {
            let budget = MemoryBudget::parse("--mem-budget", &a.mem_budget)?;
            let source = SynthSource::new(a.photons, a.bands.into(), a.seed, a.distribution)?;
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
            let at = cli::parse_point("--at", &a.at)?;
            let budget = littoral::size::parse_size("--mem-budget", &a.mem_budget)?;
            let search = a.search()?;
            let map = PhotonMap::new(MapFile::open(&a.file)?, budget)?;
            let layer = a.layer.map(Layer::index);
            let mut found = Vec::new();
            map.query_into(at, layer, search, &mut found)?;
            print_json(&found)
        }
        MapCommand::Dump { file } => {
            let map = MapFile::open(&file)?;
            cli::print_with(|out| map.dump_csv(out))
        }
    }
}

fn run_plan(a: PlanArgs) -> AnyResult<()> {
    let budget = MemoryBudget::parse("--mem-budget", &a.mem_budget)?;
    let bin_dir = match &a.bin_dir {
        Some(d) => d.clone(),
        None => std::env::current_exe()?
            .parent()
            .map(|p| p.to_path_buf())
            .unwrap_or_default(),
    };
    let planned = littoral::job::distributed::plan::PlanRequest {
        scene: a.scene,
        photons: a.photons,
        seed: a.seed,
        integrator: a.integrator,
        samples_per_pixel: a.spp,
        shards: a.shards,
        dir: a.out.clone(),
        results: a.results,
        mem_budget: budget.total(),
        cpus: a.cpus_per_task,
        partition: a.partition,
        time: a.time,
        bin_dir,
    }
    .write()?;
    for s in &planned.scripts {
        println!("{}", s.display());
    }
    eprintln!(
        "wrote {} scripts into {}: run {} to submit ({} array tasks per stage, {} MiB and {} CPUs each)",
        planned.scripts.len(),
        a.out.display(),
        planned
            .scripts
            .last()
            .map(|p| p.display().to_string())
            .unwrap_or_default(),
        a.shards,
        planned.task_mem_mib,
        a.cpus_per_task
    );
    Ok(())
}
