//! `stereocull cluster` under `mpirun` on this machine (feature `cluster`; CI runs it as
//! its second command): every rank's images and cull dumps of every frame equal one
//! process's, over 3 and 6 ranks on `cave` and 2 on `hmd-peripheral`, with a walking
//! viewer, moving and churned instances and an animated glTF; one frame equals
//! `render`'s; the README's command runs as written; and a rank that cannot start,
//! loaded another scene, is killed or receives a damaged frame ends the job non-zero
//! within seconds, naming itself, with no process left behind.

#![cfg(feature = "cluster")]

mod support;

use std::path::Path;
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

const BIN: &str = env!("CARGO_BIN_EXE_stereocull");

/// One job at a time: each takes the machine's cores, and the fault tests look for
/// ranks left behind.
static ONE_JOB: std::sync::Mutex<()> = std::sync::Mutex::new(());

fn one_job() -> std::sync::MutexGuard<'static, ()> {
    ONE_JOB
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// `mpirun` for `ranks` copies of `args` (a list of `(ranks, args)` for several
/// programs), allowed to run as root here and not on the machine.
fn mpirun(programs: &[(u32, Vec<String>)]) -> Command {
    let mut command = Command::new("mpirun");
    command
        .env("OMPI_ALLOW_RUN_AS_ROOT", "1")
        .env("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1")
        .env("LP_NUM_THREADS", "1")
        .arg("--oversubscribe");
    for (k, (ranks, args)) in programs.iter().enumerate() {
        if k > 0 {
            command.arg(":");
        }
        command
            .args(["-n", &ranks.to_string(), BIN, "cluster"])
            .args(args);
    }
    command
}

fn words(s: &str) -> Vec<String> {
    s.split_whitespace().map(String::from).collect()
}

fn run(programs: &[(u32, Vec<String>)]) -> Output {
    mpirun(programs).output().expect("mpirun runs")
}

fn files(dir: &Path) -> Vec<std::path::PathBuf> {
    let mut all = Vec::new();
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        match path.is_dir() {
            true => all.extend(files(&path)),
            false => all.push(path),
        }
    }
    all.sort();
    all
}

/// Runs `args` over each of `ranks` and over one rank, every frame written, and
/// compares every image byte for byte; returns the one-rank run's directory.
fn same_over(ranks: &[u32], args: &str, root: &Path) -> std::path::PathBuf {
    let one = root.join("one");
    let out = |dir: &Path| format!("{args} --every-frame --out {}", dir.display());
    let done = run(&[(1, words(&out(&one)))]);
    assert!(
        done.status.success(),
        "{}",
        String::from_utf8_lossy(&done.stderr)
    );
    let want = files(&one);
    assert!(want.len() >= 4, "{want:?}");
    for &n in ranks {
        let dir = root.join(format!("ranks-{n}"));
        let done = run(&[(n, words(&out(&dir)))]);
        assert!(
            done.status.success(),
            "{n} ranks: {}",
            String::from_utf8_lossy(&done.stderr)
        );
        let got = files(&dir);
        assert_eq!(got.len(), want.len(), "{n} ranks: images");
        // Exact on any CPU: every rank runs the same binary's shaders on the same
        // host's lavapipe, drawing the same draws from the same inputs.
        for (g, w) in got.iter().zip(&want) {
            assert!(
                std::fs::read(g).unwrap() == std::fs::read(w).unwrap(),
                "{n} ranks: {} differs from one process's",
                g.display()
            );
        }
    }
    one
}

#[test]
fn every_rank_draws_what_one_process_draws() {
    let _job = one_job();
    let root = tempfile::tempdir().unwrap();
    let cave = "--rig cave --scene procedural:3000 --frames 3 --moving 1 --churn 1 --walk \
                --width 48 --height 48";
    let one = same_over(&[3, 6], cave, &root.path().join("cave"));
    // The frames differ: the viewer walks and the scene changes.
    let frame = |k: u32| std::fs::read(one.join(format!("frame-{k}/front.png"))).unwrap();
    assert!(frame(0) != frame(2), "the frames are all alike");
    let animated = support::gltf_sample("BoxAnimated", "glb");
    let hmd = format!(
        "--rig hmd-peripheral --scene {} --frames 3 --time 0.4 --walk --width 48 --height 48",
        animated.display()
    );
    same_over(&[2], &hmd, &root.path().join("hmd"));
}

/// The README's cluster command exactly as written (the binary its build made, the
/// test build's here), plus only the flags the README says to add on a machine like
/// CI's, root with fewer cores than ranks: all five walls written, and on fewer cores
/// than ranks the one line that says they share them.
#[test]
fn the_readmes_command_draws_the_five_walls() {
    let _job = one_job();
    let readme = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/README.md"))
        .expect("README.md");
    let line = (readme.lines())
        .find(|l| l.starts_with("mpirun "))
        .expect("the README's mpirun command");
    let mut command = words(line);
    assert_eq!(command[3], "target/release/stereocull", "{line}");
    command[3] = BIN.into();
    // Right after `mpirun`, as the README says.
    let added = ["--allow-run-as-root", "--oversubscribe"];
    for flag in added {
        assert!(
            readme.contains(&format!("`{flag}`")),
            "the README names {flag}"
        );
    }
    let dir = tempfile::tempdir().unwrap();
    let done = Command::new(&command[0])
        .args(added)
        .args(&command[1..])
        .current_dir(dir.path())
        .output()
        .expect("mpirun runs");
    let stderr = String::from_utf8_lossy(&done.stderr);
    assert!(done.status.success(), "{stderr}");
    for wall in ["front", "left", "right", "floor", "ceiling"] {
        let image = dir.path().join(format!("out/{wall}.png"));
        assert!(image.is_file(), "{} missing", image.display());
    }
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let said = stderr.matches("ranks share").count();
    assert_eq!(said, usize::from(cores < 3), "{stderr}");
}

#[test]
fn one_frame_is_renders_frame() {
    let _job = one_job();
    let root = tempfile::tempdir().unwrap();
    let common = "--rig cave --scene procedural:2000 --width 48 --height 48 --time 0.5";
    let cluster = root.path().join("cluster");
    let done = run(&[(2, words(&format!("{common} --out {}", cluster.display())))]);
    assert!(
        done.status.success(),
        "{}",
        String::from_utf8_lossy(&done.stderr)
    );
    let render = root.path().join("render");
    let rendered = Command::new(BIN)
        .env("LP_NUM_THREADS", "1")
        .args(["render"])
        .args(words(common))
        .args(["--out", render.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(rendered.status.success());
    for name in ["front", "left", "right", "floor", "ceiling"] {
        let file = format!("{name}.png");
        assert!(
            std::fs::read(cluster.join(&file)).unwrap()
                == std::fs::read(render.join(&file)).unwrap(),
            "{name}"
        );
    }
}

/// The job's exit, its standard error, and how long it took.
fn failing(programs: &[(u32, Vec<String>)]) -> (bool, String, Duration) {
    let start = Instant::now();
    let done = run(programs);
    let stderr = String::from_utf8_lossy(&done.stderr).into_owned();
    (done.status.success(), stderr, start.elapsed())
}

/// The processes whose command line runs `stereocull cluster` (`/proc`, as `pgrep`
/// would, without needing it), with their environments.
fn ranks() -> Vec<(String, Vec<u8>)> {
    let Ok(entries) = std::fs::read_dir("/proc") else {
        return Vec::new();
    };
    entries
        .flatten()
        .filter_map(|p| {
            let cmdline = std::fs::read(p.path().join("cmdline")).ok()?;
            let args: Vec<&[u8]> = cmdline.split(|&b| b == 0).collect();
            let ours =
                args.first()?.ends_with(b"stereocull") && args.get(1) == Some(&&b"cluster"[..]);
            let environ = std::fs::read(p.path().join("environ")).ok()?;
            ours.then(|| (p.file_name().to_string_lossy().into_owned(), environ))
        })
        .collect()
}

fn no_rank_left() -> bool {
    ranks().is_empty()
}

#[test]
fn a_rank_that_fails_ends_the_job_naming_itself() {
    let _job = one_job();
    let base = "--scene procedural:2000 --width 32 --height 32 --rig cave";
    let cases = [
        (
            format!("{base} --frames 2"),
            "--scene procedural:2000 --width 32 --height 32 --rig nosuch --frames 2".to_string(),
            "rank 1 of 2: cannot start: rig nosuch",
        ),
        (
            format!("{base} --frames 2"),
            "--scene procedural:2001 --width 32 --height 32 --rig cave --frames 2".to_string(),
            "rank 1 loaded another scene",
        ),
        (
            format!("{base} --frames 4 --bad-frame 2"),
            format!("{base} --frames 4 --bad-frame 2"),
            "frame input: version",
        ),
    ];
    for (head, other, says) in cases {
        let (ok, stderr, took) = failing(&[(1, words(&head)), (1, words(&other))]);
        assert!(!ok, "{says}: the job succeeded");
        assert!(stderr.contains(says), "{says}: {stderr}");
        assert!(took < Duration::from_secs(60), "{says}: {took:?}");
    }
    assert!(no_rank_left(), "a rank outlived its job");
}

#[test]
fn a_killed_rank_ends_the_job() {
    let _job = one_job();
    let args = words("--scene procedural:2000 --width 32 --height 32 --rig cave --frames 100000");
    let mut job = mpirun(&[(3, args)])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Rank 1's process, once the job runs.
    let rank_one = || {
        ranks().into_iter().find_map(|(pid, environ)| {
            let one = environ
                .split(|&b| b == 0)
                .any(|v| v == b"OMPI_COMM_WORLD_RANK=1");
            one.then_some(pid)
        })
    };
    let start = Instant::now();
    let pid = loop {
        if let Some(pid) = rank_one() {
            break pid;
        }
        assert!(
            start.elapsed() < Duration::from_secs(60),
            "rank 1 never started"
        );
        std::thread::sleep(Duration::from_millis(100));
    };
    std::thread::sleep(Duration::from_secs(2));
    let killed = Instant::now();
    Command::new("kill").args(["-9", &pid]).status().unwrap();
    let status = loop {
        if let Some(status) = job.try_wait().unwrap() {
            break status;
        }
        assert!(
            killed.elapsed() < Duration::from_secs(30),
            "the job outlived its rank"
        );
        std::thread::sleep(Duration::from_millis(100));
    };
    assert!(!status.success());
    std::thread::sleep(Duration::from_millis(500));
    assert!(no_rank_left(), "a rank outlived its job");
}

/// A rig file assigns displays to ranks: rank 0 draws the walls given it, and the images
/// are still `render`'s; a rank past the job's is an error naming the display.
#[test]
fn a_rig_file_assigns_displays_to_ranks() {
    let _job = one_job();
    let root = tempfile::tempdir().unwrap();
    let mut rig = stereocull::rig::Rig::preset("cave").unwrap();
    for (d, rank) in rig.displays.iter_mut().zip([1, 1, 0, 0, 1]) {
        d.rank = Some(rank);
    }
    let file = root.path().join("cave.json");
    std::fs::write(&file, serde_json::to_string(&rig).unwrap()).unwrap();
    let common = format!(
        "--rig {} --scene procedural:2000 --width 48 --height 48",
        file.display()
    );
    let out = root.path().join("cluster");
    let done = run(&[(2, words(&format!("{common} --out {}", out.display())))]);
    let stdout = String::from_utf8_lossy(&done.stdout);
    assert!(
        done.status.success(),
        "{}",
        String::from_utf8_lossy(&done.stderr)
    );
    assert!(stdout.contains("rank 0 draws right, floor"), "{stdout}");
    let render = root.path().join("render");
    let rendered = Command::new(BIN)
        .env("LP_NUM_THREADS", "1")
        .arg("render")
        .args(words(&common))
        .args(["--out", render.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(rendered.status.success());
    for d in &rig.displays {
        let file = format!("{}.png", d.name);
        assert!(
            std::fs::read(out.join(&file)).unwrap() == std::fs::read(render.join(&file)).unwrap()
        );
    }
    let (ok, stderr, _) = failing(&[(1, words(&common))]);
    assert!(
        !ok && stderr.contains("display \"front\" is assigned to rank 1, the job has 1 ranks"),
        "{stderr}"
    );
}
