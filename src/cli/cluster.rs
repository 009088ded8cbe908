//! `stereocull cluster`, under `mpirun`: a rig's displays over MPI ranks, frame-locked.
//! Rank 0, the head, walks the viewer, makes the scene's edits (`--moving`, `--churn`)
//! and broadcasts each frame's input ([`FrameInput`], as bytes); every rank applies it
//! to its own copy of the scene and draws its displays (a rig file's `rank` per
//! display, else round robin over the ranks that draw), waits for its GPU, then for every other rank at a barrier (the swap lock), and
//! then presents: writes its images, or counts the frame. Rank 0 gathers each rank's
//! figures.
//!
//! Nothing hangs and nothing is silent: a rank that cannot start (no adapter, a bad
//! rig, another scene) or receives a damaged frame prints one line naming itself and
//! the cause and aborts the job (`MPI_Abort`), which ends every rank; a rank killed
//! outright ends the job through `mpirun`.

use std::path::PathBuf;
use std::time::Instant;

use clap::Parser;
use mpi::traits::{Communicator, CommunicatorCollectives, Root};

use super::cull::display_dump;
use super::edits::{EditArgs, EditDriver};
use super::render::display_images;
use super::save;
use super::session::Session;
use super::{SceneArgs, write_json};
use crate::error::{Error, Result};
use crate::frame_input::{FrameInput, scene_identity};
use crate::live::LiveScene;
use crate::renderer::{CullMode, StereoMode, instances_per_object};
use crate::rig::Viewer;

/// Seconds between frames (90 Hz).
const FRAME_SECONDS: f32 = 1.0 / 90.0;

#[derive(Parser)]
pub struct ClusterArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    #[command(flatten)]
    pub edits: EditArgs,
    /// Frames to run.
    #[arg(long, default_value_t = 1)]
    pub frames: u32,
    /// The first frame's time in seconds; frame k is drawn at `time + k / 90`.
    #[arg(long, default_value_t = 0.0)]
    pub time: f32,
    /// Write each rank's displays of the last frame here, named as `render` names them
    /// (`<display>.png`); without it a rank only counts its frames.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// With `--out`: every frame's images, under `frame-<k>/`.
    #[arg(long)]
    pub every_frame: bool,
    /// The viewer looks around and sways, as `stress` walks it (off: it stands).
    #[arg(long)]
    pub walk: bool,
    /// Whether the head (rank 0) draws displays too, or only leads.
    #[arg(long, value_enum, default_value = "on")]
    pub head_draws: super::Switch,
    #[arg(long, value_enum, default_value = "gpu")]
    pub cull: CullMode,
    #[arg(long, value_enum, default_value = "instanced")]
    pub mode: StereoMode,
    /// MSAA samples per pixel (default as `render`'s).
    #[arg(long)]
    pub msaa: Option<u32>,
    /// Fault injection for the tests: the head sends frame K with a version no rank
    /// reads, which must stop the job.
    #[arg(long, hide = true)]
    pub bad_frame: Option<u32>,
}

/// What every rank tells the head at the start: whether it opened, and what it loaded.
const HELLO_BYTES: usize = 1 + 32;

pub fn cluster(args: &ClusterArgs) -> Result<()> {
    let Some(universe) = mpi::initialize() else {
        return Err(Error::Unsupported(
            "MPI was initialized already in this process".into(),
        ));
    };
    let world = universe.world();
    let (rank, ranks) = (world.rank(), world.size());
    let fail = |what: &str, e: &Error| -> ! {
        eprintln!("stereocull cluster: rank {rank} of {ranks}: {what}: {e}");
        world.abort(2)
    };
    let shared = shared_cores(&world);
    let opened = open(args, rank as u32, ranks as u32);
    let identity = scene_identity(&args.scene.scene).unwrap_or_else(|e| fail("scene", &e));
    let mut hello = [0u8; HELLO_BYTES];
    hello[0] = u8::from(opened.is_ok());
    hello[1..].copy_from_slice(&identity);
    let mut all = vec![0u8; HELLO_BYTES * ranks as usize];
    world.all_gather_into(&hello[..], &mut all[..]);
    let mut node = opened.unwrap_or_else(|e| fail("cannot start", &e));
    for (r, theirs) in all.chunks(HELLO_BYTES).enumerate() {
        if theirs[0] == 0 {
            // That rank names its own cause and aborts the job, this rank with it.
            world.barrier();
        }
        if theirs[1..] != identity[..] && rank == 0 {
            let hex = |b: &[u8]| b.iter().map(|x| format!("{x:02x}")).collect::<String>();
            let e = Error::InvalidScene(format!(
                "rank {r} loaded another scene: {} here, {} there",
                hex(&identity),
                hex(&theirs[1..])
            ));
            fail("scene identity", &e);
        }
    }
    let mut figures = Figures::default();
    for frame in 0..args.frames {
        let input = match &mut node.head {
            Some(head) => Some(head.input(args, frame)?),
            None => None,
        };
        let mut bytes = input.as_ref().map(FrameInput::to_bytes);
        if let Some(b) = bytes.as_mut().filter(|_| args.bad_frame == Some(frame)) {
            b[4] ^= 0x80;
        }
        let sent = Instant::now();
        let bytes = broadcast(&world, bytes);
        let input = FrameInput::from_bytes(&bytes).unwrap_or_else(|e| fail("frame input", &e));
        let received = sent.elapsed();
        let start = Instant::now();
        if let Some(session) = &mut node.session {
            // As `render` primes occlusion: two frames at the first one's pose, unedited.
            let primed = frame == 0 && session.renderer.occlusion_bytes().is_some();
            let still = FrameInput {
                edits: Vec::new(),
                ..input.clone()
            };
            for _ in 0..2 * u32::from(primed) {
                session
                    .frame_from(&still)
                    .unwrap_or_else(|e| fail("frame", &e));
                session.gpu.wait().unwrap_or_else(|e| fail("frame", &e));
            }
            session
                .frame_from(&input)
                .unwrap_or_else(|e| fail("frame", &e));
            session.gpu.wait().unwrap_or_else(|e| fail("frame", &e));
        }
        let drawn = start.elapsed();
        figures.arrivals.push(since_epoch_us());
        world.barrier();
        figures.push([received, drawn, start.elapsed() - drawn], bytes.len());
        let last = frame + 1 == args.frames;
        if let (Some(out), Some(session)) = (&args.out, &node.session)
            && (last || args.every_frame)
        {
            let dir = match args.every_frame {
                true => out.join(format!("frame-{frame}")),
                false => out.clone(),
            };
            present(session, &dir).unwrap_or_else(|e| fail("present", &e));
        }
    }
    report(&world, &node, &figures, shared);
    Ok(())
}

/// Whether this machine runs more of the job's ranks than it has cores; if so, its
/// first rank says so once, before the first frame. Such ranks take turns on the
/// cores (three lavapipe ranks on two: each frame's draw waits for the others'), so
/// the swap-lock skew measures the sharing: 80 ms at 256 x 256 a wall, 1.4 s at the
/// `cave`'s 1024 x 1024, where a cluster's is a fraction of a millisecond.
fn shared_cores(world: &impl Communicator) -> bool {
    let here = world.split_shared(world.rank());
    let (ranks, cores) = (here.size() as usize, available_cores());
    let shared = ranks > cores;
    if shared && here.rank() == 0 {
        eprintln!(
            "stereocull cluster: {ranks} ranks share {cores} cores on this machine: they take \
             turns, so frames are slow and the swap-lock skew measures the sharing, not the \
             lock (no fault)"
        );
    }
    shared
}

fn available_cores() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

/// One rank: what it draws (none where it draws no display), and on rank 0 the head.
struct Node {
    session: Option<Session>,
    head: Option<Head>,
    displays: Vec<String>,
}

/// The head's own copy of the scene, which its edits are made on and sent from, and
/// where its viewer starts.
struct Head {
    live: Option<(LiveScene, EditDriver)>,
    viewer: Viewer,
}

impl Head {
    /// Frame `frame`'s input: the viewer walked, the driver's edits.
    fn input(&mut self, args: &ClusterArgs, frame: u32) -> Result<FrameInput> {
        let mut viewer = self.viewer;
        if args.walk {
            let phase = frame as f32 / args.frames.max(1) as f32 * std::f32::consts::TAU;
            viewer.yaw_deg += 40.0 * phase.sin();
            viewer.position[0] += 0.3 * (2.0 * phase).sin();
        }
        let edits = match &mut self.live {
            Some((live, driver)) => driver.apply(live, frame)?,
            None => Vec::new(),
        };
        Ok(FrameInput {
            frame: frame as u64,
            time: args.time + frame as f32 * FRAME_SECONDS,
            viewer,
            gaze: None,
            edits,
        })
    }
}

/// Opens rank `rank`'s part: its displays (those the rig file assigns it, then round
/// robin over the ranks that draw) and, on rank 0, the head.
fn open(args: &ClusterArgs, rank: u32, ranks: u32) -> Result<Node> {
    let rig = args.scene.load_rig(&args.scene.load_scene()?)?;
    if let Some(d) = rig
        .displays
        .iter()
        .find(|d| d.rank.is_some_and(|r| r >= ranks))
    {
        let message = format!(
            "display {:?} is assigned to rank {}, the job has {ranks} ranks",
            d.name,
            d.rank.unwrap_or_default()
        );
        return Err(Error::rig(&args.scene.rig, message));
    }
    let drawing_from = u32::from(!args.head_draws.on() && ranks > 1);
    let round_robin =
        |i: usize| rank >= drawing_from && i as u32 % (ranks - drawing_from) == rank - drawing_from;
    let displays: Vec<String> = (rig.displays.iter().enumerate())
        .filter(|&(i, d)| d.rank.map_or_else(|| round_robin(i), |r| r == rank))
        .map(|(_, d)| d.name.clone())
        .collect();
    let session = match displays.is_empty() {
        true => None,
        false => {
            let mut scene = args.scene.clone();
            scene.displays = displays.clone();
            let how = (args.cull, args.mode, args.msaa, false);
            Some(Session::open(&scene, how, &args.edits, args.time)?)
        }
    };
    let head = match rank {
        0 => {
            let scene = args.scene.load_scene()?;
            let posing = args.scene.posing.resolve(args.cull);
            let live = super::edits::live_copy(&scene, &args.edits, posing)?;
            Some(Head {
                live,
                viewer: rig.viewer,
            })
        }
        _ => None,
    };
    Ok(Node {
        session,
        head,
        displays,
    })
}

/// The head's bytes on every rank (`bytes` given on rank 0 only).
fn broadcast(world: &impl Communicator, bytes: Option<Vec<u8>>) -> Vec<u8> {
    let root = world.process_at_rank(0);
    let mut length = bytes.as_ref().map_or(0, |b| b.len() as u64);
    root.broadcast_into(&mut length);
    let mut buffer = bytes.unwrap_or_else(|| vec![0; length as usize]);
    root.broadcast_into(&mut buffer[..]);
    buffer
}

/// Writes every display of `session`'s last frame into `dir` as `render` names them,
/// and its cull buffers beside as `<display>.cull.json` (as `stereocull cull` dumps a
/// display).
fn present(session: &Session, dir: &std::path::Path) -> Result<()> {
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    let (device, queue) = (&session.gpu.device, &session.gpu.queue);
    let options = session.renderer.options();
    for (index, display) in session.rig.displays.iter().enumerate() {
        let (drawn, composite) = display_images(session, index)?;
        save(
            &composite.unwrap_or(drawn),
            &dir.join(format!("{}.png", display.name)),
        )?;
        let cull = session.renderer.diagnostics(device, queue).cull(index)?;
        let views = match (options.inset_cull, display.views()) {
            (true, 4) => 2,
            (_, views) => views,
        };
        let per_object = instances_per_object(options.mode, views);
        let dump = display_dump(&display.name, per_object, &cull, session.current_scene());
        write_json(&dir.join(format!("{}.cull.json", display.name)), &dump)?;
    }
    Ok(())
}

/// A rank's frames: milliseconds receiving the frame's input (broadcast and decode),
/// drawing (sync to GPU idle) and waiting at the swap lock; the input's bytes.
#[derive(Default)]
struct Figures {
    ms: [Vec<f64>; 3],
    bytes: Vec<usize>,
    /// When the rank reached each frame's swap lock: microseconds of the system clock
    /// (one host's ranks share it; across machines it is as good as their clocks' sync).
    arrivals: Vec<f64>,
}

impl Figures {
    fn push(&mut self, phases: [std::time::Duration; 3], bytes: usize) {
        for (v, d) in self.ms.iter_mut().zip(phases) {
            v.push(d.as_secs_f64() * 1e3);
        }
        self.bytes.push(bytes);
    }

    /// The medians of the three phases, then of the bytes.
    fn medians(&self) -> [f64; 4] {
        let bytes: Vec<f64> = self.bytes.iter().map(|&b| b as f64).collect();
        let [a, b, c] = &self.ms;
        [a, b, c, &bytes].map(|v| median_p95(v)[0])
    }
}

fn since_epoch_us() -> f64 {
    let now = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH);
    now.map_or(0.0, |d| d.as_secs_f64() * 1e6)
}

/// The median and 95th percentile of `v`.
fn median_p95(v: &[f64]) -> [f64; 2] {
    let mut v = v.to_vec();
    v.sort_by(f64::total_cmp);
    let at = |q: f64| {
        v.get(((v.len() as f64 - 1.0) * q).round() as usize)
            .copied()
    };
    [at(0.5).unwrap_or(0.0), at(0.95).unwrap_or(0.0)]
}

/// Rank 0 prints one line per rank: its frames' medians of receiving the input,
/// drawing and the swap lock's wait, and the input's bytes; the skew says where ranks
/// share the head's machine's cores (`shared`).
fn report(world: &impl Communicator, node: &Node, figures: &Figures, shared: bool) {
    let mine = figures.medians();
    let root = world.process_at_rank(0);
    if world.rank() != 0 {
        root.gather_into(&mine[..]);
        root.gather_into(&figures.arrivals[..]);
        return;
    }
    let ranks = world.size() as usize;
    let mut all = vec![[0.0f64; 4]; ranks];
    let flat: &mut [f64] = bytemuck::cast_slice_mut(&mut all[..]);
    root.gather_into_root(&mine[..], flat);
    let frames = figures.arrivals.len();
    let mut arrivals = vec![0.0f64; frames * ranks];
    root.gather_into_root(&figures.arrivals[..], &mut arrivals[..]);
    // Per frame, from the first rank's arrival to the last's.
    let skew: Vec<f64> = (0..frames)
        .map(|f| {
            let at = (0..ranks).map(|r| arrivals[r * frames + f]);
            let (low, high) = at.fold((f64::MAX, f64::MIN), |(l, h), t| (l.min(t), h.max(t)));
            (high - low) / 1e3
        })
        .collect();
    let [median, p95] = median_p95(&skew);
    let why = match shared {
        true => " (ranks share cores: the sharing's skew)",
        false => "",
    };
    println!("swap-lock arrival skew: median {median:.3} ms, p95 {p95:.3} ms{why}");
    for (r, [received, drawn, waited, bytes]) in all.iter().enumerate() {
        println!(
            "rank {r}: {} frames; medians: input {received:.3} ms ({bytes} bytes), draw {drawn:.2} ms, swap lock {waited:.3} ms",
            figures.bytes.len()
        );
    }
    println!("rank 0 draws {}", node.displays.join(", "));
}
