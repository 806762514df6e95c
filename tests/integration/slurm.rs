//! The plan's batch scripts on a real Slurm cluster: Debian's slurm-wlm
//! and munge as a single node, brought up by `.ci/slurm-up.sh` (which
//! `.ci/run` runs, and which sets LITTORAL_REQUIRE_SLURM). The emit and
//! render job arrays, the merge and the assembly run as chained jobs, and
//! the results are byte-identical to the same render on one machine.
//! Without a cluster (and without LITTORAL_REQUIRE_SLURM) the test says so
//! and passes.

use crate::common::{littoral, p, tempdir};
use std::process::Command;

fn cluster_ready() -> bool {
    Command::new("sinfo")
        .args(["-h", "-o", "%T"])
        .output()
        .map(|o| o.status.success() && String::from_utf8_lossy(&o.stdout).contains("idle"))
        .unwrap_or(false)
}

#[test]
fn plan_runs_on_slurm_and_matches_one_machine() {
    if !cluster_ready() {
        assert!(
            std::env::var_os("LITTORAL_REQUIRE_SLURM").is_none(),
            "LITTORAL_REQUIRE_SLURM is set but no Slurm node is idle (run .ci/slurm-up.sh)"
        );
        eprintln!("no Slurm cluster here: run .ci/slurm-up.sh to test the plan on one");
        return;
    }
    let dir = tempdir();
    let scene = dir.path().join("s.toml");
    std::fs::write(
        &scene,
        crate::common::MINIMAL_SCENE.replace("count = 1000", "count = 40000")
            + "[sensor]\npixels = [40, 24]\ngsd_m = 0.25\n[[radiometer]]\ndepth_m = 1.0\nview = \"nadir\"\nposition_m = [5.0, 5.0]\n",
    )
    .unwrap();
    let plan = dir.path().join("plan");
    let out = littoral(&[
        "plan",
        p(&scene),
        "--shards",
        "3",
        "--out",
        p(&plan),
        "--mem-budget",
        "96MiB",
        "--cpus-per-task",
        "1",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let submit = Command::new("timeout")
        .args(["900", p(&plan.join("submit.sh")), "--wait"])
        .output()
        .unwrap();
    let logs = || {
        std::fs::read_dir(plan.join("logs"))
            .map(|d| {
                d.filter_map(|e| e.ok())
                    .map(|e| {
                        format!(
                            "== {}\n{}",
                            e.path().display(),
                            std::fs::read_to_string(e.path()).unwrap_or_default()
                        )
                    })
                    .collect::<Vec<_>>()
                    .join("\n")
            })
            .unwrap_or_default()
    };
    assert!(
        submit.status.success(),
        "the jobs failed: {}{}\n{}",
        String::from_utf8_lossy(&submit.stdout),
        String::from_utf8_lossy(&submit.stderr),
        logs()
    );
    // Every array task ran.
    for i in 0..3 {
        assert!(
            plan.join(format!("shards/part-{i}.shard")).exists(),
            "{}",
            logs()
        );
        assert!(
            plan.join(format!("parts/part-{i}/part.json")).exists(),
            "{}",
            logs()
        );
        assert!(plan.join(format!("logs/emit-{i}.out")).exists());
        assert!(plan.join(format!("logs/render-{i}.out")).exists());
    }
    // The same render on one machine, with the same budget.
    let single = dir.path().join("single");
    let out = littoral(&[
        "render",
        p(&scene),
        "--out",
        p(&single),
        "--mem-budget",
        "96MiB",
        "--quiet",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let results = plan.join("results");
    let mut compared = 0;
    for e in std::fs::read_dir(&single).unwrap() {
        let name = e.unwrap().file_name().to_string_lossy().into_owned();
        if name.ends_with(".json") || name.ends_with(".html") {
            continue;
        }
        assert!(
            std::fs::read(single.join(&name)).unwrap()
                == std::fs::read(results.join(&name)).unwrap(),
            "{name} differs between Slurm and one machine"
        );
        compared += 1;
    }
    assert!(compared >= 15, "{compared} files compared");
    // The merged map is the single emission's, byte for byte.
    let map = dir.path().join("single.map");
    let out = littoral(&[
        "emit",
        p(&scene),
        "--map",
        p(&map),
        "--mem-budget",
        "96MiB",
        "--quiet",
    ]);
    assert!(out.status.success());
    assert!(std::fs::read(&map).unwrap() == std::fs::read(plan.join("map.map")).unwrap());
}
