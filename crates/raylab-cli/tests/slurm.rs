//! The farm scripts on a real Slurm cluster: a one-node cluster started on this machine
//! (`farm/local-slurm.sh`, Debian's slurm-wlm and munge), a job array of tiles and a dependent
//! merge, and a tile requeued mid-render (as a pre-empted job is) that goes on from its
//! checkpoint. The merged image must be the single render's, bit for bit.
//!
//! Skips with a message where Slurm is not installed, unless `RAYLAB_REQUIRE_SLURM` is set (CI
//! sets it, and `.ci/run` installs Slurm), where it fails instead.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::{Duration, Instant};

#[path = "common/farm.rs"]
mod common;
use common::bits;

fn farm(script: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../farm").join(script)
}

fn mitsuba_box() -> String {
    concat!(env!("CARGO_MANIFEST_DIR"), "/../../scenes/cornell-mitsuba.toml").to_string()
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// Whether the Slurm and munge daemons and clients are installed; if not, the reason.
fn slurm_missing() -> Option<String> {
    let missing: Vec<&str> = ["munged", "slurmctld", "slurmd", "sbatch", "scontrol"]
        .into_iter()
        .filter(|tool| {
            !Command::new("sh")
                .args(["-c", &format!("command -v {tool}")])
                .output()
                .is_ok_and(|o| o.status.success())
        })
        .collect();
    (!missing.is_empty()).then(|| format!("not installed: {}", missing.join(", ")))
}

/// A one-node cluster, stopped (its daemons killed by their pid files) when dropped, even when
/// the test fails.
struct Cluster {
    dir: tempfile::TempDir,
}

impl Cluster {
    fn start() -> Cluster {
        let dir = tempfile::tempdir().unwrap();
        // Ports of its own, so that a cluster someone started by hand does not get in the way.
        let port = 20_000 + (std::process::id() % 20_000) * 2;
        let out = Command::new(farm("local-slurm.sh"))
            .env("SLURMCTLD_PORT", port.to_string())
            .env("SLURMD_PORT", (port + 1).to_string())
            .arg("start")
            .arg(dir.path().join("cluster"))
            .output()
            .unwrap();
        // The guard first: a cluster that half started is stopped too.
        let cluster = Cluster { dir };
        assert!(out.status.success(), "the cluster did not start: {}", text(&out.stderr));
        cluster
    }

    fn conf(&self) -> PathBuf {
        self.dir.path().join("cluster/slurm.conf")
    }

    /// A command with this cluster's configuration and the raylab under test.
    fn command(&self, program: impl AsRef<std::ffi::OsStr>) -> Command {
        let mut command = Command::new(program);
        command
            .env("SLURM_CONF", self.conf())
            .env("RAYLAB", env!("CARGO_BIN_EXE_raylab"))
            .current_dir(self.dir.path());
        command
    }

    fn run(&self, program: impl AsRef<std::ffi::OsStr>, args: &[&str]) -> Output {
        let out = self.command(program).args(args).output().unwrap();
        assert!(out.status.success(), "{args:?}: {}{}", text(&out.stdout), text(&out.stderr));
        out
    }
}

impl Drop for Cluster {
    fn drop(&mut self) {
        let _ = Command::new(farm("local-slurm.sh"))
            .arg("stop")
            .arg(self.dir.path().join("cluster"))
            .status();
    }
}

/// The single render to compare with.
fn single(dir: &Path, name: &str, args: &[&str]) -> (Vec<(String, Vec<u32>)>, u32, raylab::Region) {
    let scene = mitsuba_box();
    let mut all = vec!["render", scene.as_str(), "-o", name];
    all.extend_from_slice(args);
    let out =
        Command::new(env!("CARGO_BIN_EXE_raylab")).args(&all).current_dir(dir).output().unwrap();
    assert!(out.status.success(), "{}", text(&out.stderr));
    bits(&dir.join(name))
}

#[test]
fn a_slurm_job_array_renders_tiles_that_merge_to_the_single_render() {
    if let Some(reason) = slurm_missing() {
        assert!(
            std::env::var_os("RAYLAB_REQUIRE_SLURM").is_none(),
            "RAYLAB_REQUIRE_SLURM is set but Slurm is {reason} (apt-get install slurm-wlm munge)"
        );
        eprintln!("skipped: Slurm is {reason} (apt-get install slurm-wlm munge)");
        return;
    }
    let cluster = Cluster::start();
    let d = cluster.dir.path();
    let scene = mitsuba_box();

    // Four tiles, one array task each, then the merge once all have succeeded.
    let options = ["--size", "96x61", "--spp", "8"];
    let mut args = vec!["--wait", "4", "full.exr", scene.as_str()];
    args.extend_from_slice(&options);
    let out = cluster.run(farm("submit-slurm.sh"), &args);
    assert!(text(&out.stdout).contains("(4 tasks)"), "{}", text(&out.stdout));
    let merge_log = std::fs::read_to_string(d.join("full.exr.parts/merge.log")).unwrap();
    assert!(merge_log.contains("full.exr: 96×61 from 4 parts, 8 samples per pixel"), "{merge_log}");
    assert_eq!(bits(&d.join("full.exr")), single(d, "single.exr", &options));

    // An animation, one array task per frame, equals the frames rendered in one process.
    let animated = common::animated_box(d);
    let options = ["--size", "32x24", "--spp", "4"];
    let mut args = vec!["--wait", "1", "3", "frames/f_%02d.exr", animated.as_str()];
    args.extend_from_slice(&options);
    cluster.run(farm("submit-slurm-frames.sh"), &args);
    let out = Command::new(env!("CARGO_BIN_EXE_raylab"))
        .args(
            [&["render", animated.as_str(), "--frames", "1..3", "-o", "g_%02d.exr"][..], &options]
                .concat(),
        )
        .current_dir(d)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", text(&out.stderr));
    for f in 1..=3 {
        assert_eq!(
            bits(&d.join(format!("frames/f_{f:02}.exr"))),
            bits(&d.join(format!("g_{f:02}.exr")))
        );
    }

    // One long tile, requeued (as pre-emption does: SIGTERM, then the job runs again) once it
    // has written a checkpoint: the same command goes on from it.
    let options = ["--size", "64x48", "--spp", "1500"];
    let mut args = vec!["1", "requeued.exr", scene.as_str()];
    args.extend_from_slice(&options);
    let mut submit = cluster.command(farm("submit-slurm.sh"));
    let out = submit.env("CHECKPOINT_SECONDS", "0.1").args(&args).output().unwrap();
    assert!(out.status.success(), "{}", text(&out.stderr));
    let stdout = text(&out.stdout);
    let array = stdout
        .split_whitespace()
        .skip_while(|w| *w != "array")
        .nth(1)
        .expect("the array's job id")
        .to_string();
    let checkpoint = d.join("requeued.exr.parts/tile_0.checkpoint.exr");
    let start = Instant::now();
    while !checkpoint.exists() {
        assert!(start.elapsed() < Duration::from_secs(120), "no checkpoint was written");
        std::thread::sleep(Duration::from_millis(20));
    }
    cluster.run("scontrol", &["requeue", &array]);
    // Slurm holds a requeued job back for `cred_expire` seconds (local-slurm.sh sets 10; the
    // default is 120) so that the node has let go of the old run's credential: it is pending
    // for that reason first, then it starts by itself. (Starting it at once with `scontrol
    // update StartTime=now` raced with that, and lost now and then.)
    let start = Instant::now();
    loop {
        let state = cluster.run("squeue", &["-h", "-j", &array, "-o", "%T %r"]);
        if text(&state.stdout).trim() == "PENDING BeginTime" {
            break;
        }
        assert!(start.elapsed() < Duration::from_secs(120), "{}", text(&state.stdout));
        std::thread::sleep(Duration::from_millis(50));
    }
    let output = d.join("requeued.exr");
    let start = Instant::now();
    while !output.exists() {
        if start.elapsed() > Duration::from_secs(300) {
            let log = |name: &str| {
                std::fs::read_to_string(d.join("requeued.exr.parts").join(name)).unwrap_or_default()
            };
            let queue = cluster.run("squeue", &["-h", "-o", "%i %T %r"]);
            panic!(
                "the requeued render never merged; queue:\n{}\ntile log:\n{}\nmerge log:\n{}",
                text(&queue.stdout),
                log("tile_0.log"),
                log("merge.log")
            );
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    // The merge job writes atomically, so the file is whole once it is there.
    let log = std::fs::read_to_string(d.join("requeued.exr.parts/tile_0.log")).unwrap();
    assert!(log.contains("interrupted: wrote"), "the first run was interrupted: {log}");
    assert!(log.contains("going on from"), "the requeued run went on from its checkpoint: {log}");
    assert_eq!(bits(&output), single(d, "single-requeued.exr", &options));
    assert!(!checkpoint.exists(), "the finished tile deleted its checkpoint");
}
