//! The `littoral` command line. Thin: parsing, progress bars and exit codes;
//! the library does the work.

mod args;

use args::*;
use clap::Parser;
use littoral::cli::{self, print_json, AnyResult, Bars};
use littoral::job::{EmitJob, MemoryBudget, RenderJob};
use littoral::scene::{Overrides, Scene};
use littoral::store::{build_map, MapFile, PhotonMap, PhotonQuery, Search};
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
        Command::Emit(a) => run_emit(a),
        Command::Plan(a) => run_plan(a),
        Command::Render(a) => run_render(a),
    }
}

fn run_render(a: RenderArgs) -> AnyResult<()> {
    let start = Instant::now();
    let budget = MemoryBudget::parse("--mem-budget", &a.mem_budget)?;
    let overrides = Overrides {
        photons: a.photons,
        bands: a.bands.map(usize::from),
        seed: a.seed,
        boundary: a.boundary,
        spectral: a.spectral,
        integrator: a.integrator,
        samples_per_pixel: a.spp,
    };
    let scene = match &a.scene {
        Some(path) => Scene::load(path, &overrides)?,
        None => Scene::coastal(&overrides)?,
    };
    if let Some(tiles) = a.tiles {
        let job = littoral::job::parts::RenderPartJob {
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
        littoral::job::parts::render_resumable(&job, &Bars::new(a.quiet))?
    } else {
        job.run(&Bars::new(a.quiet))?
    };
    if !a.quiet {
        eprintln!("{}", r.summary());
    }
    for w in &r.warnings {
        eprintln!("littoral: warning: {w}");
    }
    Ok(())
}

fn run_emit(a: EmitArgs) -> AnyResult<()> {
    let start = Instant::now();
    let budget = MemoryBudget::parse("--mem-budget", &a.mem_budget)?;
    let overrides = Overrides {
        photons: a.photons,
        seed: a.seed,
        ..Overrides::default()
    };
    let scene = Scene::load(&a.scene, &overrides)?;
    if let Some(shard) = a.shard {
        let _lock = littoral::job::prepare_map_outputs(&scene, &a.map, a.report.as_deref(), false)?;
        littoral::mem::tune_allocator();
        let sampler = littoral::mem::PeakSampler::start();
        let provenance = littoral::emit::emission_provenance(&scene)?;
        let h = littoral::emit::emit_shard(
            &scene,
            &provenance,
            &a.map,
            shard,
            &budget.emission(a.threads),
            &Bars::new(a.quiet),
        )?;
        let summary = serde_json::json!({
            "shard": h.shard,
            "shards": h.shards,
            "indices": h.indices,
            "photons": h.photons,
            "file_bytes": std::fs::metadata(&a.map).map(|m| m.len()).unwrap_or(0),
            "path": a.map.display().to_string(),
            "seconds": start.elapsed().as_secs_f64(),
            "mem_budget_bytes": budget.total(),
            "peak_memory": sampler.finish(),
        });
        if let Some(path) = &a.report {
            littoral::output::write_atomic(
                path,
                (serde_json::to_string_pretty(&summary)? + "\n").as_bytes(),
            )?;
        }
        if !a.quiet {
            eprintln!(
                "emitted shard {}/{}: photon indices {}..{}, {} photons stored in {}",
                h.shard,
                h.shards,
                h.indices[0],
                h.indices[1],
                h.photons,
                a.map.display()
            );
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
    for w in &r.warnings {
        eprintln!("littoral: warning: {w}");
    }
    Ok(())
}

fn run_map(cmd: MapCommand) -> AnyResult<()> {
    match cmd {
        MapCommand::Merge(a) => {
            let budget = match &a.mem_budget {
                Some(text) => Some(MemoryBudget::parse("--mem-budget", text)?),
                None => None,
            };
            let report_file = match &a.report {
                Some(path) => Some(littoral::output::temp_beside(path)?),
                None => None,
            };
            let job = littoral::job::MergeJob {
                parts: &a.parts,
                map: a.out.clone(),
                budget,
            };
            let r = job.run(&Bars::new(a.quiet))?;
            if let (Some(mut tmp), Some(path)) = (report_file, &a.report) {
                use std::io::Write;
                let text = serde_json::to_string_pretty(&r)? + "\n";
                tmp.write_all(text.as_bytes())
                    .map_err(|e| littoral::Error::io(path, "write", e))?;
                littoral::output::publish(tmp, path)?;
            }
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
            let layer = a.layer.map(|l| match l {
                Layer::Volume => littoral::photon::LAYER_VOLUME,
                Layer::VolumeUp => littoral::photon::LAYER_VOLUME_UP,
                Layer::Surface => littoral::photon::LAYER_SURFACE,
            });
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
    let overrides = Overrides {
        photons: a.photons,
        seed: a.seed,
        integrator: a.integrator,
        samples_per_pixel: a.spp,
        ..Overrides::default()
    };
    std::fs::create_dir_all(&a.out)
        .map_err(|e| littoral::Error::io(&a.out, "create directory", e))?;
    let scene_path = match &a.scene {
        Some(p) => std::path::absolute(p).map_err(|e| littoral::Error::io(p, "resolve", e))?,
        None => {
            let p = std::path::absolute(a.out.join("scene.toml"))
                .map_err(|e| littoral::Error::io(&a.out, "resolve", e))?;
            littoral::output::write_atomic(&p, littoral::scene::COASTAL_TOML.as_bytes())?;
            p
        }
    };
    let scene = Scene::load(&scene_path, &overrides)?;
    let mut scene_args = vec![scene_path.display().to_string()];
    for (flag, v) in [
        ("--photons", a.photons.map(|v| v.to_string())),
        ("--seed", a.seed.map(|v| v.to_string())),
    ] {
        if let Some(v) = v {
            scene_args.extend([flag.to_string(), v]);
        }
    }
    // Flags emit does not take go to render only: the render scripts get
    // them through the scene arguments of the render (see below).
    let mut render_only = Vec::new();
    if let Some(i) = a.integrator {
        use clap::ValueEnum;
        let name = i
            .to_possible_value()
            .map(|v| v.get_name().to_string())
            .unwrap_or_default();
        render_only.extend(["--integrator".to_string(), name]);
    }
    if let Some(spp) = a.spp {
        render_only.extend(["--spp".to_string(), spp.to_string()]);
    }
    let bin_dir = match &a.bin_dir {
        Some(d) => d.clone(),
        None => std::env::current_exe()?
            .parent()
            .map(|p| p.to_path_buf())
            .unwrap_or_default(),
    };
    let plan = littoral::job::plan::Plan {
        scene: &scene,
        scene_args,
        render_args: render_only,
        shards: a.shards,
        dir: a.out.clone(),
        results: a.results.clone().unwrap_or_else(|| a.out.join("results")),
        mem_budget: budget.total(),
        cpus: a.cpus_per_task,
        partition: a.partition.clone(),
        time: a.time.clone(),
        bin_dir,
    };
    let scripts = plan.write()?;
    for s in &scripts {
        println!("{}", s.display());
    }
    eprintln!(
        "wrote {} scripts into {}: run {} to submit ({} array tasks per stage, {} MiB and {} CPUs each)",
        scripts.len(),
        a.out.display(),
        scripts.last().map(|p| p.display().to_string()).unwrap_or_default(),
        a.shards,
        plan.task_mem_mib(),
        a.cpus_per_task
    );
    Ok(())
}
