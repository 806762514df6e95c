//! Batch scripts for a sharded run on a Slurm cluster (`littoral plan`).
//!
//! Four jobs, chained with `afterok` dependencies by `submit.sh`:
//! 1. `emit.sbatch`, a job array of N tasks: `littoral emit --shard I/N`,
//!    each task a shard file in `shards/`;
//! 2. `merge.sbatch`: `littoral map merge` of the N shards into `map.map`;
//! 3. `render.sbatch`, a job array of N tasks: `littoral render --tiles
//!    I/N`, each task a part directory in `parts/`;
//! 4. `assemble.sbatch`: `littoral assemble` of the parts into the
//!    results directory.
//!
//! With the path integrator there is no map: only the render array and the
//! assembly. Every task reads `SLURM_ARRAY_TASK_ID` and runs with the
//! plan's `--mem-budget`; it asks Slurm for that budget plus
//! [`TASK_OVERHEAD_MIB`] and a quarter (the budget bounds anonymous memory;
//! the binary, the mapped photon map's resident pages and the page cache of
//! written files come on top, and a cgroup-enforcing cluster counts them).
//! The same budget everywhere makes the outputs byte-identical to
//! `littoral render SCENE --mem-budget BUDGET` on one machine.
//!
//! Every path in the scripts is absolute: the cluster needs a filesystem
//! shared by the nodes, holding the scene, the files it names, the plan
//! directory and the binaries.
//!
//! Not for: submitting (run `submit.sh`), or schedulers other than Slurm.

use crate::error::{Error, Result};
use crate::scene::{IntegratorMode, Scene};
use std::path::{Path, PathBuf};

/// Memory (MiB) a task asks for beyond its budget: the binary, the
/// runtime, the file pages of the map being read or written.
pub const TASK_OVERHEAD_MIB: u64 = 256;

/// What to plan.
pub struct Plan<'a> {
    pub scene: &'a Scene,
    /// The scene file (absolute) and the overrides emit and render share,
    /// as `littoral` flags.
    pub scene_args: Vec<String>,
    /// Flags for the render only (integrator, samples per pixel).
    pub render_args: Vec<String>,
    /// Shards of the emission and parts of the render.
    pub shards: u64,
    /// Where the scripts, shards, parts and logs go.
    pub dir: PathBuf,
    /// Where the assembled outputs go.
    pub results: PathBuf,
    /// `--mem-budget` of every task, in bytes.
    pub mem_budget: u64,
    /// CPUs per task.
    pub cpus: u32,
    /// Slurm partition, time limit and extra `#SBATCH` lines.
    pub partition: Option<String>,
    pub time: Option<String>,
    /// Directory of the `littoral` binary.
    pub bin_dir: PathBuf,
}

/// A plan as `littoral plan` asks for it: a scene file (or none, for the
/// built-in scene, which is then written into the plan directory as
/// `scene.toml` so that every task reads the same text) and the overrides
/// of the run.
pub struct PlanRequest {
    pub scene: Option<PathBuf>,
    pub photons: Option<u64>,
    pub seed: Option<u64>,
    pub integrator: Option<IntegratorMode>,
    pub samples_per_pixel: Option<u32>,
    pub shards: u64,
    pub dir: PathBuf,
    /// Where the assembled outputs go (default `DIR/results`).
    pub results: Option<PathBuf>,
    pub mem_budget: u64,
    pub cpus: u32,
    pub partition: Option<String>,
    pub time: Option<String>,
    pub bin_dir: PathBuf,
}

/// What [`PlanRequest::write`] wrote.
pub struct Planned {
    /// The scripts, `submit.sh` last.
    pub scripts: Vec<PathBuf>,
    /// Memory (MiB) each task asks Slurm for.
    pub task_mem_mib: u64,
}

impl PlanRequest {
    /// Check the scene with its overrides and write the plan's scripts.
    pub fn write(&self) -> Result<Planned> {
        std::fs::create_dir_all(&self.dir)
            .map_err(|e| Error::io(&self.dir, "create directory", e))?;
        let scene_path = match &self.scene {
            Some(p) => std::path::absolute(p).map_err(|e| Error::io(p, "resolve", e))?,
            None => {
                let p = std::path::absolute(self.dir.join("scene.toml"))
                    .map_err(|e| Error::io(&self.dir, "resolve", e))?;
                crate::output::write_atomic(&p, crate::scene::COASTAL_TOML.as_bytes())?;
                p
            }
        };
        let overrides = crate::scene::Overrides {
            photons: self.photons,
            seed: self.seed,
            integrator: self.integrator,
            samples_per_pixel: self.samples_per_pixel,
            ..Default::default()
        };
        let scene = Scene::load(&scene_path, &overrides)?;
        // Emit and render both take the scene's overrides; the render alone
        // takes the integrator and the samples per pixel.
        let mut scene_args = vec![scene_path.display().to_string()];
        for (flag, v) in [("--photons", self.photons), ("--seed", self.seed)] {
            if let Some(v) = v {
                scene_args.extend([flag.to_string(), v.to_string()]);
            }
        }
        let mut render_args = Vec::new();
        if let Some(i) = self.integrator {
            use clap::ValueEnum;
            let name = i
                .to_possible_value()
                .map(|v| v.get_name().to_string())
                .unwrap_or_default();
            render_args.extend(["--integrator".to_string(), name]);
        }
        if let Some(spp) = self.samples_per_pixel {
            render_args.extend(["--spp".to_string(), spp.to_string()]);
        }
        let plan = Plan {
            scene: &scene,
            scene_args,
            render_args,
            shards: self.shards,
            dir: self.dir.clone(),
            results: self
                .results
                .clone()
                .unwrap_or_else(|| self.dir.join("results")),
            mem_budget: self.mem_budget,
            cpus: self.cpus,
            partition: self.partition.clone(),
            time: self.time.clone(),
            bin_dir: self.bin_dir.clone(),
        };
        Ok(Planned {
            scripts: plan.write()?,
            task_mem_mib: plan.task_mem_mib(),
        })
    }
}

/// Quote `s` for a POSIX shell.
fn sh(s: &str) -> String {
    if !s.is_empty()
        && s.chars()
            .all(|c| c.is_ascii_alphanumeric() || "/._-=:+,".contains(c))
    {
        s.to_string()
    } else {
        format!("'{}'", s.replace('\'', r"'\''"))
    }
}

fn abs(p: &Path) -> Result<PathBuf> {
    if p.is_absolute() {
        Ok(p.to_path_buf())
    } else {
        let cwd =
            std::env::current_dir().map_err(|e| Error::io(".", "find the working directory", e))?;
        Ok(cwd.join(p))
    }
}

impl Plan<'_> {
    /// Memory (MiB) each task asks Slurm for.
    pub fn task_mem_mib(&self) -> u64 {
        let budget = self.mem_budget.div_ceil(1 << 20);
        budget + budget / 4 + TASK_OVERHEAD_MIB
    }

    fn header(&self, name: &str, array: bool) -> String {
        let mut h = format!(
            "#!/bin/bash\n#SBATCH --job-name=littoral-{name}\n#SBATCH --cpus-per-task={}\n#SBATCH --mem={}M\n",
            self.cpus,
            self.task_mem_mib()
        );
        let logs = self.dir.join("logs");
        // `#SBATCH` lines are not shell: no quoting (`write` refuses white
        // space in the paths and values that go here).
        if array {
            h += &format!("#SBATCH --array=0-{}\n", self.shards - 1);
            h += &format!(
                "#SBATCH --output={}\n",
                logs.join(format!("{name}-%a.out")).display()
            );
        } else {
            h += &format!(
                "#SBATCH --output={}\n",
                logs.join(format!("{name}.out")).display()
            );
        }
        if let Some(p) = &self.partition {
            h += &format!("#SBATCH --partition={p}\n");
        }
        if let Some(t) = &self.time {
            h += &format!("#SBATCH --time={t}\n");
        }
        h += "set -euo pipefail\n";
        h
    }

    /// The values that go on `#SBATCH` lines, which cannot carry white
    /// space (nor quote it).
    fn check_sbatch_values(&self, dir: &Path) -> Result<()> {
        for (flag, v) in [
            ("--out", Some(dir.display().to_string())),
            ("--partition", self.partition.clone()),
            ("--time", self.time.clone()),
        ] {
            if let Some(v) = v.filter(|v| v.chars().any(char::is_whitespace)) {
                return Err(Error::invalid(
                    flag,
                    format!("'{v}' has white space, which #SBATCH lines cannot carry"),
                ));
            }
        }
        Ok(())
    }

    /// Write the scripts into `dir`; returns their paths (`submit.sh` last).
    pub fn write(&self) -> Result<Vec<PathBuf>> {
        if self.shards == 0 {
            return Err(Error::invalid("--shards", "must be at least 1"));
        }
        let dir = abs(&self.dir)?;
        self.check_sbatch_values(&dir)?;
        let results = abs(&self.results)?;
        let plan = Plan {
            dir: dir.clone(),
            results: results.clone(),
            bin_dir: abs(&self.bin_dir)?,
            scene_args: self.scene_args.clone(),
            render_args: self.render_args.clone(),
            partition: self.partition.clone(),
            time: self.time.clone(),
            ..*self
        };
        for sub in ["logs", "shards", "parts"] {
            std::fs::create_dir_all(dir.join(sub))
                .map_err(|e| Error::io(dir.join(sub), "create directory", e))?;
        }
        let littoral = sh(&plan.bin_dir.join("littoral").display().to_string());
        let scene = plan
            .scene_args
            .iter()
            .map(|a| sh(a))
            .collect::<Vec<_>>()
            .join(" ");
        let render_scene = plan
            .scene_args
            .iter()
            .chain(&plan.render_args)
            .map(|a| sh(a))
            .collect::<Vec<_>>()
            .join(" ");
        let n = plan.shards;
        let budget = format!("--mem-budget {}", plan.mem_budget);
        let threads = "--threads \"${SLURM_CPUS_PER_TASK:-1}\"";
        let map = sh(&dir.join("map.map").display().to_string());
        let shard =
            |id: &str| sh(&dir.join("shards").display().to_string()) + &format!("/part-{id}.shard");
        let part = |id: &str| sh(&dir.join("parts").display().to_string()) + &format!("/part-{id}");
        let photon_map = plan.scene.render.integrator == IntegratorMode::PhotonMap;
        let mut scripts = Vec::new();
        let mut write = |name: &str, text: String| -> Result<()> {
            let path = dir.join(name);
            crate::output::write_atomic(&path, text.as_bytes())?;
            #[cfg(unix)]
            {
                use std::os::unix::fs::PermissionsExt;
                std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o755))
                    .map_err(|e| Error::io(&path, "make executable", e))?;
            }
            scripts.push(path);
            Ok(())
        };
        let id = "\"$SLURM_ARRAY_TASK_ID\"";
        if photon_map {
            write(
                "emit.sbatch",
                plan.header("emit", true)
                    + &format!(
                        "exec {littoral} emit {scene} --shard {id}/{n} --map {} {budget} {threads} --quiet\n",
                        shard("${SLURM_ARRAY_TASK_ID}")
                    ),
            )?;
            let shards: Vec<String> = (0..n).map(|i| shard(&i.to_string())).collect();
            write(
                "merge.sbatch",
                plan.header("merge", false)
                    + &format!(
                        "exec {littoral} map merge {} --out {map} --report {} {budget} --quiet\n",
                        shards.join(" "),
                        sh(&dir.join("emission.json").display().to_string())
                    ),
            )?;
        }
        let map_arg = if photon_map {
            format!(" --map {map}")
        } else {
            String::new()
        };
        write(
            "render.sbatch",
            plan.header("render", true)
                + &format!(
                    "exec {littoral} render {render_scene}{map_arg} --tiles {id}/{n} --out {} {budget} {threads} --quiet\n",
                    part("${SLURM_ARRAY_TASK_ID}")
                ),
        )?;
        let parts: Vec<String> = (0..n).map(|i| part(&i.to_string())).collect();
        write(
            "assemble.sbatch",
            plan.header("assemble", false)
                + &format!(
                    "exec {littoral} assemble {} --out {} {threads}\n",
                    parts.join(" "),
                    sh(&results.display().to_string())
                ),
        )?;
        let stages: Vec<&str> = if photon_map {
            vec!["emit", "merge", "render", "assemble"]
        } else {
            vec!["render", "assemble"]
        };
        write("submit.sh", submit_script(&stages))?;
        Ok(scripts)
    }
}

/// `submit.sh`: submit `stages` (`NAME.sbatch`), each after the one
/// before succeeds; prints the last job's id.
fn submit_script(stages: &[&str]) -> String {
    let mut submit = String::from(
        "#!/bin/bash\n# Submit the plan's jobs, each after the one before succeeds; prints the\n# last job's id. With --wait, returns when it has finished (non-zero if\n# any job failed).\nset -euo pipefail\ncd \"$(dirname \"$0\")\"\nwait_flag=()\nif [[ \"${1:-}\" == --wait ]]; then wait_flag=(--wait); fi\n",
    );
    let mut prev: Option<String> = None;
    for (k, stage) in stages.iter().enumerate() {
        let last = k + 1 == stages.len();
        let dep = prev
            .as_ref()
            .map(|p| format!(" --dependency=afterok:\"${p}\" --kill-on-invalid-dep=yes"))
            .unwrap_or_default();
        // `${a[@]+"${a[@]}"}`: an empty array under `set -u` is an
        // unbound variable to bash 4.3 and older.
        let wait = if last {
            " ${wait_flag[@]+\"${wait_flag[@]}\"}"
        } else {
            ""
        };
        submit += &format!("{stage}=$(sbatch --parsable{dep}{wait} {stage}.sbatch)\n");
        prev = Some(stage.to_string());
    }
    submit += &format!("echo \"${}\"\n", prev.expect("a stage"));
    submit
}

#[cfg(test)]
mod tests;
