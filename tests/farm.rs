//! Past one machine (docs/farm.md): `render --tile` and `wpbgi assemble` from the outside, the
//! Open Job Description template in `farm/` run by `openjd run`, and the Slurm scripts on a
//! single-node Slurm started by the test. Every route must give frames equal byte for byte
//! to a single-process `render --frames` of the same cache.

mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

const WPBGI: &str = env!("CARGO_BIN_EXE_wpbgi");
/// A fixed capture date and no timings in the EXR headers, so that two renders of one frame
/// are the same bytes.
const EPOCH: &str = "1764000000";
/// Small enough for the suite, and neither side a multiple of the render's 32-pixel tiles (its
/// tiles at this size, `render::tile_side`; a
/// 2 × 2 grid then has one column boundary on a tile boundary and its row boundary off one).
const SIZE: &str = "64x40";

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn dir(name: &str) -> common::Scratch {
    common::Scratch::new(&format!("farm-{name}"))
}

fn utf8(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

fn wpbgi(args: &[&str]) -> Output {
    Command::new(WPBGI)
        .args(args)
        .env("SOURCE_DATE_EPOCH", EPOCH)
        .output()
        .expect("runs")
}

fn assert_ok(out: &Output, what: &str) {
    assert!(
        out.status.success(),
        "{what}: {}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
}

/// `out` failed with one line of standard error that says `needle`.
fn assert_refused(out: &Output, needle: &str) {
    assert!(!out.status.success());
    let msg = String::from_utf8_lossy(&out.stderr);
    assert!(msg.contains(needle) && msg.lines().count() == 1, "{msg}");
}

/// Bake `scene` small into `cache`.
fn bake(scene: &Path, cache: &Path) {
    let mut args = vec!["bake", utf8(scene), "-o", utf8(cache)];
    args.extend(common::SMALL_BAKE);
    let out = wpbgi(&args);
    assert_ok(&out, "bake");
}

/// The frames `frames` of `scene` rendered by one process from `cache` into `dir`, as
/// `beauty.####.exr`.
fn single_process(scene: &Path, cache: &Path, dir: &Path, frames: &str) {
    let out = wpbgi(&[
        "render",
        utf8(scene),
        "--cache",
        utf8(cache),
        "--frames",
        frames,
        "--size",
        SIZE,
        "-o",
        utf8(&dir.join("beauty.$F4.exr")),
    ]);
    assert_ok(&out, "single-process render");
}

/// Frames `frames` (four-digit numbers) of `a` and `b` are the same bytes.
fn assert_same_frames(a: &Path, b: &Path, frames: &[u32]) {
    for f in frames {
        let name = format!("beauty.{f:04}.exr");
        let (x, y) = (
            std::fs::read(a.join(&name))
                .unwrap_or_else(|e| panic!("{}: {e}", a.join(&name).display())),
            std::fs::read(b.join(&name))
                .unwrap_or_else(|e| panic!("{}: {e}", b.join(&name).display())),
        );
        assert!(
            x == y,
            "frame {f}: {} and {} differ",
            a.display(),
            b.display()
        );
    }
}

/// The bundled scene's cache rendered tile by tile (`--tile` on a 2 × 2 grid) and assembled
/// equals the whole render byte for byte; tiles whose headers differ only in their times
/// (no `SOURCE_DATE_EPOCH`) assemble; `assemble` refuses a missing tile, an overlapping one
/// and a tile of another render, writing nothing.
#[test]
fn tiles_assemble_into_the_whole_frame() {
    let d = dir("assemble");
    let scene = root().join("scenes/cbox-rough.gltf");
    let cache = d.join("scene.wpc");
    bake(&scene, &cache);
    let whole = d.join("whole");
    std::fs::create_dir_all(&whole).expect("dir");
    single_process(&scene, &cache, &whole, "1");
    // Tile (column, row) of the 2 × 2 grid; `timed`: without SOURCE_DATE_EPOCH.
    let render_tile = |column: u32, row: u32, extra: &[&str], timed: bool| {
        let name = if timed { "timed" } else { "tile" };
        let path = d.join(format!("{name}.c{column}r{row}.exr"));
        let mut cmd = Command::new(WPBGI);
        cmd.args([
            "render",
            utf8(&scene),
            "--cache",
            utf8(&cache),
            "--size",
            SIZE,
        ])
        .args(["--tile-grid", "2x2", "--tile", &format!("{column},{row}")])
        .args(["-o", utf8(&path)])
        .args(extra);
        if timed {
            cmd.env_remove("SOURCE_DATE_EPOCH");
        } else {
            cmd.env("SOURCE_DATE_EPOCH", EPOCH);
        }
        (path, cmd.output().expect("runs"))
    };
    let tile = |column: u32, row: u32, extra: &[&str]| {
        let (path, out) = render_tile(column, row, extra, false);
        assert_ok(&out, "tile render");
        path
    };
    let tiles = [
        tile(1, 1, &[]),
        tile(2, 1, &[]),
        tile(1, 2, &[]),
        tile(2, 2, &[]),
    ];
    let assembled = d.join("assembled");
    std::fs::create_dir_all(&assembled).expect("dir");
    let mut args = vec!["assemble", "-o"];
    let frame = assembled.join("beauty.0001.exr");
    args.push(utf8(&frame));
    args.extend(tiles.iter().rev().map(|p| utf8(p)));
    assert_ok(&wpbgi(&args), "assemble");
    assert_same_frames(&whole, &assembled, &[1]);

    // Without SOURCE_DATE_EPOCH each tile's header has its own capture date and seconds:
    // the tiles still assemble, the frame taking the latest date and the seconds summed.
    let timed: Vec<PathBuf> = [(1, 1), (2, 1), (1, 2), (2, 2)]
        .iter()
        .map(|&(column, row)| {
            let (path, out) = render_tile(column, row, &[], true);
            assert_ok(&out, "timed tile render");
            path
        })
        .collect();
    let timed_frame = d.join("timed.exr");
    let mut args = vec!["assemble", "-o", utf8(&timed_frame)];
    args.extend(timed.iter().map(|p| utf8(p)));
    assert_ok(&wpbgi(&args), "assemble of timed tiles");
    let header = std::fs::read(&timed_frame).expect("timed frame");
    assert!(header.windows(14).any(|w| w == b"render_seconds"));

    let refused = d.join("refused.exr");
    let assemble = |tiles: &[&Path]| {
        let mut args = vec!["assemble", "-o", utf8(&refused)];
        args.extend(tiles.iter().map(|p| utf8(p)));
        wpbgi(&args)
    };
    let [a, b, c, e] = &tiles;
    assert_refused(&assemble(&[a, b, c]), "missing");
    assert_refused(&assemble(&[a, b, c, e, b]), "overlaps");
    // A tile of a render with other settings: its header says so.
    let other = tile(2, 2, &["--seed", "7"]);
    assert_refused(&assemble(&[a, b, c, &other]), "header");
    assert!(!refused.exists(), "a refused assembly wrote its output");
    // A tile outside the grid is refused by the render.
    let (_, out) = render_tile(3, 1, &[], false);
    assert_refused(&out, "not in the 2x2 grid");
}

/// `render::grid_crop`'s tiles cover the image exactly once for every grid up to 7 × 7 on
/// sizes around multiples of the render's tiles (32 pixels under 512 on the shorter side,
/// 64 from 512); inner bounds fall on multiples of the tile where every tile stays non-empty
/// so; grids larger than the image and tiles outside the grid are refused.
#[test]
fn grid_tiles_partition_the_image() {
    use wpbgi::render::{grid_crop, tile_side};
    for (w, h) in [(256, 256), (64, 40), (100, 37), (1920, 1080), (7, 5)] {
        for columns in 1..=7u32 {
            for rows in 1..=7u32 {
                if columns > w || rows > h {
                    assert!(grid_crop((w, h), [columns, rows], [1, 1]).is_err());
                    continue;
                }
                let mut covered = vec![0u8; (w * h) as usize];
                for row in 1..=rows {
                    for column in 1..=columns {
                        let [x0, y0, x1, y1] =
                            grid_crop((w, h), [columns, rows], [column, row]).expect("in grid");
                        assert!(x0 < x1 && y0 < y1, "{w}x{h} {columns}x{rows}: empty tile");
                        for y in y0..y1 {
                            for x in x0..x1 {
                                covered[(y * w + x) as usize] += 1;
                            }
                        }
                    }
                }
                assert!(covered.iter().all(|&c| c == 1), "{w}x{h} {columns}x{rows}");
            }
        }
    }
    // 1920 = 30 tiles of 64: three columns split at 640 and 1280, on tile boundaries;
    // 1080 rows in two: 540 rounds down to 512.
    assert_eq!(
        grid_crop((1920, 1080), [3, 2], [2, 2]).ok(),
        Some([640, 512, 1280, 1080])
    );
    assert_eq!((tile_side(1920, 1080), tile_side(64, 40)), (64, 32));
    // 1000 × 600 (tiles of 64) in two columns: 500 rounds down to 448, where tiles of 32
    // would have kept 480.
    assert_eq!(
        grid_crop((1000, 600), [2, 1], [1, 1]).ok(),
        Some([0, 0, 448, 600])
    );
    // 64 × 40 in a 2 × 2 grid: the column bound lands on 32, the row bound cannot (0 would
    // empty the first row) and stays at 20.
    assert_eq!(
        grid_crop((64, 40), [2, 2], [2, 2]).ok(),
        Some([32, 20, 64, 40])
    );
    assert!(grid_crop((64, 40), [2, 2], [3, 1]).is_err());
    assert!(grid_crop((64, 40), [0, 2], [1, 1]).is_err());
}

/// The Open Job Description CLI, from `WPBGI_OPENJD` or the PATH (scripts/test.sh installs
/// openjd-cli into target/farm-venv and names it).
fn openjd() -> Option<PathBuf> {
    if let Some(p) = std::env::var_os("WPBGI_OPENJD") {
        return Some(PathBuf::from(p));
    }
    let found = Command::new("openjd")
        .arg("--help")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success());
    found.then(|| PathBuf::from("openjd"))
}

/// `farm/wpbgi.openjd.yaml` run locally by `openjd run` on the bundled scene, 2 frames on a
/// 2 × 2 tile grid (bake, 8 tile renders, 2 assemblies): both frames equal the
/// single-process render of its cache byte for byte.
#[test]
fn the_openjd_template_renders_what_one_process_does() {
    let Some(openjd) = openjd() else {
        eprintln!(
            "skipped: no Open Job Description CLI (pip install openjd-cli, or set WPBGI_OPENJD); \
             scripts/test.sh installs it"
        );
        return;
    };
    let d = dir("openjd");
    let scene = root().join("scenes/cbox-rough.gltf");
    let out = d.join("out");
    let params = [
        format!("Scene={}", utf8(&scene)),
        format!("OutputDir={}", utf8(&out)),
        "Frames=1-2".to_string(),
        "TileColumns=2".to_string(),
        "TileRows=2".to_string(),
        "BakeArgs=--points 2000 --light-samples 16 --bounces 2".to_string(),
        format!("RenderArgs=--size {SIZE}"),
        format!("Wpbgi={WPBGI}"),
    ];
    let mut cmd = Command::new(&openjd);
    cmd.arg("run")
        .arg(root().join("farm/wpbgi.openjd.yaml"))
        .args(["--step", "Assemble", "--run-dependencies"])
        .env("SOURCE_DATE_EPOCH", EPOCH);
    for p in &params {
        cmd.args(["-p", p]);
    }
    let run = cmd.output().expect("openjd runs");
    assert_ok(&run, "openjd run");
    let tiles = std::fs::read_dir(out.join("tiles")).expect("tiles").count();
    assert_eq!(tiles, 8, "2 frames × 4 tiles");
    let single = d.join("single");
    std::fs::create_dir_all(&single).expect("dir");
    single_process(&scene, &out.join("scene.wpc"), &single, "1-2");
    assert_same_frames(&single, &out, &[1, 2]);
}

/// A single-node Slurm (munged, slurmctld and slurmd on localhost, configured in a temporary
/// folder) runs `farm/slurm/submit.sh` on the camera-dolly stage (2 frames that differ) with
/// a 2 × 2 grid: bake, a render array after it and an assembly array after that. One render
/// task is killed once while it runs; Slurm requeues it and the frames still equal the
/// single-process render byte for byte.
///
/// It needs root (the daemons run as root) and the Debian packages `slurm-wlm` and `munge`,
/// which scripts/test.sh installs. Where either is missing it says so and returns; by hand:
/// `sudo apt-get install slurm-wlm munge && cargo test --release --test farm slurm`.
#[test]
fn slurm_renders_what_one_process_does_after_a_killed_task() {
    let missing: Vec<&str> = ["munged", "slurmctld", "slurmd", "sbatch", "mungekey"]
        .into_iter()
        .filter(|b| which(b).is_none())
        .collect();
    let root_user = Command::new("id")
        .arg("-u")
        .output()
        .is_ok_and(|o| o.stdout.starts_with(b"0\n"));
    if !missing.is_empty() || !root_user {
        eprintln!(
            "skipped: the single-node Slurm needs root and the packages slurm-wlm and munge \
             (missing: {missing:?}, root: {root_user}); scripts/test.sh installs them"
        );
        return;
    }
    let d = dir("slurm");
    let Some(cluster) = Cluster::start(&d) else {
        // The machine, not wpbgi: the daemons did not start (their logs are printed).
        return;
    };
    let stage = root().join("tests/data/usd/cbox-dolly.usda");
    let out = d.join("out");
    let submit = Command::new(root().join("farm/slurm/submit.sh"))
        .arg(&stage)
        .arg(&out)
        .args(["--frames", "1-2", "--tiles", "2x2", "--retries", "1"])
        .args([
            "--bake-args",
            "--points 2000 --light-samples 16 --bounces 2",
        ])
        .args(["--render-args", &format!("--size {SIZE}")])
        .args(["--wpbgi", WPBGI])
        .envs(cluster.env())
        .env("SOURCE_DATE_EPOCH", EPOCH)
        .output()
        .expect("submit.sh runs");
    assert_ok(&submit, "submit.sh");
    // Kill one render task's wpbgi once, while it runs (this test's: the other tests render
    // tiles too, from other caches).
    let deadline = Instant::now() + Duration::from_secs(300);
    let cache = out.join("scene.wpc");
    let killed = loop {
        if let Some(pid) = render_task(&cache, "2,1") {
            // SAFETY: kill(2) on a process id read from /proc just now; at worst the process
            // has ended and the call fails.
            break unsafe { libc::kill(pid, libc::SIGKILL) } == 0;
        }
        assert!(
            Instant::now() < deadline,
            "no render task ran within 5 minutes"
        );
        std::thread::sleep(Duration::from_millis(20));
    };
    assert!(killed, "could not kill the render task");
    // Wait for both frames.
    let frames = [out.join("beauty.0001.exr"), out.join("beauty.0002.exr")];
    let deadline = Instant::now() + Duration::from_secs(600);
    while !frames.iter().all(|f| f.exists()) {
        assert!(
            Instant::now() < deadline,
            "the frames did not appear within 10 minutes; logs in {}",
            out.join("logs").display()
        );
        std::thread::sleep(Duration::from_millis(200));
    }
    let logs: String = std::fs::read_dir(out.join("logs"))
        .expect("logs")
        .flatten()
        .map(|e| std::fs::read_to_string(e.path()).unwrap_or_default())
        .collect();
    assert!(logs.contains("requeued"), "no task was requeued:\n{logs}");
    let single = d.join("single");
    std::fs::create_dir_all(&single).expect("dir");
    single_process(&stage, &out.join("scene.wpc"), &single, "1-2");
    assert_same_frames(&single, &out, &[1, 2]);
    let (one, two) = (
        std::fs::read(&frames[0]).expect("frame 1"),
        std::fs::read(&frames[1]).expect("frame 2"),
    );
    assert!(one != two, "the camera moves: frames 1 and 2 differ");
    drop(cluster);
}

/// The process id of a running `wpbgi render` of tile `tile` from `cache`, read from
/// /proc (no procps needed).
fn render_task(cache: &Path, tile: &str) -> Option<i32> {
    let want = ["render", "--cache", utf8(cache), "--tile", tile];
    std::fs::read_dir("/proc").ok()?.flatten().find_map(|e| {
        let pid: i32 = e.file_name().to_str()?.parse().ok()?;
        let cmdline = std::fs::read(e.path().join("cmdline")).ok()?;
        let args: Vec<&[u8]> = cmdline.split(|&b| b == 0).collect();
        let has = |w: &str| args.contains(&w.as_bytes());
        let is_wpbgi = args.first().is_some_and(|a| a.ends_with(b"wpbgi"));
        (is_wpbgi && want.iter().all(|w| has(w))).then_some(pid)
    })
}

fn which(name: &str) -> Option<PathBuf> {
    let path = std::env::var_os("PATH").unwrap_or_default();
    std::env::split_paths(&path)
        .chain(["/usr/sbin".into(), "/sbin".into()])
        .map(|p| p.join(name))
        .find(|p| p.is_file())
}

/// munged, slurmctld and slurmd on localhost, all state under one folder; stopped on drop.
/// Its one departure from Slurm's defaults: `cred_expire=10`, which is also how long a
/// requeued task waits before it may start again (120 s by default, slurm.conf(5)).
struct Cluster {
    dir: PathBuf,
    daemons: Vec<std::process::Child>,
}

impl Cluster {
    /// The cluster, up; or `None`, having printed the daemons' logs, where this machine
    /// cannot run them (the test then says so and returns: what it tests is the scripts and
    /// wpbgi under a working Slurm, not the machine).
    fn start(dir: &Path) -> Option<Cluster> {
        let dir = dir.join("slurm");
        for sub in ["state", "spool", "log", "munge"] {
            std::fs::create_dir_all(dir.join(sub)).expect("slurm dirs");
        }
        // Ports of our own, so that a Slurm already on the machine is left alone.
        let base = 17_000 + (std::process::id() % 1000) as u16 * 2;
        let cpus = std::thread::available_parallelism().map_or(1, |n| n.get());
        let conf = format!(
            "ClusterName=wpbgitest\nSlurmctldHost=localhost\nSlurmUser=root\n\
             SlurmctldPort={}\nSlurmdPort={}\nAuthType=auth/munge\n\
             AuthInfo=socket={},cred_expire=10\nStateSaveLocation={}\nSlurmdSpoolDir={}\n\
             SlurmctldPidFile={}\nSlurmdPidFile={}\nSlurmctldLogFile={}\nSlurmdLogFile={}\n\
             ProctrackType=proctrack/linuxproc\nTaskPlugin=task/none\n\
             SelectType=select/cons_tres\nSelectTypeParameters=CR_CPU\n\
             JobRequeue=1\nReturnToService=2\nSchedulerType=sched/builtin\n\
             MpiDefault=none\nJobAcctGatherType=jobacct_gather/none\n\
             NodeName=localhost CPUs={cpus} State=UNKNOWN\n\
             PartitionName=test Nodes=localhost Default=YES MaxTime=INFINITE State=UP\n",
            base,
            base + 1,
            utf8(&dir.join("munge/munge.socket")),
            utf8(&dir.join("state")),
            utf8(&dir.join("spool")),
            utf8(&dir.join("slurmctld.pid")),
            utf8(&dir.join("slurmd.pid")),
            utf8(&dir.join("log/slurmctld.log")),
            utf8(&dir.join("log/slurmd.log")),
        );
        std::fs::write(dir.join("slurm.conf"), conf).expect("slurm.conf");
        let key = dir.join("munge/munge.key");
        let status = Command::new(which("mungekey").expect("mungekey"))
            .args(["--create", "--keyfile", utf8(&key)])
            .status()
            .expect("mungekey");
        assert!(status.success(), "mungekey");
        let spawn = |name: &str, args: &[&str]| {
            Command::new(which(name).unwrap_or_else(|| panic!("{name}")))
                .args(args)
                .env("SLURM_CONF", dir.join("slurm.conf"))
                .stdout(Stdio::null())
                .stderr(Stdio::null())
                .spawn()
                .unwrap_or_else(|e| panic!("{name}: {e}"))
        };
        let mut cluster = Cluster {
            dir: dir.clone(),
            daemons: Vec::new(),
        };
        cluster.daemons.push(spawn(
            "munged",
            &[
                "--foreground",
                "--force",
                "--key-file",
                utf8(&key),
                "--socket",
                utf8(&dir.join("munge/munge.socket")),
                "--pid-file",
                utf8(&dir.join("munge/munged.pid")),
                "--seed-file",
                utf8(&dir.join("munge/munged.seed")),
                "--log-file",
                utf8(&dir.join("log/munged.log")),
            ],
        ));
        std::thread::sleep(Duration::from_millis(500));
        cluster.daemons.push(spawn("slurmctld", &["-D", "-i"]));
        std::thread::sleep(Duration::from_millis(500));
        cluster
            .daemons
            .push(spawn("slurmd", &["-D", "-N", "localhost"]));
        // Wait for the node to be idle.
        let deadline = Instant::now() + Duration::from_secs(60);
        loop {
            let out = Command::new(which("sinfo").expect("sinfo"))
                .args(["-h", "-o", "%t"])
                .envs(cluster.env())
                .output();
            if out.is_ok_and(|o| String::from_utf8_lossy(&o.stdout).trim() == "idle") {
                break;
            }
            if Instant::now() > deadline {
                let logs: String = std::fs::read_dir(dir.join("log"))
                    .into_iter()
                    .flatten()
                    .flatten()
                    .map(|e| {
                        let text = std::fs::read_to_string(e.path()).unwrap_or_default();
                        format!("--- {}\n{text}", e.path().display())
                    })
                    .collect();
                eprintln!(
                    "skipped: the single-node Slurm did not come up within 60 s on this \
                     machine; its logs:\n{logs}"
                );
                return None;
            }
            std::thread::sleep(Duration::from_millis(250));
        }
        Some(cluster)
    }

    fn env(&self) -> Vec<(&'static str, PathBuf)> {
        vec![("SLURM_CONF", self.dir.join("slurm.conf"))]
    }
}

impl Drop for Cluster {
    fn drop(&mut self) {
        for d in self.daemons.iter_mut().rev() {
            let _ = d.kill();
            let _ = d.wait();
        }
    }
}
